#!/usr/bin/env bash
# Long flights (issue 10) in CI: the 2-minute flight (synth:flight,minutes=2: 3600 frames at
# 30 Hz through rooms joined by corridors, up to 2 m/s and 90 deg/s) through the suite split
# as on a vehicle: scripts/bench-suite runs rgbd-tracker and rgbd-mapper in two network
# namespaces joined by a veth (link.sh), logs the link and samples both processes' resident
# memory every 5 s. Bounds, the issue's targets:
#   - the tracker's resident memory at most 150 MB at every sample;
#   - the link, both ways (keyframes, maps, receipts, status; LCM payload in the link's log,
#     lcm-log-stats), at most 1 Mbit/s on average: the tracker's link budget (1000 kbit/s,
#     counting the maps it receives: common/link_budget.h) held.
# Sanity: every keyframe acknowledged; at least 600 frames posed (the flight's first 20 s,
# which the batch runner tracks whole; the tracker is then lost for long stretches: open work);
# every place the mapper recognised audited against the truth, and no wrong loop in the map.
# Not bounded here: the ATE (real-time runs of the flight spread 0.04-3.7 m: its tracking is
# open work) and the memory's course after the first minute (on jemalloc it rises for a
# sample or two and comes back: a bound on two minutes would measure those spikes, not a
# trend; the ten-minute flight shows the trend: docs/open_work.md, session 43).
# Measured 2026-11-30 (one run of this test, jemalloc): tracker peak 83.2 MB, 69.5-77.5 MB
# after the first minute, link 0.953 Mbit/s in all, 3469 / 3600 posed, 127 s.
source "$(dirname "$0")/common.sh"
require_netns
MAX_TRACKER_MB=150 MAX_LINK_MBIT_S=1.0 BUDGET_KBPS=1000

# The tracker at the normal priority (bench-suite's default is SCHED_FIFO, as on a vehicle):
# ctest runs two tests at once on CI's two cores, and a tracker relocalising under SCHED_FIFO
# would take a whole core from the other test's real-time processes.
"$SRC/scripts/bench-suite" --source synth:flight,minutes=2 --out "$WORK/bench" --memory-every 5 \
    --link-budget-kbps "$BUDGET_KBPS" --tracker-set tracker_node.realtime_priority=0 > "$WORK/bench.log" 2>&1 \
  || fail "bench-suite failed: $(tail -5 "$WORK/bench.log")"
dir=$WORK/bench/synth_flight_minutes_2
value() { awk -v k="$1" '$1 == k {print $2}' "$2"; }
cat "$dir/figures.txt"
echo "tracker memory [s: MB]: $(awk 'NR > 1 {printf "%s: %s  ", $1, $2}' "$dir/memory.txt")"

# The larger of the sampled peak and the tracker's own VmHWM at exit (a spike between samples).
peak=$(awk -v a="$(value tracker_peak_mb "$dir/figures.txt")" -v b="$(value peak_rss_mb "$dir/tracker.out")" \
  'BEGIN { print (b + 0 > a + 0) ? b : a }')
awk -v p="$peak" -v m="$MAX_TRACKER_MB" 'BEGIN { exit !(p > 0 && p <= m) }' \
  || fail "the tracker's peak resident memory $peak MB is above $MAX_TRACKER_MB MB"
total=$(value link_total_mbit_s "$dir/figures.txt")
awk -v t="$total" -v m="$MAX_LINK_MBIT_S" 'BEGIN { exit !(t > 0 && t <= m) }' \
  || fail "the link carried $total Mbit/s, above $MAX_LINK_MBIT_S"
[ "$(value keyframes_unacked "$dir/tracker.out")" = 0 ] || fail "keyframes left unacknowledged"
poses=$(value poses "$dir/figures.txt")
[ "$poses" -ge 600 ] || fail "only $poses of 3600 frames posed"
# The final map's keyframes (rgbd-mapper --keyframes-out) evaluated.
awk -v a="$(value ate_keyframes_rmse_m "$dir/figures.txt")" 'BEGIN { exit !(a + 0 > 0) }' \
  || fail "no ATE of the final map's keyframes: $(value ate_keyframes_rmse_m "$dir/figures.txt")"
# Loops (issue 11): every place the mapper recognised is audited against the truth
# (scripts/lib/loop_audit.py reads its log line), and none in the map is wrong.
[ "$(value loop_audit_checked "$dir/figures.txt")" = "$(value loops_recognised "$dir/figures.txt")" ] \
  || fail "$(value loops_recognised "$dir/figures.txt") places recognised, $(value loop_audit_checked "$dir/figures.txt") audited"
[ "$(value loops_accepted_wrong "$dir/figures.txt")" = 0 ] \
  || fail "$(value loops_accepted_wrong "$dir/figures.txt") loop edges in the map are off the truth"
echo "PASS"
