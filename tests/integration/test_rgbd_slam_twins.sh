#!/usr/bin/env bash
# Perceptual aliasing (issue 11): synth:twins, two rooms alike texture for texture 14 m
# apart, flown through one after the other and back (scene.h). A lookalike place must neither
# close a loop nor take a lost tracker:
#  - the whole flight: the second room's keyframes are recognised as the first room's by
#    appearance and verified with depth, and refused as farther than the drift explains
#    (loops_beyond_drift); no loop is closed, and no loop edge in the map is wrong by the
#    truth (loops_accepted_wrong, eval/loop_audit.h);
#  - a 1 s cover in the second room, before it is mapped in the directions the camera turns
#    to: the first room's keyframes show the same views, but a vehicle cannot have flown
#    14 m in 1 s (tracker.relocalise_max_speed_m_s, 3 m/s): the tracker stays lost until it
#    sees what it mapped of the second room, and relocalises there.
# Without the bound (relocalise_max_speed_m_s=0) the cover relocalises into the first room,
# 14 m off: run as the control that the scene still provokes it.
# Measured 2026-11-26: flight 1503/1800 posed (lost facing west in the corridor, where the
# points found lie on far walls without depth), ATE 25.2 mm, 8 queries beyond the drift, 0
# loops closed; cover relocalised at frame 1073, ATE 11.2 mm, final error 0.025 m; control
# final error 14.0 m.
source "$(dirname "$0")/common.sh"

keys="poses|relocalisations|loops_[a-z_]+|ate_rmse_m|final_position_error_m"
run() { run_slam "$1" "$2" "$keys" "${@:3}"; }
value() { summary_value "$@"; }
at_most() { awk -v a="$(value "$1" "$2")" -v b="$3" 'BEGIN { exit !(a != "" && a <= b) }' || fail "$1: $2 $(value "$1" "$2") over $3"; }

run flight twins
[ "$(value flight poses)" -ge 1400 ] || fail "flight: only $(value flight poses) of 1800 frames posed"
[ "$(value flight loops_closed)" -eq 0 ] || fail "flight: $(value flight loops_closed) loops closed between lookalike rooms"
[ "$(value flight loops_accepted_wrong)" -eq 0 ] \
  || fail "flight: $(value flight loops_accepted_wrong) loop edges in the map are off the truth (eval/loop_audit.h)"
[ "$(value flight loops_beyond_drift)" -ge 1 ] \
  || fail "flight: no lookalike keyframe was recognised and refused: the test no longer tests it"
at_most flight ate_rmse_m 0.05
at_most flight final_position_error_m 0.05

run cover twins,frames=1200,cover=1040-1069
[ "$(value cover relocalisations)" -ge 1 ] || fail "cover: never relocalised"
at_most cover ate_rmse_m 0.03
at_most cover final_position_error_m 0.1

run control twins,frames=1200,cover=1040-1069 --set tracker.relocalise_max_speed_m_s=0
awk -v e="$(value control final_position_error_m)" 'BEGIN { exit !(e > 10) }' \
  || fail "control: without the bound the cover ended $(value control final_position_error_m) m off, not in the other room: the test no longer tests the bound"
echo "PASS"
