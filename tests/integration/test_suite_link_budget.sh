#!/usr/bin/env bash
# rgbd-tracker --link-budget-kbps over the split suite (link.sh, split.sh): the room (300
# frames, 10 s) without a budget, then with 300 kbit/s, below what its keyframes need at full
# quality. With the budget the tracker sends keyframes coarser (fewer bytes per keyframe),
# loses none (all acknowledged, a pose for 99 % of the frames), and what it sent on the link
# (keyframes, receipts, status, measured in the link's log) stays within the budget over the
# log's duration plus the bucket's burst (2 s) plus, for each keyframe it had to send over
# budget (counted by the tracker), one keyframe of the unbudgeted run. The ATE stays within
# 2x of the unbudgeted run's (as test_suite_split bounds a lossy link). The budget is a target
# that the keyframes' quality follows, not a hard cap (common/link_budget.h): the bound checks
# the tracker's accounting and that it sends less, not that the room fits in 300 kbit/s.
source "$(dirname "$0")/common.sh"
source "$(dirname "$0")/link.sh"
source "$(dirname "$0")/split.sh"
require_netns
link_up
seq=synth:room,frames=300
budget_kbps=300

SPLIT_TRACKER_ARGS=(--link-budget-kbps 0)
split_start "$WORK/free" 0
split_capture "$WORK/free" "$seq"
split_finish "$WORK/free"
split_report "$WORK/free" "no budget"

SPLIT_TRACKER_ARGS=(--link-budget-kbps "$budget_kbps")
split_start "$WORK/budget" 0
split_capture "$WORK/budget" "$seq"
split_finish "$WORK/budget"
split_report "$WORK/budget" "budget $budget_kbps kbit/s"

free=$WORK/free/tracker.out t=$WORK/budget/tracker.out
for run in free budget; do
  poses=$(tail -n +2 "$WORK/$run/trajectory.csv" | wc -l)
  [ "$poses" -ge 297 ] || fail "$run: poses for $poses of 300 frames (< 99 %)"
  [ "$(split_value keyframes_unacked "$WORK/$run/tracker.out")" = 0 ] || fail "$run: keyframes left unacknowledged"
done
[ "$(split_value link_budget_kbps "$t")" = "$budget_kbps" ] || fail "the tracker did not take --link-budget-kbps: $(cat "$t")"
[ "$(split_value keyframes_coarser "$t")" -gt 0 ] || fail "no keyframe was sent coarser under $budget_kbps kbit/s"
per_kf() { awk -v b="$(split_value keyframe_bytes "$1")" -v n="$(split_value keyframe_sends "$1")" 'BEGIN { printf "%.0f", b / n }'; }
free_kf=$(per_kf "$free") budget_kf=$(per_kf "$t")
echo "bytes per keyframe sent: $free_kf without a budget, $budget_kf with $budget_kbps kbit/s"
[ "$budget_kf" -lt "$free_kf" ] || fail "keyframes were not smaller under the budget ($budget_kf >= $free_kf bytes)"
over=$(split_value keyframes_over_budget "$t")
sent=$(awk '$1 ~ /^(SLAM_KEYFRAME|SLAM_MAP_RECEIPT|SLAM_STATUS)$/ { s += $3 } END { print s + 0 }' "$WORK/budget/link.txt")
duration=$(split_value duration_s "$WORK/budget/link.txt")
allowed=$(awk -v k="$budget_kbps" -v d="$duration" -v o="$over" -v kf="$free_kf" \
  'BEGIN { printf "%.0f", k * 125 * (d + 2) + (o + 1) * kf }')
echo "tracker bytes on the link: $sent over $duration s; allowed $allowed ($over keyframes over budget)"
[ "$sent" -le "$allowed" ] || fail "the tracker sent $sent bytes, above the budget's $allowed"
free_ate=$(split_value ate_rmse_m "$WORK/free/eval.txt") budget_ate=$(split_value ate_rmse_m "$WORK/budget/eval.txt")
awk -v a="$budget_ate" -v b="$free_ate" 'BEGIN { exit !(a <= 2.0 * b) }' \
  || fail "ATE under the budget $budget_ate m is above 2x the unbudgeted run's $free_ate m"
echo "PASS"
