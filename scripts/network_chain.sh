#!/usr/bin/env bash
# The whole chain on real sequences with two front ends, side by side: the detector's boxes (fuse
# makes masks from boxes and depth) and YOLOv5n-seg's instance masks (ONNX, objmap detect), each
# detect -> track -> fuse with groundtruth.txt, then objmap eval masks (the share of each object's
# seen points inside its own masks). Prints one Markdown table (docs/benchmarks.md, "Real-data maps
# with network masks").
#   bash scripts/network_chain.sh [OBJMAP] [DATA] [OUT]
set -euo pipefail
objmap=${1:-build/bin/objmap}
data=${2:-../shared/data}
out=${3:-out/network_chain}
models=$data/../models
seg_model=$models/yolov5n-seg_coco/yolov5n-seg_480x640.onnx
box_model=$models/yolo-fastest-1.1_coco/yolo-fastest-1.1-xl.weights
mkdir -p "$out"
now() { date +%s.%N; }

# run <name> <dataset> <front end> <detector args...>: detect (unless the sequence's own
# segmentation is given as "given:<folder>"), track, fuse; the timings in <out>/<name>/times.
run() {
  local name=$1 dataset=$2 front=$3; shift 3
  local dir=$out/$name t0 t1 t2 t3
  mkdir -p "$dir"
  t0=$(now)
  if [[ $front == given:* ]]; then
    seg=$dataset/${front#given:}
  else
    "$objmap" detect --dataset "$dataset" --model "$front" "$@" --out "$dir/detect" \
      > "$dir/detect.log"
    seg=$dir/detect
  fi
  t1=$(now)
  "$objmap" track --dataset "$dataset" --segmentation "$seg" --out "$dir/track" > "$dir/track.log"
  t2=$(now)
  "$objmap" fuse --dataset "$dataset" --trajectory "$dataset/groundtruth.txt" \
    --segmentation "$dir/track" --out "$dir/run" > "$dir/fuse.log" 2> "$dir/fuse.err"
  t3=$(now)
  "$objmap" eval masks --run "$dir/run" --json "$dir/masks.json" > "$dir/masks.log"
  echo "$t0 $t1 $t2 $t3" > "$dir/times"
}

frames_of() { grep -vc '^#' "$1/rgb.txt"; }

echo "| sequence | front end | objects by class | suspected duplicates | points per object (median) | seen points inside their own masks | detect / track / fuse, ms per frame |"
echo "|---|---|---|---|---|---|---|"
for seq in tum/fr1_desk_9 tum/fr1_rpy_every4 tum/fr3_cabinet_58kf ycbv_0000_10f; do
  d=$data/$seq
  [ -d "$d" ] || continue
  name=$(basename "$seq")
  case $name in
    fr1_*) boxes="given:detections_yolofastest" ;;
    fr3_cabinet*) boxes="given:boxes_yolov2" ;;
    *) boxes="$box_model" ;;
  esac
  run "$name-boxes" "$d" "$boxes" --classes all
  run "$name-masks" "$d" "$seg_model" --classes all --threads 2
  for front in boxes masks; do
    python3 - "$out/$name-$front" "$name" "$front" "$(frames_of "$d")" <<'PY'
import json, sys, statistics
dir, name, front, frames = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
objs = json.load(open(dir + "/run/objects.json"))["objects"]
run = json.load(open(dir + "/run/run.json"))
classes = {}
for o in objs: classes[o["class"]] = classes.get(o["class"], 0) + 1
by_class = ", ".join(f"{c} {n}" for c, n in sorted(classes.items())) or "none"
points = statistics.median([o["points"]["outlier_filtered"] for o in objs]) if objs else 0
t0, t1, t2, t3 = map(float, open(dir + "/times").read().split())
ms = lambda a, b: 1000 * (b - a) / frames
det = "given" if t1 - t0 < 0.05 else f"{ms(t0, t1):.0f}"
label = "detector boxes" if front == "boxes" else "YOLOv5n-seg masks"
share = json.load(open(dir + "/masks.json"))["share"]
print(f"| {name} | {label} | {len(objs)}: {by_class} | {run['duplicates']['count']} | {points:.0f} | {100 * share:.1f}% | {det} / {ms(t1, t2):.0f} / {ms(t2, t3):.0f} |")
PY
  done
done
