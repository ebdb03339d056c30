#!/usr/bin/env bash
# The flight's first 720 frames in its second world (synth:flight,frames=720,seed=2): corridor
# C1 at 2 m/s from frame 540, weakly textured walls and the hall's far wall beyond the depth
# range ahead. Without the motion prior the pose is lost at frames 704-708 (at 704 58
# points found do not fix it), 712-713, 715 and 717-718 (710 posed at 64 mm); with it (tracker.motion_prior,
# motion_prior.h) the flight keeps its pose: measured 2026-11-27 with the occlusion rule and
# the viewing bound on (session 27), 720 / 720 posed, ATE 5.5 mm. (World 8, this test's
# world before them, no longer needs the prior: 720 posed at 7.0 mm without it, nor do worlds
# 12 and 13 (world 10 since session 26); over worlds 1-20 without the prior worlds 2 and 11 lose frames (710
# and 719 posed), worlds 1, 6 and 7 end at 9-13 mm against 4.5-5.2 with it; docs/open_work.md, session 27.)
source "$(dirname "$0")/common.sh"
ATE_BOUND_M=0.010

SPEC=flight,frames=720,seed=2
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
