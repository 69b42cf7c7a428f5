#!/usr/bin/env bash
# make demo: a synthetic scene, validated and run through the pipeline; prints the result.
set -euo pipefail
objmap=${1:-build/bin/objmap}
out=${2:-out/demo}
mkdir -p "$(dirname "$out")"
echo "== objmap synth --out $out/scene"
"$objmap" synth --out "$out/scene"
echo "== objmap validate"
"$objmap" validate --dataset "$out/scene" --trajectory "$out/scene/groundtruth.txt" \
  --segmentation "$out/scene/segmentation"
