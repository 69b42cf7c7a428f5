#!/usr/bin/env bash
# make demo: the default synthetic scene with exact ground truth (seed 3: a tabletop of 12 objects,
# 90 frames on a 60° arc), validated, fused into an object map and evaluated against the true
# objects; then the scene's drifting SLAM estimate is fused with the object-constrained pose
# correction, and the trajectory error before and after is printed.
set -euo pipefail
objmap=${1:-build/bin/objmap}
out=${2:-out/demo}
# Each command below replaces its own folder under $out (an earlier output of its kind only, never
# anything else), so nothing here deletes a folder that DEMO names by mistake.
mkdir -p "$out"
scene="$out/scene"
run="$out/run"
corrected="$out/run_corrected"
echo "== objmap synth --out $scene --seed 3"
"$objmap" synth --out "$scene" --seed 3
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
echo "== objmap query --run $run \"cup on table\"  (the scene: up, surfaces, what stands on what)"
"$objmap" query --run "$run" "cup on table"
echo
echo "== objmap fuse --trajectory $scene/estimated.txt --correct-poses --out $corrected  (the drifting estimate)"
"$objmap" fuse --dataset "$scene" --trajectory "$scene/estimated.txt" \
  --segmentation "$scene/segmentation" --out "$corrected" --correct-poses 2>/dev/null |
  grep -E "^(objects|correction|written)"
echo
echo "== objmap eval ate: the estimate, then the corrected trajectory"
"$objmap" eval ate --gt "$scene/groundtruth.txt" --est "$scene/estimated.txt" | grep -E "^ATE|rmse"
"$objmap" eval ate --gt "$scene/groundtruth.txt" --est "$corrected/trajectory_corrected.txt" |
  grep -E "^ATE|rmse"
echo
echo "== objmap report --run $corrected --gt $scene/groundtruth.txt --corrected $corrected/trajectory_corrected.txt"
"$objmap" report --run "$corrected" --gt "$scene/groundtruth.txt" \
  --corrected "$corrected/trajectory_corrected.txt"
echo
echo "The object map is in $run (ground-truth poses) and $corrected (corrected poses): objects.json,"
echo "objects/*.ply, map_semantic.ply (open the PLY files in CloudCompare, MeshLab or Open3D)."
echo "The report (one self-contained page: top view, trajectory, ATE, thumbnails, tables):"
echo "  $corrected/report/report.html"
