#!/usr/bin/env bash
# make sanitize: the unit, CLI and integration tests (ctest) on a build with AddressSanitizer and
# UndefinedBehaviorSanitizer (g++, -O1, ccache) in build-asan/: the library, the objmap binary and
# the test programs, no benchmarks. Any sanitizer report fails the test that triggers it.
#   scripts/sanitize.sh [DATA]   env: JOBS (default 2), SANITIZE_TESTS (a ctest -R regex: only the
#   tests it matches), SANITIZE_TARGETS (build only these targets, e.g. "objmap_app test_live
#   test_io": the programs those tests run; default all)
# e.g. SANITIZE_TESTS="live/|TrajectoryTail" SANITIZE_TARGETS="objmap_app test_live test_io" make sanitize
set -euo pipefail
cd "$(dirname "$0")/.."
data=${1:-${OBJMAP_DATA:-$(cd .. && pwd)/shared/data}}
build=build-asan
# EIGEN_MALLOC_ALREADY_ALIGNED=1: under ASan Eigen stops trusting glibc's 16-byte aligned malloc and
# frees through its own offset scheme, while Debian's PCL (built without ASan) allocates point
# clouds with plain malloc; a pcl::PointCloud made in PCL and freed in objmap then reads 8 bytes
# before the block (a false heap-buffer-overflow in every run that finds planes). The define keeps
# the Release builds' allocator, which glibc's and ASan's 16-byte alignment make correct.
flags="-O1 -g1 -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
flags="$flags -DEIGEN_MALLOC_ALREADY_ALIGNED=1"
start=$(date +%s)
# Configured every time (cheap), so that a change of the flags above rebuilds what it must.
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=None "-DCMAKE_CXX_FLAGS=$flags" \
  -DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined -DOBJMAP_BUILD_TESTS=ON \
  -DOBJMAP_BUILD_BENCHMARKS=OFF >/dev/null
read -r -a targets <<<"${SANITIZE_TARGETS:-}"
[ ${#targets[@]} -eq 0 ] || targets=(--target "${targets[@]}")
if ! cmake --build "$build" -j"${JOBS:-2}" "${targets[@]}" >"$build/build.log" 2>&1; then
  tail -30 "$build/build.log" >&2
  exit 1
fi
built=$(date +%s)
echo "sanitize: built in $((built - start)) s"
# The install test builds a consumer of the installed (sanitized) library: same flags for it.
export CXXFLAGS="$flags" LDFLAGS="-fsanitize=address,undefined"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# Leaks inside third-party libraries (scripts/lsan.supp names each and why).
# print_suppressions=0: the suppressions' tally is not printed at exit, so that a test that counts
# the lines of a command's error output (one line for a bad input) sees the command's own.
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/scripts/lsan.supp:print_suppressions=0}
status=0
selection=()
[ -z "${SANITIZE_TESTS:-}" ] || selection=(-R "$SANITIZE_TESTS")
(cd "$build" && OBJMAP_DATA="$data" ctest --output-on-failure -j"${JOBS:-2}" "${selection[@]}") ||
  status=$?
echo "sanitize: tests in $(($(date +%s) - built)) s, $(($(date +%s) - start)) s in all"
exit $status
