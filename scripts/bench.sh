#!/usr/bin/env bash
# make bench: runs the benchmark programs that exist so far and prints their figures (bench_fuse:
# the whole `objmap fuse` on fr1_rpy_every4 vs. decoding its PNGs, peak RSS, vs. Open3D).
set -euo pipefail
objmap=${1:-build/bin/objmap}
data=${2:-../shared/data}
bindir=$(dirname "$objmap")
found=0
for b in "$bindir"/bench_*; do
  [ -x "$b" ] || continue
  found=1
  echo "== $b"
  OBJMAP_DATA="$data" "$b"
done
[ $found -eq 1 ] || echo "no benchmark programs built (configure with -DOBJMAP_BUILD_BENCHMARKS=ON)"
