#!/usr/bin/env bash
# Memory of `objmap fuse` on long runs (docs/benchmarks.md, "Memory on long runs"): the synthetic
# table-top scene (`objmap synth`; its camera circles the same table at 20°/s, one turn in 540
# frames) at MEM_FRAMES frames (default 300 and 1200), each fused with its groundtruth.txt, with the
# default options, with the dense map's median pruning (--dense-prune-every 16) and with its peak
# rule, re-judged (--dense-prune-every 8 --dense-prune-peak 0.75 --dense-prune-rejudge 4). Prints
# per run the keyframes, the dense map's voxels, the voxels pruned, the peak resident memory of the
# process (/usr/bin/time -v) and the time per keyframe, then per variant the ratios of the last
# frame count to the first (the targets: voxels <= 1.3x, peak memory <= 1.5x).
#   bash scripts/bench_memory.sh [OBJMAP] [OUT]        (make bench-memory [BUILD=DIR])
# Environment: MEM_FRAMES ("300 1200"), MEM_SEED (1), MEM_THREADS (synth and fuse --threads, 2),
# MEM_VARIANTS (fuse options per variant, ';'-separated; default: the three above).
# The scenes are kept in OUT/synth_s<seed>_f<frames>/ and made only when missing (1200 frames: about
# 5 minutes on two cores, 0.9 GB).
set -euo pipefail
objmap=${1:-build/bin/objmap}
out=${2:-out/bench_memory}
frames=${MEM_FRAMES:-300 1200}
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

printf '%-62s %-7s %-9s %-12s %-13s %-13s %-11s\n' "fuse options" frames keyframes \
  "dense voxels" "voxels pruned" "peak RSS, MB" "ms/keyframe"
IFS=';' read -r -a variant_list <<<"$variants"
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
