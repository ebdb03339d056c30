#!/usr/bin/env bash
# rgbd-slam across a 1 s gap in the frames (issue 3): the synthetic room with frames
# 120-149 dropped (30 frames at 30 Hz; the others keep their timestamps). It must complete,
# give poses again after the gap, stay within the ATE bound, and say whether tracking was
# lost and how it recovered.
# Measured 2026-11-22: 270/270 frames got a pose, 150/150 after the gap (the first at frame
# 150), lost_frames 0, ATE 2.0 mm. Across the gap the camera moves 0.15 m and 17 deg; the
# tracker's rotation estimate from the small blurry image bridges that, so it is never lost
# and the relocaliser is not needed (test_rgbd_slam_covered.sh exercises it). (A 2 s gap is
# tested by test_rgbd_slam_relocalise_anywhere.sh.)
source "$(dirname "$0")/common.sh"
ATE_BOUND_M=0.005          # measured 2.0 mm; the room test's bound
MIN_POSES_AFTER_GAP=140    # of 150: room for a few frames of relocalisation elsewhere
GAP_END_S=1700000004.967   # frame 149 at 30 Hz (1700000000 s + 149/30 s)
GAP_START_S=1700000003.967 # frame 119

"$PROCS/rgbd-slam" --source synth:room,frames=300,drop=120-149 --output "$WORK/gap.txt" \
    --deterministic --quiet > "$WORK/gap.out" 2> "$WORK/gap.err" \
  || fail "rgbd-slam failed: $(tail -5 "$WORK/gap.err")"
grep -E "^(frames|poses|keyframes|lost_frames|ate_rmse_m|coverage) " "$WORK/gap.out"
value() { awk -v k="$1" '$1 == k { print $2 }' "$WORK/gap.out"; }
frames=$(value frames) poses=$(value poses) lost=$(value lost_frames) ate=$(value ate_rmse_m)
[ "$frames" -eq 270 ] || fail "rgbd-slam saw $frames frames, expected 270 (300 minus 30 dropped)"
inside=$(awk -v a="$GAP_START_S" -v b="$GAP_END_S" '!/^#/ && $1 > a + 0.01 && $1 < b + 0.01' "$WORK/gap.txt" | wc -l)
[ "$inside" -eq 0 ] || fail "$inside poses inside the gap: the frames were not dropped"
after=$(awk -v b="$GAP_END_S" '!/^#/ && $1 > b + 0.01' "$WORK/gap.txt" | wc -l)
first_after=$(awk -v b="$GAP_END_S" '!/^#/ && $1 > b + 0.01 { printf "%d", ($1 - 1700000000) * 30 + 0.5; exit }' "$WORK/gap.txt")
if [ "$lost" -eq 0 ]; then
  echo "gap: tracked through without being lost; $after/150 frames after the gap have a pose, the first at frame ${first_after:-none}"
else
  echo "gap: tracking lost for $lost frames, recovered (relocalised) at frame ${first_after:-never}; $after/150 frames after the gap have a pose"
fi
[ "$after" -ge "$MIN_POSES_AFTER_GAP" ] || fail "only $after of 150 frames after the gap got a pose (lost_frames $lost)"
# ATE by slam-eval against the scene's exact ground truth (all 300 frames; synth-write
# writes it with the images), which must agree with rgbd-slam's own figure.
"$PROCS/synth-write" room,frames=300 "$WORK/gt" > /dev/null 2> "$WORK/synth.err" \
  || fail "synth-write failed: $(cat "$WORK/synth.err")"
"$PROCS/slam-eval" "$WORK/gt/groundtruth.txt" "$WORK/gap.txt" --frames 270 > "$WORK/eval.out" \
  || fail "slam-eval failed"
eval_ate=$(awk '$1 == "ate_rmse_m" { print $2 }' "$WORK/eval.out")
echo "slam-eval: ate_rmse_m $eval_ate, $(grep -E '^coverage ' "$WORK/eval.out")"
awk -v a="$eval_ate" -v b="$ate" 'BEGIN { d = a - b; exit !(d < 1e-6 && d > -1e-6) }' \
  || fail "slam-eval ATE $eval_ate m differs from rgbd-slam's $ate m"
awk -v a="$eval_ate" -v b="$ATE_BOUND_M" 'BEGIN { exit !(a <= b) }' || fail "ATE $eval_ate m exceeds $ATE_BOUND_M m"
echo "PASS"
