#!/usr/bin/env bash
# Map files with rgbd-slam on the synthetic room (docs/design.md, "Map files"): a first run
# saves its map; a second run over the same frames loads it with --localise-only and must
# pose (nearly) every frame in the first run's world, as accurately, adding no keyframe;
# a third extends it (--load-map alone). Bad uses end with a clear error and status 2.
# Measured: see the README's table of commands.
source "$(dirname "$0")/common.sh"
ATE_BOUND_M=0.003
MIN_POSES=295
slam() { "$PROCS/rgbd-slam" --source synth:room,frames=300 --deterministic --quiet "$@"; }
value() { awk -v k="$1" '$1 == k { print $2 }' "$2"; }

localise_in_saved_map "$MIN_POSES" "$ATE_BOUND_M" --source synth:room,frames=300 --deterministic --quiet
ls "$WORK" | grep -q 'saved.map.tmp' && fail "a temporary file was left behind"
[ "$(value map_points "$WORK/localise.out")" -eq "$(value map_points "$WORK/save.out")" ] || fail "localise-only changed the map"
# The first run's world frame: the first pose is near the first run's (not re-initialised at
# the identity somewhere else, which ATE's alignment would hide).
first_a=$(awk 'NR==1 {print $2, $3, $4}' "$WORK/saved.txt")
first_b=$(awk 'NR==1 {print $2, $3, $4}' "$WORK/localised.txt")
awk -v a="$first_a" -v b="$first_b" 'BEGIN { split(a, p); split(b, q);
  d = sqrt((p[1]-q[1])^2 + (p[2]-q[2])^2 + (p[3]-q[3])^2); exit !(d < 0.01) }' \
  || fail "first poses differ: $first_a vs $first_b"

# Extending: keyframe ids continue after the loaded ones; the map saved again loads.
slam --output "$WORK/c.txt" --load-map "$WORK/saved.map" --save-map "$WORK/room2.map" > "$WORK/c.out" 2> "$WORK/c.err" \
  || fail "extending run failed: $(tail -5 "$WORK/c.err")"
grep -E "^(poses|keyframes|map_points|ate_rmse_m) " "$WORK/c.out"
[ "$(value poses "$WORK/c.out")" -ge "$MIN_POSES" ] || fail "extending run posed too few frames"
slam --output "$WORK/d.txt" --load-map "$WORK/room2.map" --localise-only --max-frames 20 > "$WORK/d.out" 2> "$WORK/d.err" \
  || fail "the extended map does not load: $(tail -5 "$WORK/d.err")"

# Bad uses: clear errors, exit status 2, nothing overwritten.
expect_error() {  # expect_error TEXT ARGS...: rgbd-slam fails with status 2 and says TEXT
  local text=$1 status=0
  shift
  slam --output "$WORK/bad.txt" "$@" > /dev/null 2> "$WORK/bad.err" || status=$?
  [ "$status" -eq 2 ] || fail "expected status 2 for $*, got $status: $(cat "$WORK/bad.err")"
  grep -q "$text" "$WORK/bad.err" || fail "expected '$text' for $*: $(cat "$WORK/bad.err")"
  echo "refused as expected: $(head -1 "$WORK/bad.err")"
}
expect_error "needs --load-map" --localise-only
expect_error "cannot open map file" --load-map "$WORK/missing.map"
head -c 5000 "$WORK/saved.map" > "$WORK/cut.map"
expect_error "truncated at byte 5000" --load-map "$WORK/cut.map"
echo "not a map" > "$WORK/text.map"
expect_error "not a map file" --load-map "$WORK/text.map"
expect_error "folder of --save-map" --save-map "$WORK/no/such/dir/x.map"
expect_error "made in mode depth-ba" --load-map "$WORK/saved.map" --set slam.mode=depth-init
echo "PASS"
