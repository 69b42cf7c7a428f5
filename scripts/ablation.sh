#!/usr/bin/env bash
# make ablation (also the last part of make bench): objmap's changes to the paper, one at a time,
# and a sweep of the eq 22 weights.
#   bash scripts/ablation.sh [OBJMAP] [DATA]      (make ablation [DATA=DIR] [BUILD=DIR])
#
# 1. Ablation. Rows: synthetic scenes (`objmap synth --seed N` at the default orbit for N in
#    $ABLATION_SEEDS, default 1 2 3; seed 1 at --orbit-speed 60; seed 5 with --confusion-rate 0.2
#    --id-switch-rate 0.2) and every sequence under DATA that has a segmentation and a
#    groundtruth.txt (found as scripts/bench.sh finds them). Columns (COLUMNS below): `fuse
#    --method paper`, objmap's defaults, and the defaults with one of objmap's changes set back to
#    the paper's value (one column per option that --method paper sets:
#    pipeline::set_method_preset). Each cell is fused with groundtruth.txt (eval objects vs the true
#    objects; points kept from run.json) and with the sequence's estimate (eval objects vs the map
#    fused with groundtruth.txt over the same frames: Tables 4-5), as scripts/bench.sh does.
# 2. Sweep of eq 22 on synthetic seeds that no test uses ($SWEEP_SEEDS, default 11 12 13 14 15),
#    twice: on scenes made with $SWEEP_SYNTH (default --orbit-speed 60 --confusion-rate 0.2
#    --id-switch-rate 0.2, the hard set) and at the default orbit and rates (SWEEP_DEFAULT_ORBIT=0
#    leaves that one out): w_id x w_d x K ($SWEEP_WID, $SWEEP_WD, $SWEEP_K) at w_m = $SWEEP_WM
#    (P > K does not change when all weights and K are scaled together, so w_m is held), fused
#    with groundtruth.txt.
# 3. scripts/ablation_tables.py writes the ablation tables between <!-- ablation:begin --> and
#    <!-- ablation:end --> of docs/benchmarks.md, the sweep between <!-- sweep:begin --> and
#    <!-- sweep:end --> of docs/fusion.md (the rest untouched), and out/ablation/tables.md.
# Outputs: out/ablation/ (objects.json, run.json and every eval JSON; PLY files are deleted).
# Environment: ABLATION_OUT, ABLATION_SEEDS, ABLATION_PARTS ("ablation sweep"), ABLATION_EST=0
# (no estimate fuses: no Tables 4-5 figure), ABLATION_COLUMNS (names of COLUMNS to run, default
# all), SWEEP_SEEDS, SWEEP_SYNTH, SWEEP_DEFAULT_ORBIT, SWEEP_WID, SWEEP_WD, SWEEP_WM, SWEEP_K,
# BENCH_DOC, FUSION_DOC.
set -uo pipefail
objmap=${1:-build/bin/objmap}
data=${2:-../shared/data}
out=${ABLATION_OUT:-out/ablation}
seeds=${ABLATION_SEEDS-"1 2 3"}
parts=${ABLATION_PARTS:-"ablation sweep"}
with_est=${ABLATION_EST:-1}
sweep_seeds=${SWEEP_SEEDS-"11 12 13 14 15"}
sweep_wid=${SWEEP_WID:-"0.2 0.3 0.5"}
sweep_wd=${SWEEP_WD:-"0.1 0.2 0.4"}
sweep_wm=${SWEEP_WM:-0.5}
sweep_k=${SWEEP_K:-"0.3 0.4 0.5"}
# The sweep's scene sets, name|synth options: fast orbit, class confusions and id switches (the
# weights put to the test), and the default orbit and rates (where nearly every cell maps every
# object).
sweep_sets=("hard|${SWEEP_SYNTH-"--orbit-speed 60 --confusion-rate 0.2 --id-switch-rate 0.2"}")
[ "${SWEEP_DEFAULT_ORBIT:-1}" = 0 ] || sweep_sets+=("default|")
here=$(cd "$(dirname "$0")" && pwd)
py=python3
export step_tag=ablation
# shellcheck source=bench_common.sh
. "$here/bench_common.sh"

# name|label|fuse arguments. One column per option that `--method paper` sets
# (pipeline::set_method_preset, fusion::set_paper_rules); ablation_tables.py checks that the
# paper's run.json differs from objmap's in no other option.
COLUMNS=(
  "paper|paper (--method paper)|--method paper"
  "objmap|objmap (defaults)|"
  "iou|--overlap iou|--overlap iou"
  "tolerance|--overlap-tolerance 0|--overlap-tolerance 0"
  "gate_radius|--gate-radius-factor 0|--gate-radius-factor 0"
  "distance_gate|--distance-score gate|--distance-score gate"
  "weights|w_id = w_d = 0.5|--weight-id 0.5 --weight-distance 0.5"
  "one_per_frame|--one-per-frame false|--one-per-frame false"
  "best_first|--best-first false|--best-first false"
  "final_merge|--final-merge false|--final-merge false"
  "class_confusions|--merge-class-confusions false|--merge-class-confusions false"
  "confirmation|--confirmation id_keyframes|--confirmation id_keyframes"
  "voxel_support|--min-voxel-support 0|--min-voxel-support 0"
  "outlier_on_points|--outlier-on-points true|--outlier-on-points true"
  "nearest_centre|--voxel-nearest-centre true|--voxel-nearest-centre true"
  "position|--position-is-centroid true|--position-is-centroid true"
  "mask_refine|--mask-refine false|--mask-refine false"
  "depth_gate|--depth-gate false|--depth-gate false"
  "duplicate_rule|--duplicate-overlap 1|--duplicate-overlap 1"
  "min_depth|--min-depth 0.01|--min-depth 0.01"
)

use_objmap "$objmap" ablation
fresh_out "$out" ablation ABLATION_OUT
started=$(date -u +%s)
{
  echo "load_start=$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null)"
  echo "date=$(date -u '+%Y-%m-%d %H:%M UTC')"
  echo "sweep_wm=$sweep_wm"
  for set in "${sweep_sets[@]}"; do echo "sweep_set_${set%%|*}=${set#*|}"; done
} >"$out/features.txt"
printf '%s\n' "${COLUMNS[@]}" >"$out/columns.txt"

# Every fuse samples the dense map at every 4th pixel (--dense-stride 4): the dense map gives the
# up direction, hence the frame of each object's `position` (the centre of its percentile box, in
# the gravity frame) and so the position errors; without it the up is the cameras' prior, 22 deg
# off on synth seed 1, and positions move by up to 3 cm. With every 4th pixel the up stays within
# 0.2 deg and every position within 0.4 mm of the full run's (seed 1), at about 60 % of its time.
fuse() { "$objmap" fuse --dense-stride 4 "$@"; }

wanted() {  # wanted NAME: the column is in $ABLATION_COLUMNS (all when unset)
  [ -z "${ABLATION_COLUMNS:-}" ] && return 0
  [[ " $ABLATION_COLUMNS " == *" $1 "* ]]
}

slim() { find "$1" -name '*.ply' -delete 2>/dev/null; }  # keep the JSON, not the clouds

# ablation_row NAME DATASET SEGMENTATION ESTIMATE GT_OBJECTS [extra fuse args...]
ablation_row() {
  local name=$1 dataset=$2 seg=$3 est=$4 gtobj=$5
  shift 5
  local o="$out/ablation/$name" entry col est_map="" ref_traj=""
  local -a args
  mkdir -p "$o"
  {
    echo "name=$name"
    echo "dataset=$dataset"
    echo "segmentation=$seg"
    echo "estimate=$est"
    echo "gt_objects=$gtobj"
    echo "fuse_args=$*"
  } >"$o/meta.txt"
  if [ "$with_est" = 1 ] && [ -n "$est" ]; then
    $py "$here/bench_tables.py" prepare --dataset "$dataset" --gt "$dataset/groundtruth.txt" \
      --est "$est" --out-dir "$o" >"$o/prepare.txt" 2>&1
    est_map=$(sed -n 's/^estimate=//p' "$o/prepare.txt")
    ref_traj=$(sed -n 's/^reference=//p' "$o/prepare.txt")
    [ -n "$est_map" ] || est_map=$est
  fi
  for entry in "${COLUMNS[@]}"; do
    col=${entry%%|*}
    wanted "$col" || continue
    read -ra args <<<"${entry##*|}"
    local c="$o/$col"
    mkdir -p "$c"
    step "ablation $name: $col (groundtruth.txt)"
    if run "$c/fuse_gt.log" fuse --dataset "$dataset" --trajectory "$dataset/groundtruth.txt" \
      --segmentation "$seg" --out "$c/run_gt" "$@" "${args[@]}"; then
      slim "$c/run_gt"
      [ -n "$gtobj" ] && run "$c/eval_truth.log" "$objmap" eval objects \
        --map "$c/run_gt/objects.json" --gt-objects "$gtobj" --json "$c/vs_truth.json"
    fi
    [ -n "$est_map" ] || continue
    local ref_run="$c/run_gt"
    if [ -n "$ref_traj" ]; then
      ref_run="$c/run_gt_span"
      run "$c/fuse_gt_span.log" fuse --dataset "$dataset" --trajectory "$ref_traj" \
        --segmentation "$seg" --out "$ref_run" "$@" "${args[@]}" || continue
      slim "$ref_run"
    fi
    step "ablation $name: $col ($(basename "$est_map"))"
    if run "$c/fuse_est.log" fuse --dataset "$dataset" --trajectory "$est_map" \
      --segmentation "$seg" --out "$c/run_est" "$@" "${args[@]}"; then
      slim "$c/run_est"
      [ -f "$ref_run/objects.json" ] && run "$c/eval_est.log" "$objmap" eval objects \
        --map "$c/run_est/objects.json" --reference "$ref_run/objects.json" \
        --json "$c/est_vs_gtmap.json"
    fi
  done
}

# synth_scene DIR ARGS...: an `objmap synth` scene, made once.
synth_scene() {
  local dir=$1
  shift
  [ -f "$dir/objects_gt.json" ] && return 0
  mkdir -p "$(dirname "$dir")"
  step "objmap synth --out $dir $*"
  run "$dir.log" "$objmap" synth --out "$dir" "$@"
}

# 1. Ablation.
if [[ " $parts " == *" ablation "* ]]; then
  scenes="$out/scenes"
  rows=()
  for seed in $seeds; do rows+=("synth_seed$seed|--seed $seed"); done
  rows+=("synth_seed1_orbit60|--seed 1 --orbit-speed 60")
  rows+=("synth_seed5_confused|--seed 5 --confusion-rate 0.2 --id-switch-rate 0.2")
  for r in "${rows[@]}"; do
    name=${r%%|*}
    # shellcheck disable=SC2086
    synth_scene "$scenes/$name" ${r#*|} || continue
    s="$scenes/$name"
    ablation_row "$name" "$s" "$s/segmentation" "$s/estimated.txt" "$s/objects_gt.json"
  done
  if [ -d "$data" ]; then
    data=$(cd "$data" && pwd)
    while IFS= read -r rgbtxt; do
      dir=$(dirname "$rgbtxt")
      if [ ! -f "$dir/depth.txt" ] || [ ! -f "$dir/groundtruth.txt" ]; then continue; fi
      name=$(basename "$dir")
      sequence_inputs "$dir"  # sets seg, est, gtobj
      [ -n "$seg" ] || continue
      if [ -z "$est" ]; then  # as scripts/bench.sh: a seeded drifted copy of the ground truth
        mkdir -p "$out/ablation/$name"
        est="$out/ablation/$name/drifted_seed1.txt"
        $py "$here/drift_trajectory.py" "$dir/groundtruth.txt" "$est" --seed 1 \
          >"$out/ablation/$name/drift.log" 2>&1 || est=""
      fi
      extra=()
      [ "$(frames_of "$dir")" -le 30 ] && extra=(--keyframes all)
      ablation_row "$name" "$dir" "$seg" "$est" "$gtobj" "${extra[@]}"
    done < <(find -L "$data" -mindepth 1 -maxdepth 4 -name rgb.txt | sort)
  fi
fi

# 2. Sweep of eq 22, on each set of scenes.
if [[ " $parts " == *" sweep "* ]]; then
  for set in "${sweep_sets[@]}"; do
    set_name=${set%%|*}
    for seed in $sweep_seeds; do
      s="$out/scenes/sweep_${set_name}_seed$seed"
      # shellcheck disable=SC2086  # the options are words
      synth_scene "$s" --seed "$seed" ${set#*|} || continue
      for k in $sweep_k; do
        for wid in $sweep_wid; do
          for wd in $sweep_wd; do
            c="$out/sweep/$set_name/seed$seed/wid${wid}_wd${wd}_wm${sweep_wm}_k$k"
            mkdir -p "$c"
            step "sweep ($set_name) seed $seed: w_id $wid, w_d $wd, w_m $sweep_wm, K $k"
            if run "$c/fuse.log" fuse --dataset "$s" --trajectory "$s/groundtruth.txt" \
              --segmentation "$s/segmentation" --out "$c/run_gt" --weight-id "$wid" \
              --weight-distance "$wd" --weight-overlap "$sweep_wm" --match-threshold "$k"; then
              slim "$c/run_gt"
              run "$c/eval_truth.log" "$objmap" eval objects --map "$c/run_gt/objects.json" \
                --gt-objects "$s/objects_gt.json" --json "$c/vs_truth.json"
            fi
          done
        done
      done
    done
  done
fi

# 3. The tables.
step "writing the tables (${BENCH_DOC:-docs/benchmarks.md}, ${FUSION_DOC:-docs/fusion.md})"
$py "$here/ablation_tables.py" render --ablation "$out" --doc "${BENCH_DOC:-docs/benchmarks.md}" \
  --fusion-doc "${FUSION_DOC:-docs/fusion.md}" --objmap "$objmap" \
  --seconds $(($(date -u +%s) - started)) --command "${ABLATION_COMMAND:-make ablation}"
