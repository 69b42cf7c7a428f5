# shellcheck shell=bash disable=SC2034  # seg, est, gtobj are for the caller
# Shared by scripts/bench.sh and scripts/ablation.sh (sourced): logging, running a step, and where
# a sequence folder keeps its inputs.

step() { echo "${step_tag:-bench}: $*" >&2; }

# run LOG CMD...: runs CMD with its output in LOG; on failure says so (the caller goes on).
run() {
  local log=$1
  shift
  if "$@" >"$log" 2>&1; then return 0; fi
  echo "  failed ($(tail -n 1 "$log")): $*" >&2
  return 1
}

frames_of() { grep -vc '^\s*#' "$1/rgb.txt" 2>/dev/null || echo 0; }

first_match() {  # first existing path among the arguments (globs expanded by the caller)
  local p
  for p in "$@"; do
    if [ -e "$p" ]; then
      echo "$p"
      return
    fi
  done
}

# sequence_inputs DIR: sets seg (the first of segmentation/, detections*/, boxes*/, masks/), est
# (CameraTrajectory.txt, else KeyFrameTrajectory.txt, else *estimate*.txt / vo_*.txt) and gtobj
# (objects_gt.json, else objects_gt.txt); each empty when absent.
sequence_inputs() {
  local dir=$1
  seg=$(first_match "$dir/segmentation" "$dir"/detections* "$dir"/boxes* "$dir/masks")
  est=$(first_match "$dir/CameraTrajectory.txt" "$dir/KeyFrameTrajectory.txt" \
    "$dir"/*estimate*.txt "$dir"/vo_*.txt)
  gtobj=$(first_match "$dir/objects_gt.json" "$dir/objects_gt.txt")
}

# use_objmap BINARY TAG: objmap = BINARY's absolute path and bindir = its folder; exits 2 when it
# is not an executable (TAG names the script in the message).
use_objmap() {
  if [ ! -x "$1" ]; then
    echo "$2: no objmap binary at $1 (make build first)" >&2
    exit 2
  fi
  bindir=$(cd "$(dirname "$1")" && pwd)
  objmap="$bindir/$(basename "$1")"
}

# fresh_out DIR TAG VAR: empties DIR for a new run and sets out to its absolute path. Only an
# earlier run's folder (it has features.txt) or an empty one is deleted: never a folder that VAR
# (the environment variable naming it) names by mistake.
fresh_out() {
  case "$1" in
    "" | / | . | ..) echo "$2: refusing $3='$1'" >&2; exit 2 ;;
  esac
  if [ -d "$1" ] && [ -n "$(ls -A "$1")" ] && [ ! -f "$1/features.txt" ]; then
    echo "$2: $1: exists and is not an earlier $2 folder (no features.txt); expected a new" \
      "or empty folder ($3)" >&2
    exit 2
  fi
  rm -rf "$1"
  mkdir -p "$1"
  out=$(cd "$1" && pwd)
}
