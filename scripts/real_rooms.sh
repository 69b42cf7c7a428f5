#!/usr/bin/env bash
# The real sequences of DATA as a person would judge their maps (docs/fusion.md, "The extent of
# one instance", and docs/scene.md): each fused with its ground-truth poses and its own
# segmentation, then per sequence the objects, what stands "on nothing" per class, the suspected
# duplicates and the widest object of each class (scripts/real_rooms.py).
#   scripts/real_rooms.sh OBJMAP DATA OUT [extra fuse args...]
# 7-Scenes is detected first with the YOLOv8n-seg export of ../shared/models (every class; kept in
# OUT/7scenes_seg and reused). About 1 minute on 2 cores, 2 more the first time (detection).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
objmap=${1:?usage: real_rooms.sh OBJMAP DATA OUT [fuse args...]}
data=${2:?usage: real_rooms.sh OBJMAP DATA OUT [fuse args...]}
out=${3:?usage: real_rooms.sh OBJMAP DATA OUT [fuse args...]}
shift 3
models=${MODELS:-$(dirname "$data")/models}
mkdir -p "$out"
runs=()
fuse() {  # fuse NAME DATASET SEGMENTATION [args...]
  local name=$1 dataset=$2 seg=$3
  shift 3
  [ -d "$dataset" ] && [ -d "$seg" ] || { echo "real_rooms: $name: not in $data, skipped" >&2; return; }
  "$objmap" fuse --dataset "$dataset" --segmentation "$seg" --out "$out/$name" "$@" \
    >"$out/$name.log" 2>&1 || { echo "real_rooms: $name: fuse failed ($out/$name.log)" >&2; return; }
  runs+=("$name=$out/$name/objects.json")
}
tum=$data/tum
fuse fr1_rpy_every4 "$tum/fr1_rpy_every4" "$tum/fr1_rpy_every4/detections_yolofastest" \
  --trajectory "$tum/fr1_rpy_every4/groundtruth.txt" "$@"
fuse fr1_desk_9 "$tum/fr1_desk_9" "$tum/fr1_desk_9/detections_yolofastest" \
  --trajectory "$tum/fr1_desk_9/groundtruth.txt" --keyframes all "$@"
fuse fr3_cabinet_58kf "$tum/fr3_cabinet_58kf" "$tum/fr3_cabinet_58kf/boxes_yolov2" \
  --trajectory "$tum/fr3_cabinet_58kf/groundtruth.txt" "$@"
fuse ycbv_0000_10f "$data/ycbv_0000_10f" "$data/ycbv_0000_10f/masks" \
  --trajectory "$data/ycbv_0000_10f/groundtruth.txt" --keyframes all "$@"
scenes=$data/7scenes_redkitchen_3dmatch_50f
v8=$models/yolov8n-seg_coco/yolov8n-seg_640x640.onnx
if [ -d "$scenes" ] && [ -f "$v8" ]; then
  [ -d "$out/7scenes_seg" ] || "$objmap" detect --dataset "$scenes" --model "$v8" \
    --out "$out/7scenes_seg" >"$out/7scenes_detect.log" 2>&1
  fuse 7scenes_redkitchen_50f "$scenes" "$out/7scenes_seg" "$@"
  fuse 7scenes_redkitchen_50f_every_frame "$scenes" "$out/7scenes_seg" --keyframes all "$@"
fi
python3 "$here/real_rooms.py" "${runs[@]}"
