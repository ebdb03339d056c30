#!/usr/bin/env bash
# The onboard/ground split in two namespaces joined by a veth pair (link.sh): a clean run,
# then the same with 10 % random loss each way and 50 ms delay each way. With the impaired
# link the tracker publishes a pose for at least 99 % of the frames, every keyframe is
# acknowledged by the end, and the ATE is within 2x of the clean run. The clean run's
# tracker writes --frame-log: a line per frame tracked, its keyframes and latencies. Why 2x: the lossy run's
# ATE depends on when the repaired map versions arrive; four runs of the same build (2026-11-25)
# gave clean 1.56-1.57 mm and lossy 1.50 / 1.72 / 2.09 / 2.40 (a CI rehearsal) mm, up to 1.53x,
# so a 1.5x bound failed one of the four without any fault. A map that stops arriving or keyframes
# left out give several times the clean ATE.
source "$(dirname "$0")/common.sh"
source "$(dirname "$0")/link.sh"
source "$(dirname "$0")/split.sh"
require_netns
link_up
seq=synth:room,frames=300

SPLIT_TRACKER_ARGS=(--frame-log "$WORK/clean/frames.csv")
split_start "$WORK/clean" 0
split_capture "$WORK/clean" "$seq"
split_finish "$WORK/clean"
split_report "$WORK/clean" clean
SPLIT_TRACKER_ARGS=()
# The frame log: a line per frame tracked, as many keyframes as the tracker made, and a
# latency for every frame, no smaller than the frame's own tracking time.
python3 - "$WORK/clean/frames.csv" "$(split_value frames "$WORK/clean/tracker.out")" \
    "$(split_value keyframes "$WORK/clean/tracker.out")" <<'PY' || fail "the tracker's frame log is wrong"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
frames, keyframes = int(sys.argv[2]), int(sys.argv[3])
assert len(rows) == frames, f"{len(rows)} lines for {frames} frames"
made = sum(int(r["keyframe"]) for r in rows)
assert made == keyframes, f"{made} keyframes in the log, {keyframes} made"
late = [r["seq"] for r in rows if not float(r["latency_ms"]) >= float(r["track_ms"]) or r["after_pose_ms"] == ""]
assert not late, f"frames with a latency below their tracking time or no after_pose_ms: {late[:5]}"
print(f"frame log: {len(rows)} frames, {made} keyframes")
PY

link_loss 10
split_start "$WORK/lossy" 50
split_capture "$WORK/lossy" "$seq"
split_finish "$WORK/lossy"
split_report "$WORK/lossy" "10 % loss + 50 ms each way"

clean_ate=$(split_value ate_rmse_m "$WORK/clean/eval.txt")
for run in clean lossy; do
  t=$WORK/$run/tracker.out
  poses=$(tail -n +2 "$WORK/$run/trajectory.csv" | wc -l)
  [ "$poses" -ge 297 ] || fail "$run: poses for $poses of 300 frames (< 99 %)"
  [ "$(split_value keyframes_unacked "$t")" = 0 ] || fail "$run: keyframes left unacknowledged: $(cat "$t")"
  [ "$(split_value keyframes "$t")" -gt 0 ] || fail "$run: no keyframes"
done
lossy_ate=$(split_value ate_rmse_m "$WORK/lossy/eval.txt")
awk -v a="$lossy_ate" -v b="$clean_ate" 'BEGIN { exit !(a <= 2.0 * b) }' \
  || fail "ATE with loss $lossy_ate m is above 2x the clean run's $clean_ate m"
echo "PASS"
