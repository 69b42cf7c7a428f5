#!/usr/bin/env bash
# Memory of `objmap fuse` on long runs (docs/benchmarks.md, "Memory on long runs"): the synthetic
# table-top scene (`objmap synth`; its camera circles the same table at 20°/s, one turn in 540
# frames) at MEM_FRAMES frames (default 300 and 1200), each fused with its groundtruth.txt, with the
# default options, with the dense map's median pruning (--dense-prune-every 16) and with its peak
# rule, re-judged (--dense-prune-every 8 --dense-prune-peak 0.75 --dense-prune-rejudge 4). Prints
# per run the keyframes, the dense map's voxels, the voxels pruned, the peak resident memory of the
# process (/usr/bin/time -v) and the time per keyframe, then per variant the ratios of the last
# frame count to the first (the targets: voxels <= 1.3x, peak memory <= 1.5x).
# Then `objmap track` on the synthetic walk-through (`objmap synth --preset walkthrough --scale 0.5
# --seed 5`, 320x240 masks) at MEM_TRACK_FRAMES frames (default 300 and 954): its peak resident
# memory, flat in the number of frames since track streams them (at most n_init frames held).
#   bash scripts/bench_memory.sh [OBJMAP] [OUT]        (make bench-memory [BUILD=DIR])
# Environment: MEM_FRAMES ("300 1200"; "" skips fuse), MEM_SEED (1), MEM_THREADS (synth and fuse
# --threads, 2), MEM_VARIANTS (fuse options per variant, ';'-separated; default: the three above),
# MEM_TRACK_FRAMES ("300 954"; "" skips track).
# The scenes are kept in OUT/synth_s<seed>_f<frames>/ and OUT/walkthrough_s5_f<frames>/ and made
# only when missing (1200 frames: about 5 minutes on two cores, 0.9 GB; the 954-frame walk-through
# about 20 s).
set -euo pipefail
objmap=${1:-build/bin/objmap}
out=${2:-out/bench_memory}
frames=${MEM_FRAMES-300 1200}
track_frames=${MEM_TRACK_FRAMES-300 954}
seed=${MEM_SEED:-1}
threads=${MEM_THREADS:-2}
variants=${MEM_VARIANTS-";--dense-prune-every 16;--dense-prune-every 8 --dense-prune-peak 0.75 --dense-prune-rejudge 4"}

if [ ! -x "$objmap" ]; then
  echo "bench_memory: no objmap binary at $objmap (make build first)" >&2
  exit 2
fi
if [ ! -x /usr/bin/time ]; then
  echo "bench_memory: /usr/bin/time is missing (Debian: apt-get install time)" >&2
  exit 2
fi
mkdir -p "$out"

for n in $frames; do
  scene="$out/synth_s${seed}_f$n"
  if [ ! -f "$scene/synth.json" ] || ! grep -q "\"frames\": $n," "$scene/synth.json"; then
    echo "bench_memory: objmap synth --seed $seed --frames $n --out $scene" >&2
    "$objmap" synth --seed "$seed" --frames "$n" --threads "$threads" --out "$scene" \
      >"$out/synth_f$n.log" 2>&1
  fi
done

if [ -n "$frames" ]; then
  printf '%-62s %-7s %-9s %-12s %-13s %-13s %-11s\n' "fuse options" frames keyframes \
    "dense voxels" "voxels pruned" "peak RSS, MB" "ms/keyframe"
fi
IFS=';' read -r -a variant_list <<<"$variants"
[ -n "$frames" ] || variant_list=()
v=0
for args in "${variant_list[@]}"; do
  first_voxels="" first_rss="" first_n=""
  for n in $frames; do
    scene="$out/synth_s${seed}_f$n"
    run="$out/run_v${v}_f$n"
    # shellcheck disable=SC2086  # $args is a list of options
    /usr/bin/time -v "$objmap" fuse --dataset "$scene" --trajectory "$scene/groundtruth.txt" \
      --segmentation "$scene/segmentation" --threads "$threads" --out "$run" $args \
      >"$out/fuse_v${v}_f$n.log" 2>"$out/time_v${v}_f$n.txt"
    rss_kb=$(sed -n 's/^[[:space:]]*Maximum resident set size (kbytes): //p' \
      "$out/time_v${v}_f$n.txt")
    read -r keyframes voxels pruned ms < <(python3 - "$run/run.json" <<'EOF'
import json, sys
run = json.load(open(sys.argv[1]))
print(run["counts"]["keyframes"], run["points"]["dense_map"], run["points"].get("dense_pruned", 0),
      "%.1f" % run["performance"]["ms_per_keyframe"])
EOF
    )
    printf '%-62s %-7s %-9s %-12s %-13s %-13s %-11s\n' "${args:-(defaults)}" "$n" "$keyframes" \
      "$voxels" "$pruned" "$((rss_kb / 1024))" "$ms"
    if [ -z "$first_voxels" ]; then
      first_voxels=$voxels first_rss=$rss_kb first_n=$n
    else
      python3 -c "print('  %s vs %s frames: dense voxels %.2fx, peak RSS %.2fx' % \
        ('$n', '$first_n', $voxels / $first_voxels, $rss_kb / $first_rss))"
    fi
  done
  v=$((v + 1))
done

# objmap track: the walk-through's segmentation (full-image masks) tracked with appearance.
[ -n "$track_frames" ] || exit 0
printf '\n%-10s %-7s %-10s %-13s %-8s\n' "track" frames instances "peak RSS, MB" seconds
first_rss="" first_n=""
for n in $track_frames; do
  scene="$out/walkthrough_s5_f$n"
  if [ ! -f "$scene/synth.json" ] || ! grep -q "\"frames\": $n," "$scene/synth.json"; then
    echo "bench_memory: objmap synth --preset walkthrough --scale 0.5 --seed 5 --frames $n" >&2
    "$objmap" synth --preset walkthrough --scale 0.5 --seed 5 --frames "$n" --threads "$threads" \
      --out "$scene" >"$out/walkthrough_f$n.log" 2>&1
  fi
  /usr/bin/time -v "$objmap" track --dataset "$scene" --segmentation "$scene/segmentation" \
    --out "$out/track_f$n" >"$out/track_f$n.log" 2>"$out/time_track_f$n.txt"
  rss_kb=$(sed -n 's/^[[:space:]]*Maximum resident set size (kbytes): //p' \
    "$out/time_track_f$n.txt")
  seconds=$(sed -n 's/^[[:space:]]*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' \
    "$out/time_track_f$n.txt")
  instances=$(python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['instances'])" \
    "$out/track_f$n/tracks.json")
  printf '%-10s %-7s %-10s %-13s %-8s\n' "(defaults)" "$n" "$instances" "$((rss_kb / 1024))" \
    "$seconds"
  if [ -z "$first_rss" ]; then
    first_rss=$rss_kb first_n=$n
  else
    python3 -c "print('  %s vs %s frames: peak RSS %.2fx' % ('$n', '$first_n', $rss_kb / $first_rss))"
  fi
done
