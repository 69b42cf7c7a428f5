#!/usr/bin/env bash
# make demo: a synthetic scene with exact ground truth, validated, fused into an object map; prints
# the objects found and the trajectory error of the scene's drifting estimate.
set -euo pipefail
objmap=${1:-build/bin/objmap}
out=${2:-out/demo}
mkdir -p "$out"
scene="$out/scene"
run="$out/run"
echo "== objmap synth --out $scene"
"$objmap" synth --out "$scene"
echo
echo "== objmap validate --dataset $scene --trajectory $scene/groundtruth.txt --segmentation $scene/segmentation"
"$objmap" validate --dataset "$scene" --trajectory "$scene/groundtruth.txt" \
  --segmentation "$scene/segmentation" --quick
echo
echo "== objmap fuse --dataset $scene --trajectory $scene/groundtruth.txt --segmentation $scene/segmentation --out $run"
"$objmap" fuse --dataset "$scene" --trajectory "$scene/groundtruth.txt" \
  --segmentation "$scene/segmentation" --out "$run"
echo
echo "== objmap eval objects --map $run/objects.json --gt-objects $scene/objects_gt.json"
"$objmap" eval objects --map "$run/objects.json" --gt-objects "$scene/objects_gt.json"
echo
echo "== objmap report --run $run"
"$objmap" report --run "$run"
echo
echo "== objmap eval ate --gt $scene/groundtruth.txt --est $scene/estimated.txt"
"$objmap" eval ate --gt "$scene/groundtruth.txt" --est "$scene/estimated.txt"
echo
echo "The object map is in $run: objects.json, objects/*.ply, map_semantic.ply (open the PLY files"
echo "in CloudCompare, MeshLab or Open3D)."
echo "The report (one self-contained page: top view, trajectory, thumbnails, tables):"
echo "  $run/report/report.html"
