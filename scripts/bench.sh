#!/usr/bin/env bash
# make bench: the measured tables of docs/benchmarks.md, reproduced on whatever data is given.
#   1. object maps on synthetic scenes (seeds 1 2 3 5 7): fuse with the ground-truth and with the
#      drifting estimated trajectory, eval objects against the true objects and (Tables 4-5) against
#      the ground-truth map, eval ate of the estimate;
#   2. fr3_cabinet_58kf (if in DATA): fuse, eval objects against the ground-truth cuboid;
#      fr1_rpy_every4: fuse and the report's top view of the semantic map;
#   3. the benchmark programs (bench_fuse: the whole fuse on fr1_rpy_every4 vs decoding its PNGs,
#      peak RSS, vs Open3D; bench_fusion: the stages).
# Outputs go to out/bench/ (JSON of every eval); the console shows the tables.
set -euo pipefail
objmap=${1:-build/bin/objmap}
data=${2:-../shared/data}
out=${BENCH_OUT:-out/bench}
seeds=${BENCH_SEEDS:-"1 2 3 5 7"}
bindir=$(dirname "$objmap")
mkdir -p "$out"

for seed in $seeds; do
  s="$out/synth_$seed"
  echo "== synthetic scene, seed $seed (objmap synth --seed $seed --orbit-speed 60)"
  "$objmap" synth --out "$s/scene" --seed "$seed" --orbit-speed 60 >/dev/null 2>&1
  for traj in groundtruth estimated; do
    "$objmap" fuse --dataset "$s/scene" --trajectory "$s/scene/$traj.txt" \
      --segmentation "$s/scene/segmentation" --out "$s/run_$traj" >/dev/null 2>&1
  done
  "$objmap" eval objects --map "$s/run_groundtruth/objects.json" \
    --gt-objects "$s/scene/objects_gt.json" --json "$s/objects_vs_truth.json" | sed -n '/Table 3/,/^$/p'
  "$objmap" eval ate --gt "$s/scene/groundtruth.txt" --est "$s/scene/estimated.txt" \
    --json "$s/ate.json" | grep -E "rmse|pairs"
  "$objmap" eval objects --map "$s/run_estimated/objects.json" \
    --reference "$s/run_groundtruth/objects.json" --json "$s/objects_est_vs_gt_map.json" |
    sed -n '/Tables 4-5/,/^$/p'
done

cab="$data/tum/fr3_cabinet_58kf"
if [ -d "$cab" ]; then
  echo "== fr3_cabinet_58kf (boxes_yolov2, groundtruth.txt)"
  "$objmap" fuse --dataset "$cab" --trajectory "$cab/groundtruth.txt" \
    --segmentation "$cab/boxes_yolov2" --out "$out/fr3_cabinet" 2>/dev/null | sed -n '1,8p'
  "$objmap" eval objects --map "$out/fr3_cabinet/objects.json" --gt-objects "$cab/objects_gt.txt" \
    --json "$out/fr3_cabinet_objects.json" | sed -n '/Tables 4-5/,$p'
fi

rpy="$data/tum/fr1_rpy_every4"
if [ -d "$rpy" ]; then
  echo "== fr1_rpy_every4 (detections_yolofastest, groundtruth.txt): objects and the top view"
  "$objmap" fuse --dataset "$rpy" --trajectory "$rpy/groundtruth.txt" \
    --segmentation "$rpy/detections_yolofastest" --out "$out/fr1_rpy_every4" 2>/dev/null
  "$objmap" report --run "$out/fr1_rpy_every4" --pixel 0.008
fi

found=0
for b in "$bindir"/bench_*; do
  [ -x "$b" ] || continue
  found=1
  echo "== $b"
  OBJMAP_DATA="$data" "$b"
done
[ $found -eq 1 ] || echo "no benchmark programs built (configure with -DOBJMAP_BUILD_BENCHMARKS=ON)"
