#!/usr/bin/env bash
# make sanitize: the unit, CLI and integration tests (ctest) on a build with AddressSanitizer and
# UndefinedBehaviorSanitizer (g++, -O1, ccache) in build-asan/: the library, the objmap binary and
# the test programs, no benchmarks. Any sanitizer report fails the test that triggers it.
#   scripts/sanitize.sh [DATA]   env: JOBS (default 2)
set -euo pipefail
cd "$(dirname "$0")/.."
data=${1:-${OBJMAP_DATA:-$(cd .. && pwd)/shared/data}}
build=build-asan
flags="-O1 -g1 -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
start=$(date +%s)
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=None "-DCMAKE_CXX_FLAGS=$flags" \
    -DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined -DOBJMAP_BUILD_TESTS=ON \
    -DOBJMAP_BUILD_BENCHMARKS=OFF >/dev/null
fi
if ! cmake --build "$build" -j"${JOBS:-2}" >"$build/build.log" 2>&1; then
  tail -30 "$build/build.log" >&2
  exit 1
fi
built=$(date +%s)
echo "sanitize: built in $((built - start)) s"
# The install test builds a consumer of the installed (sanitized) library: same flags for it.
export CXXFLAGS="$flags" LDFLAGS="-fsanitize=address,undefined"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
status=0
(cd "$build" && OBJMAP_DATA="$data" ctest --output-on-failure -j"${JOBS:-2}") || status=$?
echo "sanitize: tests in $(($(date +%s) - built)) s, $(($(date +%s) - start)) s in all"
exit $status
