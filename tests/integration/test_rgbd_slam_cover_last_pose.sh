#!/usr/bin/env bash
# A wrong pose is worse than none: after the flight's camera is covered for 0.5 s at 2 m/s
# (synth:flight,frames=720,cover=640-654), tracking from the last pose, now 1 m behind the
# camera, finds a lookalike stretch of corridor C1 there (31 points, quality 0.21), and
# normal tracking's bar (dodgy is enough) would accept it and build the map on from it. A
# pose from the last pose must be good once the velocity at the loss has carried the
# camera beyond the fine stage's reach of it (tracker.relocalise_last_pose_reach_m, 0.3 m).
# The settings are test_rgbd_slam_flight.sh's, with occlusion and the viewing bound on:
# those are what lead the tracker to the lookalike (the recovery itself is open work).
# Measured 2026-11-27 (session 28): 640 posed (lost for good after the cover), no pose
# over 0.094 m off; the control, the bar as before (reach 1000 m): relocalised at the last
# pose, 704 posed, ATE 0.91 m, 4.45 m at worst.
source "$(dirname "$0")/common.sh"
MAX_ERROR_M=0.2

SPEC=flight,frames=720,cover=640-654
KEYS="poses|relocalisations|ate_rmse_m|ate_max_m"
# Without new parts of the map (tracker.new_part_after_failures): this test is about the
# relocaliser's bar, and a new part, started 60 failed attempts after the cover at the coasted
# pose, is a guess by design (2.67 m off here; test_suite_new_part.sh tests those).
PINNED=(--set tracker.motion_prior=false --set tracker.retry_with_coarse=false --set tracker.retry_without_sbi=false
        --set tracker.new_part_after_failures=0)
run_slam bar "$SPEC" "$KEYS" "${PINNED[@]}"
[ "$(summary_value bar poses)" -ge 630 ] || fail "only $(summary_value bar poses) frames posed, 640 before the cover"
awk -v a="$(summary_value bar ate_max_m)" -v b="$MAX_ERROR_M" 'BEGIN { exit !(a <= b) }' \
  || fail "a pose $(summary_value bar ate_max_m) m off (over $MAX_ERROR_M m): a wrong relocalisation was accepted"
# The control: with the old bar the lookalike must be taken, or the test tests nothing.
run_slam old_bar "$SPEC" "$KEYS" "${PINNED[@]}" --set tracker.relocalise_last_pose_reach_m=1000
awk -v a="$(summary_value old_bar ate_max_m)" 'BEGIN { exit !(a > 1.0) }' \
  || fail "with the old bar no pose is over 1 m off ($(summary_value old_bar ate_max_m) m): the cover no longer leads to the lookalike"
echo "PASS"
