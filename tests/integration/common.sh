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

# localise_in_saved_map MIN_POSES ATE_BOUND_M ARGS...: rgbd-slam ARGS saves its map
# ($WORK/saved.map, summary $WORK/save.out), then runs again over the same frames with
# --load-map --localise-only ($WORK/localised.txt, summary $WORK/localise.out), which must
# pose at least MIN_POSES frames within ATE_BOUND_M and add no keyframe.
localise_in_saved_map() {
  local min_poses=$1 ate_bound=$2
  shift 2
  "$PROCS/rgbd-slam" "$@" --output "$WORK/saved.txt" --save-map "$WORK/saved.map" \
      > "$WORK/save.out" 2> "$WORK/save.err" || fail "saving run failed: $(tail -5 "$WORK/save.err")"
  grep -E "^(poses|keyframes|map_points|ate_rmse_m|map_saved_bytes|map_save_ms) " "$WORK/save.out"
  "$PROCS/rgbd-slam" "$@" --output "$WORK/localised.txt" --load-map "$WORK/saved.map" --localise-only \
      > "$WORK/localise.out" 2> "$WORK/localise.err" || fail "localise-only run failed: $(tail -5 "$WORK/localise.err")"
  grep -E "^(poses|keyframes|map_points|ate_rmse_m|map_load_ms|map_start_ms|first_pose_frame|first_pose_ms) " "$WORK/localise.out"
  local poses ate
  poses=$(awk '$1 == "poses" { print $2 }' "$WORK/localise.out")
  ate=$(awk '$1 == "ate_rmse_m" { print $2 }' "$WORK/localise.out")
  [ "$poses" -ge "$min_poses" ] || fail "localise-only: only $poses frames got a pose (expected >= $min_poses)"
  [ "$(awk '$1 == "keyframes" { print $2 }' "$WORK/localise.out")" -eq 0 ] || fail "localise-only added keyframes"
  awk -v a="$ate" -v b="$ate_bound" 'BEGIN { exit !(a <= b) }' || fail "localise-only ATE $ate m exceeds $ate_bound m"
}

# run_slam NAME SPEC KEYS [rgbd-slam options]: rgbd-slam --deterministic on synth:SPEC
# ($WORK/NAME.txt, summary $WORK/NAME.out); prints the summary lines whose key matches the
# extended regular expression KEYS, prefixed with NAME.
run_slam() {
  local name=$1 spec=$2 keys=$3
  shift 3
  "$PROCS/rgbd-slam" --source "synth:$spec" --output "$WORK/$name.txt" --deterministic --quiet "$@" \
      > "$WORK/$name.out" 2> "$WORK/$name.err" || fail "rgbd-slam $spec failed: $(tail -5 "$WORK/$name.err")"
  grep -E "^($keys) " "$WORK/$name.out" | sed "s/^/$name: /"
}
# summary_value NAME KEY: the value of KEY in run NAME's summary (empty if missing).
summary_value() { awk -v k="$2" '$1 == k { print $2 }' "$WORK/$1.out"; }
