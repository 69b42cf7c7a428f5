#!/usr/bin/env bash
# objmap follow on recordings written live (docs/benchmarks.md, "Following a recording"): for each
# recording, `objmap follow` is started on an empty folder, then `objmap replay --speed 1` writes
# the recording into it at its own frame rate (as tests/live/follow_test.cpp does); at the end the
# finished recording is mapped again by `objmap run` (real recordings: the same --model) or
# `objmap fuse` (the synthetic walk-through: its own segmentation/). Prints a Markdown row per
# recording: the recording's length, when follow ended (seconds after the replay started), its
# publishes, its lag (median and max over the keyframes, RUN/status.json; "—" where a build's
# status.json has no lag_median_s), the keyframes the detector did not reach, the objects of its
# last map against the reference's, and its peak resident memory beside that of the reference's fuse
# (its run.json); then the ratio of follow's peak memory on the longest synthetic walk-through to
# the shortest.
#   bash scripts/bench_follow.sh OBJMAP DATA [OUT]        (make bench-follow; end of make bench)
# Recordings:
#   fr1_rpy_every4  DATA/tum/fr1_rpy_every4, its groundtruth.txt as the trajectory the SLAM writes,
#                   --camera fr1; no segmentation: follow and run detect with --model
#                   (BENCH_FOLLOW_MODEL)
#   7scenes         DATA/7scenes_redkitchen_3dmatch_50f (its own per-frame poses), --model as above
#   walk<N>         `objmap synth --preset walkthrough --frames N --seed 5` (640x480, its noisy
#                   segmentation/ and drifting estimated.txt), N in BENCH_FOLLOW_FRAMES
#   walkhalf954     the same at 954 frames and half size (--scale 0.5, 320x240): the recording of
#                   the live issue's lag bar, its drifting estimated.txt streamed
#   walkhalf954_gt  the same with its groundtruth.txt streamed (case walkhalfgt)
#   walk954_gt      the live issue's recording at the preset's own 640x480, its groundtruth.txt
#                   streamed (case walkgt)
#   circle<N>       `objmap synth --preset tabletop --orbit-speed 36 --frames N --seed 5`: one
#                   table circled, one turn in 300 frames, its groundtruth.txt streamed (case
#                   circle): the recording grows, the map nearly not; N in BENCH_FOLLOW_FRAMES
# Environment: BENCH_FOLLOW_CASES ("fr1_rpy_every4 7scenes walk walkhalf walkhalfgt walkgt circle"),
# BENCH_FOLLOW_FRAMES ("300 1200"),
# BENCH_FOLLOW_MODEL (DATA/../models/yolov5n-seg_coco/yolov5n-seg_480x640.onnx, as objmap run takes
# it), BENCH_FOLLOW_ARGS (more follow options, e.g. "--publish-every 1"). The synthetic scenes are
# kept in OUT/walkthrough_s5_f<N>/ and OUT/tabletop_s5_f<N>/ and made only when missing (1200
# frames: ~3 minutes, 1.2 GB).
set -euo pipefail
objmap=${1:?usage: bench_follow.sh OBJMAP DATA [OUT]}
data=${2:?usage: bench_follow.sh OBJMAP DATA [OUT]}
out=${3:-out/bench_follow}
cases=${BENCH_FOLLOW_CASES-fr1_rpy_every4 7scenes walk walkhalf walkhalfgt walkgt circle}
frames=${BENCH_FOLLOW_FRAMES-300 1200}
model=${BENCH_FOLLOW_MODEL:-$data/../models/yolov5n-seg_coco/yolov5n-seg_480x640.onnx}
read -r -a follow_args <<<"${BENCH_FOLLOW_ARGS:-}"
[ -x "$objmap" ] || { echo "bench_follow: no objmap binary at $objmap (make build first)" >&2; exit 2; }
objmap=$(realpath "$objmap")
mkdir -p "$out"

now() { date +%s.%N; }

# follow_one NAME SRC TRAJ MODEL [CAMERA]: follow on OUT/NAME/rec while replay writes SRC into it
# (TRAJ: the trajectory file name the replay streams, "" for the layout's own poses; MODEL: "" for
# the recording's segmentation/; CAMERA: --camera of follow and the reference, where the copy's
# folder name no longer tells it); then the reference map of the finished recording; one row.
follow_one() {
  local name=$1 src=$2 traj=$3 model=$4 camera=${5:-}
  local cam_args=()
  [ -z "$camera" ] || cam_args=(--camera "$camera")
  local dir=$out/$name
  rm -rf "$dir"
  mkdir -p "$dir/rec"
  local f_args=(--dataset "$dir/rec" --out "$dir/live" --idle-exit 60 "${cam_args[@]}"
    "${follow_args[@]}")
  local r_args=(--dataset "$src" --out "$dir/rec" --speed 1)
  if [ -n "$traj" ]; then
    f_args+=(--trajectory "$dir/rec/$traj")
    r_args+=(--trajectory "$src/$traj")
  fi
  [ -z "$model" ] || f_args+=(--model "$model")
  echo "bench_follow: $name: objmap follow ${f_args[*]} & objmap replay ${r_args[*]}" >&2
  "$objmap" follow "${f_args[@]}" >"$dir/follow.log" 2>&1 &
  local fpid=$! waited=0
  while [ ! -f "$dir/live/status.json" ] && [ $waited -lt 300 ]; do
    sleep 0.1
    waited=$((waited + 1))
  done
  local t0 t1 t2
  t0=$(now)
  "$objmap" replay "${r_args[@]}" >"$dir/replay.log" 2>&1 || {
    echo "bench_follow: $name: replay failed: $(tail -1 "$dir/replay.log")" >&2
    kill "$fpid" 2>/dev/null || true
    return 1
  }
  t1=$(now)
  local fstatus=0
  wait "$fpid" || fstatus=$?
  t2=$(now)
  if [ $fstatus -ne 0 ]; then
    echo "bench_follow: $name: follow exit $fstatus: $(tail -1 "$dir/follow.log")" >&2
    return 1
  fi
  # The reference: objmap run (with the model) or objmap fuse on the finished recording.
  local ref ref_name
  if [ -n "$model" ]; then
    local ref_args=(run --dataset "$dir/rec" --model "$model" --out "$dir/run" "${cam_args[@]}")
    [ -z "$traj" ] || ref_args+=(--trajectory "$dir/rec/$traj")
    "$objmap" "${ref_args[@]}" >"$dir/run.log" 2>&1 || {
      echo "bench_follow: $name: objmap run failed: $(tail -1 "$dir/run.log")" >&2
      return 1
    }
    ref=$dir/run/map ref_name=run
  else
    "$objmap" fuse --dataset "$dir/rec" --trajectory "$dir/rec/$traj" --segmentation \
      "$dir/rec/segmentation" --out "$dir/fuse" "${cam_args[@]}" >"$dir/fuse.log" 2>&1 || {
      echo "bench_follow: $name: objmap fuse failed: $(tail -1 "$dir/fuse.log")" >&2
      return 1
    }
    ref=$dir/fuse ref_name=fuse
  fi
  python3 - "$dir/live/status.json" "$ref" "$ref_name" "$name" "$t0" "$t1" "$t2" \
    "$(sed -n 's/^replayed *\([0-9]*\) frames.*/\1/p' "$dir/replay.log")" <<'EOF'
import json, sys
status = json.load(open(sys.argv[1]))
ref, ref_name, name, frames = sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[8]
t0, t1, t2 = (float(t) for t in sys.argv[5:8])
ref_objects = len(json.load(open(ref + "/objects.json"))["objects"])
ref_mb = json.load(open(ref + "/run.json"))["performance"]["peak_rss_mb"]
median = status.get("lag_median_s")
median = "—" if median is None else "%.2f" % median
print("| %s | %s | %.1f s | %.1f s | %d | %s / %.2f s | %d of %d | %d vs %d (%s) | %d MB (%d MB) |"
      % (name, frames, t1 - t0, t2 - t0, status["publishes"], median, status["lag_max_s"],
         status["frames_skipped_detect"], status["keyframes_mapped"], status["objects"],
         ref_objects, ref_name, status["peak_rss_kb"] // 1024, ref_mb))
EOF
}

echo "bench_follow: $(uptime)" >&2
echo "| recording | frames | recording | follow ends after | publishes | lag median / max | skipped by detect (of keyframes) | objects: follow vs reference | peak memory: follow (reference's fuse) |"
echo "|---|---|---|---|---|---|---|---|---|"
for c in $cases; do
  case $c in
    fr1_rpy_every4)
      follow_one fr1_rpy_every4 "$data/tum/fr1_rpy_every4" groundtruth.txt "$model" fr1 || true ;;
    7scenes)
      follow_one 7scenes "$data/7scenes_redkitchen_3dmatch_50f" "" "$model" || true ;;
    walk)
      for n in $frames; do
        scene=$out/walkthrough_s5_f$n
        if [ ! -f "$scene/synth.json" ] || ! grep -q "\"frames\": $n," "$scene/synth.json"; then
          echo "bench_follow: objmap synth --preset walkthrough --frames $n --seed 5 --out $scene" >&2
          "$objmap" synth --preset walkthrough --frames "$n" --seed 5 --threads 2 --out "$scene" \
            >"$out/synth_f$n.log" 2>&1
        fi
        follow_one "walk$n" "$scene" estimated.txt "" || true
      done ;;
    walkhalf | walkhalfgt)  # the live issue's recording: 954 frames at half size (320x240)
      scene=$out/walkthrough_s5_f954_half
      if [ ! -f "$scene/synth.json" ]; then
        echo "bench_follow: objmap synth --preset walkthrough --frames 954 --seed 5 --scale 0.5" >&2
        "$objmap" synth --preset walkthrough --frames 954 --seed 5 --scale 0.5 --threads 2 \
          --out "$scene" >"$out/synth_f954_half.log" 2>&1
      fi
      if [ "$c" = walkhalf ]; then
        follow_one walkhalf954 "$scene" estimated.txt "" || true
      else
        follow_one walkhalf954_gt "$scene" groundtruth.txt "" || true
      fi ;;
    walkgt)  # the live issue's recording at 640x480, its true poses streamed
      scene=$out/walkthrough_s5_f954
      if [ ! -f "$scene/synth.json" ] || ! grep -q '"frames": 954,' "$scene/synth.json"; then
        echo "bench_follow: objmap synth --preset walkthrough --frames 954 --seed 5 --out $scene" >&2
        "$objmap" synth --preset walkthrough --frames 954 --seed 5 --threads 2 --out "$scene" \
          >"$out/synth_f954.log" 2>&1
      fi
      follow_one walk954_gt "$scene" groundtruth.txt "" || true ;;
    circle)  # one table circled: the recording grows, the map nearly not
      for n in $frames; do
        scene=$out/tabletop_s5_f$n
        if [ ! -f "$scene/synth.json" ] || ! grep -q "\"frames\": $n," "$scene/synth.json"; then
          echo "bench_follow: objmap synth --preset tabletop --orbit-speed 36 --frames $n --seed 5" >&2
          "$objmap" synth --preset tabletop --orbit-speed 36 --frames "$n" --seed 5 --threads 2 \
            --out "$scene" >"$out/synth_tabletop_f$n.log" 2>&1
        fi
        follow_one "circle$n" "$scene" groundtruth.txt "" || true
      done ;;
    *) echo "bench_follow: unknown recording $c" >&2; exit 2 ;;
  esac
done
# Peak memory against the recording's length: the longest walk-through's and circling's over the
# shortest's, follow's beside the reference fuse's, and what follow holds beyond that fuse.
read -r -a frame_list <<<"$frames"
if [ ${#frame_list[@]} -ge 2 ]; then
  short=${frame_list[0]} long=${frame_list[${#frame_list[@]} - 1]}
  for kind in walk circle; do
    a=$out/$kind$short b=$out/$kind$long
    [ -f "$a/live/status.json" ] && [ -f "$b/live/status.json" ] || continue
    python3 - "$a" "$b" "$short" "$long" "$kind" <<'EOF2'
import json, sys
a, b, short, long, kind = sys.argv[1:6]
fa, fb = (json.load(open(d + "/live/status.json"))["peak_rss_kb"] // 1024 for d in (a, b))
ra, rb = (json.load(open(d + "/fuse/run.json"))["performance"]["peak_rss_mb"] for d in (a, b))
what = "synthetic walk-through frames" if kind == "walk" else "frames circling one table"
print("\npeak memory, %s vs %s %s: follow %.2fx (%d vs %d MB), its fuse %.2fx (%d vs %d MB);"
      " follow beyond its fuse %+d MB at %s frames, %+d MB at %s"
      % (long, short, what, fb / fa, fb, fa, rb / ra, rb, ra, fa - ra, short, fb - rb, long))
EOF2
  done
fi
echo
uptime
