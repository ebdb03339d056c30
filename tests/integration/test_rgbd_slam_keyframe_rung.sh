#!/usr/bin/env bash
# rgbd-slam --keyframe-rung N: every keyframe reaches the mapper as rgbd-mapper would decode
# it from rgbd-tracker's message at rung N of the link budget's encoding ladder. On the
# synthetic room (300 frames): the codec is applied (the trajectory differs from the run
# without it, and the coarsest rung sends fewer bytes per keyframe than the best), nothing
# fails to decode, every frame keeps its pose and the ATE stays within the room test's bound.
# Measured 2026-11-27: without the codec 1.49 mm; rung 0 (JPEG 75, depth at every 4th pixel)
# 1.63 mm, 67.8 kB a keyframe; rung 5 (JPEG 30, every 8th) 1.66 mm, 40.9 kB.
source "$(dirname "$0")/common.sh"
ATE_BOUND_M=0.005
for rung in -1 0 5; do
  "$PROCS/rgbd-slam" --source synth:room,frames=300 --output "$WORK/r$rung.txt" --deterministic --quiet \
      --keyframe-rung "$rung" > "$WORK/r$rung.out" 2> "$WORK/r$rung.err" \
    || fail "rgbd-slam --keyframe-rung $rung failed: $(tail -5 "$WORK/r$rung.err")"
  grep -E "^(poses|ate_rmse_m|keyframe_rung|keyframe_wire_kb_mean|keyframe_wire_errors) " "$WORK/r$rung.out"
  poses=$(awk '/^poses /{print $2}' "$WORK/r$rung.out")
  ate=$(awk '/^ate_rmse_m /{print $2}' "$WORK/r$rung.out")
  [ "$poses" -eq 300 ] || fail "rung $rung: only $poses of 300 frames got a pose"
  awk -v a="$ate" -v b="$ATE_BOUND_M" 'BEGIN { exit !(a <= b) }' || fail "rung $rung: ATE $ate m exceeds $ATE_BOUND_M m"
done
grep -q "^keyframe_rung" "$WORK/r-1.out" && fail "rung -1 (no codec) printed codec figures"
for rung in 0 5; do
  errors=$(awk '/^keyframe_wire_errors /{print $2}' "$WORK/r$rung.out")
  [ "$errors" = 0 ] || fail "rung $rung: $errors keyframes did not decode"
  cmp -s "$WORK/r-1.txt" "$WORK/r$rung.txt" && fail "rung $rung gave the trajectory of the run without the codec"
done
kb0=$(awk '/^keyframe_wire_kb_mean /{print $2}' "$WORK/r0.out")
kb5=$(awk '/^keyframe_wire_kb_mean /{print $2}' "$WORK/r5.out")
awk -v a="$kb5" -v b="$kb0" 'BEGIN { exit !(a > 0 && a < b) }' || fail "rung 5 sent $kb5 kB a keyframe, rung 0 $kb0 kB"
echo "PASS"
