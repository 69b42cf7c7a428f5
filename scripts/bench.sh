#!/usr/bin/env bash
# make bench: every table of docs/benchmarks.md, measured on whatever data is given.
#   bash scripts/bench.sh [OBJMAP] [DATA]      (make bench [DATA=DIR] [BUILD=DIR])
#
# 1. Sequences: every folder under DATA (depth <= 3) with rgb.txt and depth.txt. For each:
#      segmentation = the first of segmentation/, detections*/, boxes*/, masks/ (none: skipped);
#      estimate     = CameraTrajectory.txt, else KeyFrameTrajectory.txt, else *estimate*.txt / vo_*.txt,
#                     else a drifted copy of groundtruth.txt (scripts/drift_trajectory.py --seed 1);
#      ground truth = groundtruth.txt; ground-truth objects = objects_gt.json, else objects_gt.txt.
#    Plus the synthetic scenes `objmap synth --seed N --orbit-speed 60` (N in $BENCH_SEEDS, default
#    1 2 3): their estimated.txt drifts, objects_gt.json is exact.
#    Then: fuse with groundtruth.txt (and with the estimate), eval objects (map vs ground-truth objects:
#    Table 3, beside it the suspected duplicates of run.json; map of the estimate vs map of the
#    ground truth: Tables 4-5; Table 6 from run.json),
#    eval ate of the estimate and, when `objmap correct` exists, of its corrected trajectories
#    (--method paper and graph: Table 7) and of the map fused with the corrected poses.
#    An estimate in its own SLAM frame (first pose = identity) is first moved onto the ground truth's
#    pose at its first stamp; one that covers only part of the sequence is compared with a map fused
#    with groundtruth.txt over the same span (scripts/bench_tables.py prepare).
# 2. Performance on fr1_rpy_every4 (groundtruth.txt): objmap fuse (wall, CPU, peak RSS per keyframe),
#    the PNG-decode floor (bench_fuse), and the same dense-map job with Open3D
#    (scripts/open3d_baseline.py; n/a when python3-open3d is missing).
# 3. scripts/bench_tables.py writes the tables between <!-- bench:begin --> and <!-- bench:end -->
#    of docs/benchmarks.md (the rest of the file is untouched) and out/bench/tables.md.
# 4. scripts/ablation.sh: paper vs objmap vs objmap with each change reverted, and the eq 22 sweep
#    (out/bench/ablation/; its own markers in docs/benchmarks.md and docs/fusion.md).
# Outputs: out/bench/<sequence>/ (runs, every eval JSON, logs). Environment: BENCH_OUT, BENCH_SEEDS,
# BENCH_REPEAT (timing rounds, default 3), BENCH_PERF=0 (skip part 2), BENCH_NETWORK=0 (skip the
# network chain, scripts/network_chain.sh), BENCH_DOC (the Markdown file),
# BENCH_PROGRAMS=1 (also run every build/bin/bench_* program and print its output), BENCH_MEMORY=0
# (skip the memory runs, scripts/bench_memory.sh), BENCH_ABLATION=0 (skip part 4:
# scripts/ablation.sh, docs/benchmarks.md "How make bench works").
set -uo pipefail
objmap=${1:-build/bin/objmap}
data=${2:-../shared/data}
out=${BENCH_OUT:-out/bench}
seeds=${BENCH_SEEDS-"1 2 3"}
repeat=${BENCH_REPEAT:-3}
doc=${BENCH_DOC:-docs/benchmarks.md}
here=$(cd "$(dirname "$0")" && pwd)
tables="$here/bench_tables.py"
py=python3

# step, run, frames_of, first_match, sequence_inputs, use_objmap, fresh_out
# shellcheck source=bench_common.sh
. "$here/bench_common.sh"
use_objmap "$objmap" bench
fresh_out "$out" bench BENCH_OUT
started=$(date -u +%s)

has_correct=0
# An unknown subcommand makes CLI11 print the main help (exit 0), so look for the command's options.
# (The help is read whole first: `grep -q` on a pipe would cut it short, and with pipefail the
# SIGPIPE of the writer would count as "no correct".)
correct_help=$("$objmap" correct --help 2>/dev/null || true)
if grep -q -- "--method" <<<"$correct_help"; then has_correct=1; fi
{
  echo "has_correct=$has_correct"
  echo "load_start=$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null)"
  echo "date=$(date -u '+%Y-%m-%d %H:%M UTC')"
} >"$out/features.txt"

# bench_sequence NAME KIND DATASET SEGMENTATION ESTIMATE GT_OBJECTS [extra fuse args...]
bench_sequence() {
  local name=$1 kind=$2 dataset=$3 seg=$4 est=$5 gtobj=$6
  shift 6
  local o="$out/$name" m
  mkdir -p "$o"
  {
    echo "name=$name"
    echo "kind=$kind"
    echo "dataset=$dataset"
    echo "segmentation=$seg"
    echo "estimate=$est"
    echo "gt_objects=$gtobj"
    echo "frames=$(frames_of "$dataset")"
    echo "fuse_args=$*"
  } >"$o/meta.txt"
  step "$name: fuse with groundtruth.txt"
  run "$o/fuse_gt.log" "$objmap" fuse --dataset "$dataset" --trajectory "$dataset/groundtruth.txt" \
    --segmentation "$seg" --out "$o/run_gt" "$@" || return 0
  if [ -n "$gtobj" ]; then
    run "$o/eval_gt_vs_truth.log" "$objmap" eval objects --map "$o/run_gt/objects.json" \
      --gt-objects "$gtobj" --json "$o/objects_gt_vs_truth.json"
  fi
  [ -n "$est" ] || return 0
  run "$o/ate_est.log" "$objmap" eval ate --gt "$dataset/groundtruth.txt" --est "$est" \
    --json "$o/ate_est.json"
  # The estimate in the ground truth's frame (SLAM output starts at the identity) and, when it
  # covers only part of the sequence, the reference map over the same frames.
  $py "$tables" prepare --dataset "$dataset" --gt "$dataset/groundtruth.txt" --est "$est" \
    --out-dir "$o" >"$o/prepare.txt" 2>&1
  local est_map ref_traj ref_run="$o/run_gt"
  est_map=$(sed -n 's/^estimate=//p' "$o/prepare.txt")
  ref_traj=$(sed -n 's/^reference=//p' "$o/prepare.txt")
  [ -n "$est_map" ] || est_map=$est
  {
    echo "estimate_fused=$est_map"
    echo "aligned=$(sed -n 's/^aligned=//p' "$o/prepare.txt")"
    echo "reference_trajectory=$ref_traj"
  } >>"$o/meta.txt"
  if [ -n "$ref_traj" ]; then
    step "$name: fuse with groundtruth.txt over the estimate's time span"
    ref_run="$o/run_gt_span"
    run "$o/fuse_gt_span.log" "$objmap" fuse --dataset "$dataset" --trajectory "$ref_traj" \
      --segmentation "$seg" --out "$ref_run" "$@" || return 0
  fi
  step "$name: fuse with $(basename "$est_map")"
  if run "$o/fuse_est.log" "$objmap" fuse --dataset "$dataset" --trajectory "$est_map" \
    --segmentation "$seg" --out "$o/run_est" "$@"; then
    run "$o/eval_est_vs_gtmap.log" "$objmap" eval objects --map "$o/run_est/objects.json" \
      --reference "$ref_run/objects.json" --json "$o/objects_est_vs_gtmap.json"
    if [ -n "$gtobj" ]; then
      run "$o/eval_est_vs_truth.log" "$objmap" eval objects --map "$o/run_est/objects.json" \
        --gt-objects "$gtobj" --json "$o/objects_est_vs_truth.json"
    fi
  fi
  [ $has_correct -eq 1 ] && [ -d "$o/run_est" ] || return 0
  for m in paper graph; do
    step "$name: objmap correct --method $m"
    run "$o/correct_$m.log" "$objmap" correct --run "$o/run_est" --out "$o/correct_$m" \
      --method "$m" || continue
    local corrected="$o/correct_$m/trajectory_corrected.txt"
    [ -f "$corrected" ] || corrected=$(ls "$o/correct_$m/"*corrected*.txt 2>/dev/null | head -n 1)
    [ -n "$corrected" ] && [ -f "$corrected" ] || continue
    run "$o/ate_corrected_$m.log" "$objmap" eval ate --gt "$dataset/groundtruth.txt" \
      --est "$corrected" --json "$o/ate_corrected_$m.json"
    # correct writes a run folder (the re-fuse with the corrected poses); if not, fuse here.
    local corr_run="$o/correct_$m"
    if [ ! -f "$corr_run/objects.json" ]; then
      corr_run="$o/run_corrected_$m"
      run "$o/fuse_corrected_$m.log" "$objmap" fuse --dataset "$dataset" \
        --trajectory "$corrected" --segmentation "$seg" --out "$corr_run" "$@" || continue
    fi
    run "$o/eval_corrected_${m}_vs_gtmap.log" "$objmap" eval objects \
      --map "$corr_run/objects.json" --reference "$ref_run/objects.json" \
      --json "$o/objects_corrected_${m}_vs_gtmap.json"
  done
}

# 1a. Synthetic scenes.
for seed in $seeds; do
  s="$out/synth_seed$seed/scene"
  step "synth_seed$seed: objmap synth --seed $seed --orbit-speed 60"
  mkdir -p "$out/synth_seed$seed"
  run "$out/synth_seed$seed/synth.log" "$objmap" synth --out "$s" --seed "$seed" \
    --orbit-speed 60 || continue
  bench_sequence "synth_seed$seed" synthetic "$s" "$s/segmentation" "$s/estimated.txt" \
    "$s/objects_gt.json"
done

# 1b. Real sequences under DATA.
rpy=""
rpy_name=""
if [ -d "$data" ]; then
  data=$(cd "$data" && pwd)
  while IFS= read -r rgbtxt; do
    dir=$(dirname "$rgbtxt")
    [ -f "$dir/depth.txt" ] || continue
    name=$(basename "$dir")
    [ -e "$out/$name" ] && name=$(echo "${dir#"$data"/}" | tr '/' '_')
    sequence_inputs "$dir"  # sets seg, est, gtobj
    if [ -z "$est" ] && [ -n "$seg" ] && [ -f "$dir/groundtruth.txt" ]; then
      # No SLAM estimate: a seeded drifted copy of the ground truth (3% of the path, 2 deg/m yaw),
      # so that Table 7 has a row for the sequence.
      mkdir -p "$out/$name"
      est="$out/$name/drifted_seed1.txt"
      $py "$here/drift_trajectory.py" "$dir/groundtruth.txt" "$est" --seed 1 \
        >"$out/$name/drift.log" 2>&1 || est=""
    fi
    if [ -z "$seg" ] || [ ! -f "$dir/groundtruth.txt" ]; then
      mkdir -p "$out/$name"
      {
        echo "name=$name"
        echo "kind=real"
        echo "dataset=$dir"
        echo "frames=$(frames_of "$dir")"
        echo "skipped=$([ -z "$seg" ] && echo "no segmentation folder" || echo "no groundtruth.txt")"
      } >"$out/$name/meta.txt"
      step "$name: skipped ($(sed -n 's/^skipped=//p' "$out/$name/meta.txt"))"
      continue
    fi
    # Short clips (a camera that hardly moves) use every frame, not only the motion keyframes.
    extra=()
    [ "$(frames_of "$dir")" -le 30 ] && extra=(--keyframes all)
    bench_sequence "$name" real "$dir" "$seg" "$est" "$gtobj" "${extra[@]}"
    [ "$(basename "$dir")" = fr1_rpy_every4 ] && rpy=$dir && rpy_name=$name
  done < <(find -L "$data" -mindepth 1 -maxdepth 4 -name rgb.txt | sort)
else
  step "no data folder $data: synthetic scenes only"
fi

# 1c. Speed of objmap correct on a 200-keyframe run (the target: seconds, not minutes).
speed="$out/correct_speed"
if [ "${BENCH_PERF:-1}" != 0 ] && [ $has_correct -eq 1 ]; then
  mkdir -p "$speed"
  step "correct speed: synth --frames 200 --orbit-speed 60, fuse, correct (icp and visible)"
  if run "$speed/synth.log" "$objmap" synth --out "$speed/scene" --seed 1 --frames 200 \
    --orbit-speed 60 &&
    run "$speed/fuse.log" "$objmap" fuse --dataset "$speed/scene" --trajectory \
      "$speed/scene/estimated.txt" --segmentation "$speed/scene/segmentation" --out "$speed/run"; then
    for v in icp visible; do
      run "$speed/correct_$v.log" $py "$tables" measure --json "$speed/correct_$v.json" -- \
        "$objmap" correct --run "$speed/run" --out "$speed/correct_$v" --view-model "$v"
      [ -f "$speed/correct_$v/correction.json" ] &&
        cp "$speed/correct_$v/correction.json" "$speed/correction_$v.json"
      rm -rf "$speed/correct_$v"
    done
  fi
  rm -rf "$speed/scene" "$speed/run"
fi

# 2. Performance: objmap fuse vs the decode floor vs Open3D on fr1_rpy_every4 (ground truth).
perf="$out/perf"
mkdir -p "$perf"
if [ "${BENCH_PERF:-1}" != 0 ] && [ -n "$rpy" ]; then
  echo "dataset=$rpy" >"$perf/meta.txt"
  seg=$(sed -n 's/^segmentation=//p' "$out/$rpy_name/meta.txt")
  for r in $(seq 1 "$repeat"); do
    step "perf: objmap fuse, round $r of $repeat"
    run "$perf/objmap_$r.log" $py "$tables" measure --json "$perf/objmap_$r.json" -- \
      "$objmap" fuse --dataset "$rpy" --trajectory "$rpy/groundtruth.txt" --segmentation "$seg" \
      --out "$perf/run_$r"
    [ -f "$perf/run_$r/run.json" ] && cp "$perf/run_$r/run.json" "$perf/objmap_run_$r.json"
    rm -rf "$perf/run_$r"
  done
  if [ -x "$bindir/bench_fuse" ]; then
    step "perf: bench_fuse --repeat $repeat (fuse vs PNG decoding)"
    OBJMAP_DATA="$data" run "$perf/bench_fuse.log" "$bindir/bench_fuse" --repeat "$repeat" \
      --dataset "$rpy"
    cp "$perf/bench_fuse.log" "$perf/bench_fuse.txt"
  else
    echo "bench_fuse not built (configure with -DOBJMAP_BUILD_BENCHMARKS=ON)" >"$perf/bench_fuse.txt"
  fi
  o3d_py=""
  for cand in /usr/bin/python3 python3; do
    if command -v "$cand" >/dev/null && "$cand" -c "import open3d" >/dev/null 2>&1; then
      o3d_py=$cand
      break
    fi
  done
  if [ -n "$o3d_py" ]; then
    step "perf: Open3D baseline (scripts/open3d_baseline.py, 1-2 minutes, 2.7 GB)"
    if "$o3d_py" "$here/open3d_baseline.py" --dataset "$rpy" --trajectory "$rpy/groundtruth.txt" \
      >"$perf/open3d.json" 2>"$perf/open3d.log"; then
      cat "$perf/open3d.log" >&2
    else
      echo "  failed: $(tail -n 1 "$perf/open3d.log")" >&2
      rm -f "$perf/open3d.json"
    fi
  else
    echo "python3-open3d not installed (scripts/install-deps.sh --bench)" >"$perf/open3d.log"
    step "perf: Open3D n/a (python3-open3d not installed)"
  fi
fi

# 2b. The network chain (scripts/network_chain.sh): detect -> track -> fuse -> eval masks on the
#     real sequences with detector boxes and with YOLOv5n-seg masks (BENCH_NETWORK=0 skips it).
if [ "${BENCH_NETWORK:-1}" != 0 ] && [ -f "$data/../models/yolov5n-seg_coco/yolov5n-seg_480x640.onnx" ]; then
  step "network chain: detect (YOLOv5n-seg) -> track -> fuse -> eval masks, beside the boxes"
  bash "$(dirname "$0")/network_chain.sh" "$objmap" "$data" "$out/network_chain" \
    >"$out/network_chain.md" 2>"$out/network_chain.log" ||
    { tail -n 3 "$out/network_chain.log" >&2; rm -f "$out/network_chain.md"; }
fi

# 2c. Memory on long runs (scripts/bench_memory.sh): peak RSS and dense voxels of a synthetic scene
#     circled for 300 and 1200 frames; printed and kept in $out/memory.txt (docs/benchmarks.md,
#     "Memory on long runs", is written by hand from it). BENCH_MEMORY=0 skips it (~8 minutes).
if [ "${BENCH_MEMORY:-1}" != 0 ]; then
  step "memory: objmap fuse at 300 and 1200 frames of a synthetic orbit (scripts/bench_memory.sh)"
  bash "$(dirname "$0")/bench_memory.sh" "$objmap" "$out/memory" >"$out/memory.txt" \
    2>"$out/memory.log" && cat "$out/memory.txt" >&2 || tail -n 3 "$out/memory.log" >&2
fi

# 2d. Meshes (scripts/bench_mesh.sh): fuse --mesh none|objects|all on fr1_rpy_every4 and
#     ycbv_0000_10f, Open3D's ScalableTSDFVolume on the same runs, eval surface on ycbv; Markdown in
#     $out/mesh.md (docs/mesh.md, "Cost" and "Accuracy", is written by hand from it). BENCH_MESH=0
#     skips it (~2 minutes).
if [ "${BENCH_MESH:-1}" != 0 ] && [ -d "$data" ]; then
  step "meshes: objmap fuse --mesh and Open3D (scripts/bench_mesh.sh)"
  bash "$(dirname "$0")/bench_mesh.sh" "$objmap" "$data" "$out/mesh" >"$out/mesh.md" \
    2>"$out/mesh.log" && cat "$out/mesh.md" >&2 || tail -n 3 "$out/mesh.log" >&2
fi

if [ "${BENCH_PROGRAMS:-0}" = 1 ]; then
  for b in "$bindir"/bench_*; do
    [ -x "$b" ] || continue
    echo "== $b"
    OBJMAP_DATA="$data" "$b"
  done
fi

# 3. The tables.
step "writing the tables ($doc between <!-- bench:begin --> and <!-- bench:end -->)"
$py "$tables" render --bench "$out" --doc "$doc" --data "$data" --objmap "$objmap" \
  --seconds $(($(date -u +%s) - started)) --command "${BENCH_COMMAND:-make bench DATA=$data}"

# 4. The ablation (scripts/ablation.sh: its own tables in docs/benchmarks.md and docs/fusion.md).
if [ "${BENCH_ABLATION:-1}" != 0 ]; then
  step "ablation: scripts/ablation.sh (out in $out/ablation)"
  ABLATION_OUT="$out/ablation" BENCH_DOC="$doc" \
    ABLATION_COMMAND="${BENCH_COMMAND:-make bench DATA=$data} (scripts/ablation.sh)" \
    bash "$here/ablation.sh" "$objmap" "$data"
fi
