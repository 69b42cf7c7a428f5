#!/usr/bin/env bash
# The cost and accuracy of `objmap fuse --mesh` (docs/mesh.md): fuse with --mesh none|objects|all on
# fr1_rpy_every4 (Yolo-Fastest boxes) and ycbv_0000_10f (label masks), wall and CPU seconds and peak
# RSS of each (best of REPEAT runs, the machine may be shared); Open3D's ScalableTSDFVolume on the
# same runs (scripts/open3d_mesh_baseline.py: objects on ycbv, the scene on both); `objmap eval
# surface` of objmap's and Open3D's meshes on ycbv. Prints Markdown on stdout.
#   bash scripts/bench_mesh.sh OBJMAP DATA OUT
set -euo pipefail
objmap=$1
data=$2
out=$3
repeat=${REPEAT:-3}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out"
rpy=$data/tum/fr1_rpy_every4
ycb=$data/ycbv_0000_10f

# "wall cpu rss_mb" of the best (least CPU) of $repeat runs of: objmap fuse ... --out $out/$name.
measure() {
  local name=$1
  shift
  local best=""
  for _ in $(seq "$repeat"); do
    rm -rf "$out/$name"
    /usr/bin/time -f "%e %U %S %M" -o "$out/$name.time" "$objmap" fuse "$@" --out "$out/$name" \
      >"$out/$name.log" 2>&1
    local line
    line=$(awk '{printf "%.2f %.2f %.0f", $1, $2 + $3, $4 / 1024}' "$out/$name.time")
    if [ -z "$best" ] || awk -v a="$line" -v b="$best" 'BEGIN{split(a,x," ");split(b,y," ");exit !(x[2]<y[2])}'; then
      best=$line
    fi
  done
  echo "$best"
}

echo "| recording | --mesh | wall s | CPU s | CPU vs none | peak RSS MB | object meshes (triangles) | scene triangles |"
echo "|---|---|---|---|---|---|---|---|"
for rec in rpy ycb; do
  dir=${!rec}
  [ -d "$dir" ] || continue
  seg=$dir/detections_yolofastest
  [ "$rec" = ycb ] && seg=$dir/masks
  none_cpu=""
  for m in none objects all; do
    read -r wall cpu rss < <(measure "${rec}_$m" --dataset "$dir" --trajectory "$dir/groundtruth.txt" \
      --segmentation "$seg" --mesh "$m" --threads 2)
    [ "$m" = none ] && none_cpu=$cpu
    counts=$(python3 -c "import json;c=json.load(open('$out/${rec}_$m/run.json'))['counts'];print(c['object_meshes'],'(%d)'%c['object_mesh_triangles'],'|',c['scene_mesh_triangles'])")
    rel=$(awk -v a="$cpu" -v b="$none_cpu" 'BEGIN{printf "%+.0f%%", 100*(a/b-1)}')
    echo "| $(basename "$dir") | $m | $wall | $cpu | $rel | $rss | $counts |"
  done
done

o3d=/usr/bin/python3
if "$o3d" -c "import open3d" 2>/dev/null; then
  echo
  echo "| recording | Open3D ScalableTSDFVolume | wall s | CPU s | peak RSS MB | triangles |"
  echo "|---|---|---|---|---|---|"
  for job in "ycb objects" "ycb scene" "rpy scene"; do
    set -- $job
    [ -d "$out/${1}_all" ] || continue
    "$o3d" "$here/open3d_mesh_baseline.py" --run "$out/${1}_all" --out "$out/${1}_o3d_$2" "--$2" \
      >"$out/${1}_o3d_$2.json" 2>"$out/${1}_o3d_$2.log"
    python3 -c "import json;j=json.load(open('$out/${1}_o3d_$2.json'));print('| $1 | $2 | %.2f | %.2f | %.0f | %d |'%(j['seconds'],j['cpu_seconds'],j['peak_rss_mb'],j['triangles']))"
  done
fi

if [ -d "$ycb" ] && [ -d "$out/ycb_all" ]; then
  echo
  echo '```'
  echo "objmap eval surface --run ycb_all --models $ycb/models --poses $ycb/objects_pose.txt"
  "$objmap" eval surface --run "$out/ycb_all" --models "$ycb/models" --poses "$ycb/objects_pose.txt"
  if [ -d "$out/ycb_o3d_objects" ]; then
    echo "the same run with Open3D's meshes (scripts/open3d_mesh_baseline.py --objects):"
    "$objmap" eval surface --run "$out/ycb_o3d_objects" --models "$ycb/models" \
      --poses "$ycb/objects_pose.txt" | grep mesh
  fi
  echo '```'
fi
