#!/usr/bin/env bash
# Speed of `objmap detect` per backend and option, with the masks of each against the reference
# (OpenCV's dnn on the cores, the path before ONNX Runtime) on the same frames.
#   bash scripts/bench_detect.sh OBJMAP DATA [OUT]      (make bench-detect)
# The configurations run interleaved, round after round (A B C A B C ...), so that the load of
# the shared machine falls on all of them alike; the table gives the medians over the rounds:
# wall ms per frame (objmap's own "for the frames" time: loading the model left out), frames/s,
# CPU ms per frame (user + system of the whole process, model loading included, / frames), the
# speed-up of frames/s over the reference, and the masks against the reference's
# (detect_agreement: instances matched within a class by mask IoU).
# Knobs: BENCH_DETECT_SEQ (tum/fr1_rpy_every4 under DATA), BENCH_DETECT_FRAMES (40: its first
# frames; 0 all), BENCH_DETECT_ROUNDS (3), BENCH_DETECT_MODEL (YOLOv8n-seg 640 x 640 under
# DATA/../models), BENCH_DETECT_CONFIGS (names of the configurations below, default all),
# BENCH_DETECT_BASELINE (another objmap binary, e.g. one built from an earlier commit: run first as
# the configuration "before" with --threads 2, and then the reference of the table).
set -euo pipefail
objmap=${1:?usage: bench_detect.sh OBJMAP DATA [OUT]}
data=${2:?usage: bench_detect.sh OBJMAP DATA [OUT]}
out=${3:-out/bench_detect}
seq=$data/${BENCH_DETECT_SEQ:-tum/fr1_rpy_every4}
frames=${BENCH_DETECT_FRAMES:-40}
rounds=${BENCH_DETECT_ROUNDS:-3}
model=${BENCH_DETECT_MODEL:-$data/../models/yolov8n-seg_coco/yolov8n-seg_640x640.onnx}
agreement=$(dirname "$objmap")/detect_agreement
for f in "$objmap" "$agreement" "$model" "$seq/rgb.txt"; do
  [ -e "$f" ] || { echo "bench_detect: $f is missing" >&2; exit 2; }
done

# name|flags; the first is the reference.
all_configs=(
  "opencv-2|--backend opencv --threads 2"
  "opencv-1|--backend opencv --threads 1"
  "onnxruntime-2|--backend onnxruntime --threads 2"
  "onnxruntime-1|--backend onnxruntime --threads 1"
)
configs=()
[ -n "${BENCH_DETECT_BASELINE:-}" ] && configs+=("before|--threads 2")
for c in "${all_configs[@]}"; do
  name=${c%%|*}
  if [ -z "${BENCH_DETECT_CONFIGS:-}" ] || [[ " $BENCH_DETECT_CONFIGS " == *" $name "* ]]; then
    configs+=("$c")
  fi
done

# The clip: the sequence's first frames in a TUM folder of their own (rgb/ linked).
mkdir -p "$out"
clip=$out/clip
rm -rf "$clip"
mkdir -p "$clip"
ln -s "$(realpath "$seq/rgb")" "$clip/rgb"
awk -v n="$frames" '!/^#/ && (n == 0 || kept < n) {print; kept++}' "$seq/rgb.txt" >"$clip/rgb.txt"
n=$(wc -l <"$clip/rgb.txt")

echo "bench_detect: $n frames of $seq, $rounds rounds, model $(basename "$model"); $(uptime)" >&2
for round in $(seq 1 "$rounds"); do
  for c in "${configs[@]}"; do
    name=${c%%|*}
    flags=${c#*|}
    binary=$objmap
    [ "$name" = before ] && binary=$BENCH_DETECT_BASELINE
    # shellcheck disable=SC2086
    /usr/bin/time -f "%U %S" -o "$out/$name.time" "$binary" detect --dataset "$clip" \
      --model "$model" --classes all --out "$out/seg_$name" $flags >"$out/$name.log" 2>&1 || {
      echo "bench_detect: $name failed: $(tail -1 "$out/$name.log")" >&2
      continue
    }
    ms=$(sed -n 's/.*s for the frames (\([0-9.]*\) ms per frame).*/\1/p' "$out/$name.log")
    cpu=$(awk -v n="$n" '{printf "%.1f", 1000 * ($1 + $2) / n}' "$out/$name.time")
    echo "$round $name $ms $cpu" >>"$out/runs.txt.new"
    echo "  round $round $name: $ms ms/frame wall, $cpu ms/frame CPU" >&2
  done
done
mv "$out/runs.txt.new" "$out/runs.txt"

median() { sort -g | awk '{v[NR]=$1} END {print (NR%2 ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2)}'; }
reference=${configs[0]%%|*}
ref_ms=$(awk -v c="$reference" '$2==c {print $3}' "$out/runs.txt" | median)
printf '\n| configuration | flags | wall ms/frame | frames/s | CPU ms/frame | speed-up | masks vs %s |\n' \
  "$reference"
printf '|---|---|---|---|---|---|---|\n'
for c in "${configs[@]}"; do
  name=${c%%|*}
  flags=${c#*|}
  ms=$(awk -v c="$name" '$2==c {print $3}' "$out/runs.txt" | median)
  cpu=$(awk -v c="$name" '$2==c {print $4}' "$out/runs.txt" | median)
  masks=$("$agreement" "$out/seg_$reference" "$out/seg_$name" |
    awk '/^mask IoU/ {min=$7; sub(",", "", min); ok=$12" of "$14}
         /^unmatched/ {um=$3+0 + $5}
         END {printf "IoU min %s, >= 0.95: %s, unmatched %d", min, ok, um}')
  awk -v name="$name" -v flags="$flags" -v ms="$ms" -v cpu="$cpu" -v ref="$ref_ms" -v m="$masks" \
    'BEGIN {printf "| %s | `%s` | %.0f | %.2f | %.0f | %.2fx | %s |\n", name, flags, ms, 1000/ms, cpu, ref/ms, m}'
done
echo
echo "medians of $rounds rounds, $n frames; $(uptime)"
