#!/usr/bin/env bash
# Installs the Debian packages objmap needs, only those that are missing. Idempotent and quiet when
# everything is present. Run as root (or with sudo available).
#   scripts/install-deps.sh           build and test dependencies, and python3-open3d (optional:
#                                     the test that Open3D reads objmap's meshes and make bench's
#                                     Open3D baseline; when it cannot be installed the test skips and
#                                     the bench says n/a for it)
#   scripts/install-deps.sh --bench   also what `make bench` uses: python3 (the table script)
#   scripts/install-deps.sh --fuzz    also what `make fuzz` uses: clang with its libFuzzer and
#                                     sanitizer runtimes (Debian 12: libclang-rt-14-dev) and
#                                     llvm-symbolizer (llvm) for readable reports
#   scripts/install-deps.sh --slurm   also what `make test-slurm` uses: a single-node Slurm
#                                     (slurm-wlm: slurmctld + slurmd) and munge
# Every run also installs ONNX Runtime when it is missing (optional, like python3-open3d: when it
# cannot be installed objmap detect runs ONNX models in OpenCV's dnn, about 3x slower; docs/cli.md).
# Debian has no package: the x64 library of the npm package onnxruntime-node (pinned below, the
# release of the C API that lib/objmap/segmentation/ort_api.h declares) goes to
# /usr/local/lib/objmap/libonnxruntime.so.1, where objmap loads it at run time (dlopen; objmap
# builds and works without it).
#   scripts/install-deps.sh --no-onnxruntime   leaves ONNX Runtime out
set -euo pipefail
packages=(build-essential cmake pkg-config ccache
          libeigen3-dev libflann-dev liblz4-dev libpcl-dev libopencv-dev libceres-dev nlohmann-json3-dev libcli11-dev
          libgtest-dev libgmock-dev libbenchmark-dev zlib1g-dev libdeflate-dev
          libpng-dev libjpeg-dev libopenvdb-dev libtbb-dev
          librosbag-storage-dev libsensor-msgs-dev libtf2-msgs-dev
          chromium nodejs  # the report's 3D view test (headless Chromium over the DevTools protocol)
          snakemake time)  # the dataset workflow (scripts/workflow) and its test
bench_required=(python3)
bench_optional=(python3-open3d)
fuzz_required=(clang libclang-rt-14-dev llvm)
slurm_required=(slurm-wlm munge)
onnxruntime_npm=onnxruntime-node@1.29.0
onnxruntime_dir=/usr/local/lib/objmap
bench=0
onnxruntime=1
for arg in "$@"; do
  case "$arg" in
    --bench) bench=1 ;;
    --no-onnxruntime) onnxruntime=0 ;;
    --fuzz) packages+=("${fuzz_required[@]}") ;;
    --slurm) packages+=("${slurm_required[@]}") ;;
    *) echo "install-deps: unknown option $arg (expected --bench, --fuzz, --slurm or --no-onnxruntime)" >&2
       exit 2 ;;
  esac
done
[ $bench -eq 1 ] && packages+=("${bench_required[@]}")

is_installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
missing=()
for p in "${packages[@]}"; do
  is_installed "$p" || missing+=("$p")
done
optional=()
for p in "${bench_optional[@]}"; do
  is_installed "$p" || optional+=("$p")
done
sudo_cmd=()
[ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)

# ONNX Runtime's library from its npm package (pack, not install: no package scripts run).
install_onnxruntime() {
  [ -f "$onnxruntime_dir/libonnxruntime.so.1" ] && return 0
  echo "install-deps: installing ONNX Runtime ($onnxruntime_npm) into $onnxruntime_dir" >&2
  # npm: nodejs (above) brings it on most systems; Debian's own nodejs needs the npm package.
  command -v npm >/dev/null || "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends npm \
    >/dev/null || true
  local tmp
  tmp=$(mktemp -d)
  (cd "$tmp" && npm pack --silent "$onnxruntime_npm" >/dev/null &&
    tar xzf ./*.tgz package/bin/napi-v6/linux/x64/libonnxruntime.so.1) &&
    "${sudo_cmd[@]}" install -D -m 644 "$tmp/package/bin/napi-v6/linux/x64/libonnxruntime.so.1" \
      "$onnxruntime_dir/libonnxruntime.so.1" ||
    echo "install-deps: could not install ONNX Runtime; objmap detect uses OpenCV's dnn" >&2
  rm -rf "$tmp"
}

if [ ${#missing[@]} -eq 0 ] && [ ${#optional[@]} -eq 0 ]; then
  [ $onnxruntime -eq 1 ] && install_onnxruntime
  exit 0
fi
export DEBIAN_FRONTEND=noninteractive
updated=0
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}" >&2
  "${sudo_cmd[@]}" apt-get update -qq
  updated=1
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
if [ ${#optional[@]} -gt 0 ]; then
  echo "install-deps: installing ${optional[*]} (optional: the Open3D mesh test, make bench)" >&2
  { [ $updated -eq 1 ] || "${sudo_cmd[@]}" apt-get update -qq; } &&
    "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${optional[@]}" >/dev/null ||
    echo "install-deps: could not install ${optional[*]}; the Open3D mesh test skips and make" \
      "bench says n/a for Open3D" >&2
fi
[ $onnxruntime -eq 1 ] && install_onnxruntime
exit 0
