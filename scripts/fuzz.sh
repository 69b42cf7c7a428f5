#!/usr/bin/env bash
# make fuzz: builds the fuzz targets of tests/fuzz/ with clang, libFuzzer, ASan and UBSan in build-fuzz/
# and runs each for FUZZ_SECONDS (default 60) seconds on a corpus seeded from the real data
# (tests/fuzz/seeds.txt), tests/fuzz/seeds/<target>/ and the images fuzz_make_seeds makes, where they exist. A finding (a crash, a sanitizer report, an exception other than
# InputError, an InputError of several lines, an input taking > 10 s or > 2 GB) stops that target:
# the input is saved in build-fuzz/findings/<target>/, and the script exits 1 after the others.
#   scripts/fuzz.sh [DATA]   env: FUZZ_SECONDS, FUZZ_TARGETS="png ply" (default: all), JOBS
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${FUZZ_SECONDS:-60}
data=${1:-${OBJMAP_DATA:-../shared/data}}
build=build-fuzz
if ! command -v clang++ >/dev/null; then
  echo "fuzz: clang++ not found; expected clang and its fuzzer runtime (scripts/install-deps.sh --fuzz)" >&2
  exit 2
fi
read -r -a targets <<<"${FUZZ_TARGETS:-$(sed -n 's/^ *objmap_fuzz_target(\([a-z_]*\).*/\1/p' tests/fuzz/CMakeLists.txt | tr '\n' ' ')}"
if [ ! -f "$build/CMakeCache.txt" ]; then
  CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=None "-DCMAKE_CXX_FLAGS=-O1 -g" \
    -DOBJMAP_FUZZ=ON -DOBJMAP_BUILD_TESTS=OFF -DOBJMAP_BUILD_BENCHMARKS=OFF >/dev/null
fi
start=$(date +%s)
if ! cmake --build "$build" -j"${JOBS:-2}" --target "${targets[@]/#/fuzz_}" fuzz_make_seeds \
    $(grep -q '^OBJMAP_HAVE_ROSBAG:INTERNAL=1' "$build/CMakeCache.txt" && echo fuzz_make_bag_seeds) \
    >"$build/build.log" 2>&1; then
  tail -30 "$build/build.log" >&2
  exit 1
fi
# The image seeds made with objmap's PNG encoder and libjpeg (tests/fuzz/make_seeds.cpp): seeds of the
# image targets without the real data.
"$build/bin/fuzz_make_seeds" "$build/made_seeds" >/dev/null
# The rosbag target's seeds: tiny bags written with rosbag_storage (tests/fuzz/make_bag_seeds.cpp).
if [ -x "$build/bin/fuzz_make_bag_seeds" ]; then "$build/bin/fuzz_make_bag_seeds" "$build/made_seeds"; fi
echo "fuzz: built ${#targets[@]} targets in $(($(date +%s) - start)) s; ${seconds} s each"

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
failed=()
for t in "${targets[@]}"; do
  corpus=$build/corpus/$t findings=$build/findings/$t log=$build/logs/$t.log
  mkdir -p "$corpus" "$findings" "$(dirname "$log")"
  for f in $(awk -v t="$t" '$1 == t { for (i = 2; i <= NF; i++) print $i }' tests/fuzz/seeds.txt); do
    if [ -f "$data/$f" ]; then cp "$data/$f" "$corpus/data_$(echo "$f" | tr / _)"; else
      echo "fuzz: $t: seed $data/$f missing (set OBJMAP_DATA)" >&2
    fi
  done
  hand_made=()  # tiny text seeds of tests/fuzz/seeds/<target>/ and made images, when the target has some
  [ -d "tests/fuzz/seeds/$t" ] && hand_made+=("tests/fuzz/seeds/$t")
  [ -d "$build/made_seeds/$t" ] && hand_made+=("$build/made_seeds/$t")
  if "$build/bin/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="$findings/" "$corpus" "${hand_made[@]}" >"$log" 2>&1; then
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
    cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
    echo "fuzz: $t: $runs runs, coverage $cov, corpus $(ls "$corpus" | wc -l) inputs, no finding"
  else
    failed+=("$t")
    echo "fuzz: $t: FINDING, see $log; reproduce: $build/bin/fuzz_$t $(ls -t "$findings"/* 2>/dev/null | head -1)"
    grep -m3 -E 'ERROR|runtime error|FUZZ FINDING|terminate' "$log" | sed 's/^/  /' || true
  fi
done
echo "fuzz: ${#targets[@]} targets in $(($(date +%s) - start)) s; findings: ${failed[*]:-none}"
[ ${#failed[@]} -eq 0 ]
