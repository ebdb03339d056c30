#!/usr/bin/env bash
# The flight's first 720 frames in its eighth world (synth:flight,frames=720,seed=8): corridor
# C1 at 2 m/s from frame 540, weakly textured walls and the hall's far wall beyond the depth
# range ahead. Without the motion prior the pose is lost at frame 697 with 11 points found and
# again at 713-714 and 716-718 (714 posed at 58 mm); with it (tracker.motion_prior, motion_prior.h) the
# flight keeps its pose: measured 2026-11-27 with the epipolar cross-check on, 720 / 720
# posed, ATE 4.4 mm. (World 10, this test's world before the cross-check was on, no longer
# needs the prior: 720 posed at 5.5 mm without it; docs/open_work.md, session 26.)
source "$(dirname "$0")/common.sh"
ATE_BOUND_M=0.010

SPEC=flight,frames=720,seed=8
KEYS="frames|poses|frames_lost|ate_rmse_m|jumps_while_tracking"
run_slam prior "$SPEC" "$KEYS"
[ "$(summary_value prior frames)" -eq 720 ] || fail "rgbd-slam saw $(summary_value prior frames) frames, expected 720"
[ "$(summary_value prior poses)" -eq 720 ] || fail "only $(summary_value prior poses) of 720 frames posed"
awk -v a="$(summary_value prior ate_rmse_m)" -v b="$ATE_BOUND_M" 'BEGIN { exit !(a <= b) }' \
  || fail "ATE $(summary_value prior ate_rmse_m) m over $ATE_BOUND_M m"
[ "$(summary_value prior jumps_while_tracking)" -eq 0 ] || fail "$(summary_value prior jumps_while_tracking) jumps over 2 cm while reported tracking"
# The control: without the prior this world must go wrong in C1, or the test tests nothing.
run_slam no_prior "$SPEC" "$KEYS" --set tracker.motion_prior=false
awk -v p="$(summary_value no_prior poses)" -v a="$(summary_value no_prior ate_rmse_m)" -v b="$ATE_BOUND_M" \
  'BEGIN { exit !(p < 720 || a > 2 * b) }' \
  || fail "without the prior $(summary_value no_prior poses) posed at $(summary_value no_prior ate_rmse_m) m: the world no longer needs it"
echo "PASS"
