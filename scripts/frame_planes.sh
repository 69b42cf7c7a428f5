#!/usr/bin/env bash
# Does the depth agree with the trajectory's up? Each frame of a TUM-layout sequence fused on its
# own (objmap fuse of a one-frame copy of the sequence: the same images, camera and trajectory),
# and the planes the up direction found in that frame's map (run.json scene.up.planes) that lie
# within 20 deg of the world's +z: per plane its angle to +z, sample points, height and the x, y
# of its normal in the world (the direction it leans: constant over frames for a floor that is
# tilted in the trajectory's world, turning with the camera for a tilt in the camera). With a
# z-up ground truth the angles are how far the depth's planes lean from that truth; a floor or a
# table top leaning several degrees in every frame is a disagreement between depth and trajectory
# that no estimate from the depth can remove (docs/scene.md, "Figures").
#   bash scripts/frame_planes.sh SEQUENCE SEGMENTATION [STEP] [OBJMAP]
#   e.g. bash scripts/frame_planes.sh ../shared/data/tum/fr1_desk_9 detections_yolofastest
# STEP: every STEP-th frame (default 1). The trajectory is SEQUENCE/groundtruth.txt.
set -euo pipefail
seq=${1:?usage: frame_planes.sh SEQUENCE SEGMENTATION [STEP] [OBJMAP]}
seg=${2:?usage: frame_planes.sh SEQUENCE SEGMENTATION [STEP] [OBJMAP]}
step=${3:-1}
objmap=${4:-build/bin/objmap}
[ -d "$seq" ] || { echo "frame_planes.sh: $seq: no such folder; expected a TUM sequence" >&2; exit 2; }
seq=$(cd "$seq" && pwd)
for f in rgb.txt depth.txt groundtruth.txt; do
  [ -f "$seq/$f" ] || { echo "frame_planes.sh: $seq/$f: missing; expected a TUM sequence" >&2; exit 2; }
done
[ -e "$seq/$seg" ] || { echo "frame_planes.sh: $seq/$seg: missing segmentation" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mapfile -t rgb < <(grep -v '^#' "$seq/rgb.txt")
mapfile -t depth < <(grep -v '^#' "$seq/depth.txt")
echo "frame  planes within 20 deg of +z: angle to +z (deg) @ sample points (height along +z, m)" \
  "[normal x y]"
for i in "${!rgb[@]}"; do
  [ $((i % step)) = 0 ] && [ -n "${depth[$i]:-}" ] || continue
  one="$work/$(basename "$seq").frame$i"  # the sequence's name: fuse's camera preset from it
  mkdir -p "$one"
  [ -f "$seq/camera.json" ] && ln -s "$seq/camera.json" "$one/camera.json"
  ln -s "$seq/rgb" "$one/rgb"
  ln -s "$seq/depth" "$one/depth"
  (grep '^#' "$seq/rgb.txt" || true; echo "${rgb[$i]}") >"$one/rgb.txt"
  (grep '^#' "$seq/depth.txt" || true; echo "${depth[$i]}") >"$one/depth.txt"
  if ! "$objmap" fuse --dataset "$one" --trajectory "$seq/groundtruth.txt" \
    --segmentation "$seq/$seg" --keyframes all --dense-map true --out "$one.run" \
    >/dev/null 2>"$one.err"; then
    echo "$i  (fuse failed: $(tail -1 "$one.err"))"
    continue
  fi
  python3 - "$one.run/run.json" "$i" <<'EOF'
import json, math, sys
up = json.load(open(sys.argv[1]))["scene"]["up"]
out = []
for p in up["planes"]:
    n = p["normal"]
    angle = math.degrees(math.acos(min(1.0, abs(n[2]))))
    if angle < 20:
        s = 1 if n[2] > 0 else -1
        out.append("%.1f@%d (%.2f) [%+.3f %+.3f]" % (angle, p["inliers"], s * p["offset_m"],
                                                    s * n[0], s * n[1]))
print(sys.argv[2], " ".join(out))
EOF
  rm -rf "$one" "$one.run" "$one.err"
done
