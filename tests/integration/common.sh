# Sourced by the integration tests. Sets paths to the built executables and offers helpers.
# Every test that sends LCM runs its body through scripts/netns-run (a private network
# namespace with only lo), so nothing reaches the host's interfaces.
set -euo pipefail
SRC=${RGBDSLAM_SOURCE_DIR:?set by ctest}
BUILD=${RGBDSLAM_BUILD_DIR:?set by ctest}
SHARED=${RGBDSLAM_SHARED_DIR:-$SRC/../shared}
PROCS=$BUILD/procs
TOOLS=$BUILD/tests/tools
NETNS_RUN=$SRC/scripts/netns-run
LCM_URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"  # only ever used inside a private namespace (scripts/netns-run)
WORK=$(mktemp -d "${TMPDIR:-/tmp}/rgbdslam-it-XXXXXX")
trap 'rm -rf "$WORK"' EXIT

fail() { echo "FAIL: $*" >&2; exit 1; }
skip() { echo "SKIP: $*" >&2; exit 77; }

# Path of ../shared/data/NAME; fails in CI (CI=true) when missing, skips elsewhere.
require_shared_data() {
  local path=$SHARED/data/$1
  if [ ! -e "$path" ]; then
    [ "${CI:-}" = "true" ] && fail "../shared/data/$1 is missing"
    skip "../shared/data/$1 is missing"
  fi
  echo "$path"
}

# Skips (or fails in CI) when private network namespaces are not available.
require_netns() {
  if ! unshare -n true 2>/dev/null; then
    [ "${CI:-}" = "true" ] && fail "cannot create a private network namespace"
    skip "cannot create a private network namespace (needs root)"
  fi
}

# wait_for_file FILE SECONDS: waits, bounded, until FILE exists.
wait_for_file() {
  local i
  for ((i = 0; i < $2 * 10; i++)); do
    [ -e "$1" ] && return 0
    sleep 0.1
  done
  fail "timed out after $2 s waiting for $1"
}

# run_rgbd_slam SPEC: rgbd-slam --deterministic on synth:SPEC, trajectory $WORK/t.txt,
# summary $WORK/out, log $WORK/err; shows the summary's main lines and the loss/recovery
# events. summary KEY prints one value of the summary.
run_rgbd_slam() {
  "$PROCS/rgbd-slam" --source "synth:$1" --output "$WORK/t.txt" --deterministic --quiet \
      > "$WORK/out" 2> "$WORK/err" || fail "rgbd-slam failed: $(tail -5 "$WORK/err")"
  grep -E "^(frames|poses|lost_frames|lost_episodes|relocalisations|ate_rmse_m) " "$WORK/out"
  grep -E "^rgbd-slam: frame" "$WORK/err" || true
}
summary() { awk -v k="$1" '$1 == k { print $2 }' "$WORK/out"; }
