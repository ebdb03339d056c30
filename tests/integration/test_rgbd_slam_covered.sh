#!/usr/bin/env bash
# rgbd-slam with the camera covered for a second (issue 3): the synthetic room, 300 frames,
# frames 120-149 delivered dark and without depth (synth key cover=). Tracking must be lost
# on the first covered frame, the loss and the recovery must be reported (one stderr line
# each, lost_episodes / relocalisations in the summary), and the relocaliser must bring it
# back soon after the hand is gone, with the trajectory still within the room test's bound.
# Measured 2026-11-22: lost at frame 120 (0 points found), relocalised at frame 150 (the
# first uncovered frame, 442 points found) after 30 lost frames; 270/300 posed, ATE 1.9 mm.
source "$(dirname "$0")/common.sh"
ATE_BOUND_M=0.005           # measured 1.9 mm; the room test's bound
MAX_FRAMES_TO_RELOCALISE=5  # after the last covered frame (measured: 0, the first one)

run_rgbd_slam room,frames=300,cover=120-149
[ "$(summary frames)" -eq 300 ] || fail "rgbd-slam saw $(summary frames) frames, expected 300"
[ "$(summary lost_episodes)" -ge 1 ] || fail "tracking was never lost with the camera covered"
[ "$(summary relocalisations)" -ge 1 ] || fail "tracking was lost and never relocalised"
lost_at=$(sed -n 's/^rgbd-slam: frame \([0-9]*\): tracking lost.*/\1/p' "$WORK/err" | head -1)
back_at=$(sed -n 's/^rgbd-slam: frame \([0-9]*\): relocalised.*/\1/p' "$WORK/err" | tail -1)
[ -n "$lost_at" ] || fail "no 'tracking lost' line on stderr"
[ -n "$back_at" ] || fail "no 'relocalised' line on stderr"
[ "$lost_at" -ge 120 ] && [ "$lost_at" -le 121 ] \
  || fail "tracking lost at frame $lost_at, expected on the first covered frame (120)"
[ "$back_at" -ge 150 ] && [ "$back_at" -le $((149 + MAX_FRAMES_TO_RELOCALISE)) ] \
  || fail "relocalised at frame $back_at, expected within $MAX_FRAMES_TO_RELOCALISE frames of 149"
# No pose for a covered frame (a pose there would be invented), one for every frame after.
frame_of() { awk '!/^#/ { printf "%d\n", ($1 - 1700000000) * 30 + 0.5 }' "$1"; }
covered=$(frame_of "$WORK/t.txt" | awk '$1 >= 120 && $1 <= 149' | wc -l)
after=$(frame_of "$WORK/t.txt" | awk '$1 >= 150' | wc -l)
[ "$covered" -eq 0 ] || fail "$covered covered frames got a pose"
[ "$after" -ge $((150 - MAX_FRAMES_TO_RELOCALISE)) ] || fail "only $after of 150 frames after the cover got a pose"
awk -v a="$(summary ate_rmse_m)" -v b="$ATE_BOUND_M" 'BEGIN { exit !(a <= b) }' \
  || fail "ATE $(summary ate_rmse_m) m exceeds $ATE_BOUND_M m"
echo "PASS: lost at frame $lost_at, relocalised at frame $back_at, $after/150 posed after the cover"
