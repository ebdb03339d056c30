#!/usr/bin/env bash
# The flight's first 720 frames (synth:flight, 24 s: a room, then corridor C1 at up to 2 m/s).
# At 2 m/s a tracker that loses the camera for a few frames finds it 0.3 m on: relocalising
# from the last pose alone took a wrong pose there (ATE 0.63 m); trying the pose the velocity
# at the loss carried the camera to (tracker.relocalise_coast_frames) keeps the flight
# within centimetres. Measured 2026-11-25: 719 / 720 posed, 1 relocalisation, ATE 10.5 mm,
# no jump over 2 cm while reported tracking; with --set tracker.relocalise_coast_frames=0
# 717 / 720 posed, ATE 0.63 m.
source "$(dirname "$0")/common.sh"
ATE_BOUND_M=0.1

"$PROCS/rgbd-slam" --source synth:flight,frames=720 --output "$WORK/t.txt" --deterministic --quiet \
    > "$WORK/out" 2> "$WORK/err" || fail "rgbd-slam failed: $(tail -5 "$WORK/err")"
grep -E "^(frames|poses|relocalisations|ate_rmse_m|jumps_while_tracking) " "$WORK/out"
[ "$(summary frames)" -eq 720 ] || fail "rgbd-slam saw $(summary frames) frames, expected 720"
[ "$(summary poses)" -ge 700 ] || fail "only $(summary poses) of 720 frames posed"
[ "$(summary relocalisations)" -ge 1 ] || fail "never lost and relocalised: the test no longer tests the coasted pose"
awk -v a="$(summary ate_rmse_m)" -v b="$ATE_BOUND_M" 'BEGIN { exit !(a <= b) }' \
  || fail "ATE $(summary ate_rmse_m) m over $ATE_BOUND_M m"
[ "$(summary jumps_while_tracking)" -eq 0 ] || fail "$(summary jumps_while_tracking) jumps over 2 cm while reported tracking"
echo "PASS"
