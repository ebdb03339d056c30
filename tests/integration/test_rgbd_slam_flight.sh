#!/usr/bin/env bash
# The flight's first 720 frames (synth:flight, 24 s: a room, then corridor C1 at up to 2 m/s),
# the camera covered for 0.5 s at 2 m/s in C1 (frames 640-654), so the tracker finds it 1 m
# on. Relocalising from the last pose alone never finds it again there; trying the pose the
# velocity at the loss carried the camera to (tracker.relocalise_coast_frames) does.
# Measured 2026-11-26: 702 / 705 uncovered frames posed, ATE 5.9 mm, no jump over 2 cm
# while reported tracking; with --set tracker.relocalise_coast_frames=0 lost for good (640
# posed). The cover replaced the flight's own loss near frame 658, which the tracker no
# longer has since keyframes take weak corners down to the image noise (point_creation.h).
# This recovery is on a knife's edge (2026-11-27): at frame 655 the coasted pose finds 10
# of 31 points searched, the least a pose may rest on; with --set tracker.random_seed=2 or 3
# it is lost for good (642 and 640 posed), and with the motion prior (tracker.motion_prior,
# on by default since then) it finds 8 and is lost for good with each of the three seeds
# (with the cross-check too, 2026-11-27: 641, 640, 640 posed). So
# this test pins the settings under which it shows what coasting does: the prior off, as it
# was measured. A robust recovery after a cover at 2 m/s is open work (docs/open_work.md,
# session 25). With the epipolar cross-check on (mapper.epipolar_cross_check, 2026-11-27,
# session 26) these settings give 705 / 705 uncovered frames posed but ATE 61.9 mm: for ten
# frames after the recovery the pose rests on 6-26 points (quality 0.14-0.36) and the map
# is corrected by 12-24 cm after it; the bound below (0.1 m) still holds, and the control
# still fails to recover (under 690 posed).
# Occlusion and the viewing direction (tracker.occlusion_check, tracker.max_view_angle_deg,
# on since 2026-11-27, session 27) change the map before the cover; with them on and the
# settings above, the tracker relocalises at frame 655 at the last pose, 1 m back (31
# points found, quality 0.21), is lost at 656, relocalised at 657 and tracks on from there:
# 704 posed at ATE 0.91 m, 4.7 m off at the end (since 2026-11-27, session 28, that pose
# is refused: tracker.relocalise_last_pose_reach_m, test_rgbd_slam_cover_last_pose.sh; the
# tracker is then lost for good, 640 posed). So both
# are pinned off too, which gives the run measured above (705 / 705, 61.9 mm; the control
# 640 posed). With every default the cover is recovered at seed 1 (705 posed, 5.8 mm) and
# lost for good at seeds 2 and 3 (tracker.random_seed: 640 and 641 posed).
source "$(dirname "$0")/common.sh"
ATE_BOUND_M=0.1

SPEC=flight,frames=720,cover=640-654
KEYS="frames|poses|relocalisations|ate_rmse_m|jumps_while_tracking"
PINNED=(--set tracker.motion_prior=false --set tracker.retry_with_coarse=false --set tracker.retry_without_sbi=false
        --set tracker.occlusion_check=false --set tracker.max_view_angle_deg=0)
run_slam coasting "$SPEC" "$KEYS" "${PINNED[@]}"
[ "$(summary_value coasting frames)" -eq 720 ] || fail "rgbd-slam saw $(summary_value coasting frames) frames, expected 720"
[ "$(summary_value coasting poses)" -ge 690 ] || fail "only $(summary_value coasting poses) of 720 frames posed (705 uncovered)"
[ "$(summary_value coasting relocalisations)" -ge 1 ] || fail "never lost and relocalised: the test no longer tests the coasted pose"
awk -v a="$(summary_value coasting ate_rmse_m)" -v b="$ATE_BOUND_M" 'BEGIN { exit !(a <= b) }' \
  || fail "ATE $(summary_value coasting ate_rmse_m) m over $ATE_BOUND_M m"
[ "$(summary_value coasting jumps_while_tracking)" -eq 0 ] || fail "$(summary_value coasting jumps_while_tracking) jumps over 2 cm while reported tracking"
# The control: without coasting the cover must cost the flight's end, or the test tests nothing.
run_slam still "$SPEC" "$KEYS" "${PINNED[@]}" --set tracker.relocalise_coast_frames=0
[ "$(summary_value still poses)" -lt 690 ] || fail "without coasting $(summary_value still poses) frames posed: the cover no longer needs the coasted pose"
echo "PASS"
