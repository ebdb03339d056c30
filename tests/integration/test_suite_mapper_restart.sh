#!/usr/bin/env bash
# Issue 4: the mapper killed with SIGKILL mid-run and restarted. The onboard/ground split
# (split.sh) on the synthetic room, 600 frames (20 s at 30 Hz): first a clean run, then the
# same with the mapper SIGKILLed ~7 s into the capture and restarted 1 s later with the same
# --state-dir (its journal). Asserts, for the run with the restart:
#   - the restarted mapper resumed from its journal: its summary says restored > 0 keyframes
#     (and its "restored map" line is on stderr);
#   - the run completes: every keyframe acknowledged (keyframes_unacked 0, tracker exit 0),
#     every keyframe the tracker made is in the mapper's map or was culled as redundant, and poses for >= 95 % of the frames (a loaded machine skips a few);
#   - the tracker's map version kept increasing across the restart: the restarted mapper's
#     first version is above every version published before the kill, the tracker rejected
#     none of its maps as stale (maps_stale 0), and its final version is above its version
#     before the kill;
#   - ATE <= 2x the clean run's (the issue's bound). Measured over four runs: 1.3x, 1.6x,
#     1.8x and 2.05x (a failure): the restarted mapper needs ~3 s to re-integrate a journal
#     of 7-9 keyframes before its first map, so the tracker goes ~4 s on provisional
#     keyframes, and the drift of that stretch stays in the logged trajectory.
source "$(dirname "$0")/common.sh"
source "$(dirname "$0")/link.sh"
source "$(dirname "$0")/split.sh"
require_netns
require_lcm_log
link_up
frames=600
seq=synth:room,frames=$frames
t_test=$SECONDS

split_start "$WORK/clean" 0
split_capture "$WORK/clean" "$seq"
split_finish_frames "$WORK/clean" "$frames"
split_report "$WORK/clean" clean "$frames"

dir=$WORK/restart
split_start "$dir" 0
# The capture in the background, so that this shell owns the restarted mapper.
split_capture "$dir" "$seq" &
capture=$!
sleep 7
date +%s%6N > "$dir/kill_utime"
split_kill_mapper
journal_bytes=$(stat -c %s "$dir/mapper-state/map.journal" 2>/dev/null || echo 0)
sleep 1
date +%s%6N > "$dir/restart_utime"
split_restart_mapper "$dir"
wait "$capture" || fail "rgbd-capture failed"
split_finish_frames "$dir" "$frames"
split_report "$dir" "mapper SIGKILLed at 7 s, restarted 1 s later" "$frames"

t=$dir/tracker.out
split_mapper_summary "$dir" > "$dir/mapper.summary"
m=$dir/mapper.summary
t_kill=$(cat "$dir/kill_utime") t_restart=$(cat "$dir/restart_utime")
$LCMLOG maps "$dir/link.lcm" > "$dir/maps.txt"
$LCMLOG status "$dir/link.lcm" SLAM_STATUS > "$dir/tracker-status.txt"
v_before_kill=$(awk -v u="$t_kill" '$1 <= u {v = $3} END {print v + 0}' "$dir/maps.txt")
acked_before_kill=$(awk -v u="$t_kill" '$1 <= u {a = $6} END {print a}' "$dir/maps.txt")
read -r first_after_utime v_first_after snap_first_after <<< \
  "$(awk -v u="$t_restart" '$1 >= u {print $1, $3, $4; exit}' "$dir/maps.txt")"
tracker_v_before_kill=$(awk -v u="$t_kill" '$2 == "rgbd-tracker" && $1 <= u' "$dir/tracker-status.txt" | tail -1 \
  | tr ' ' '\n' | awk -F= '$1 == "map_version" {print $2}')
restored_line=$(grep '^rgbd-mapper: restored map' "$dir/mapper.err" || true)
kfs=$(split_value keyframes "$t")
poses=$(tail -n +2 "$dir/trajectory.csv" | wc -l)
clean_ate=$(split_value ate_rmse_m "$WORK/clean/eval.txt")
ate=$(split_value ate_rmse_m "$dir/eval.txt")
echo "before the kill: mapper published up to version $v_before_kill acknowledging keyframes 0..$acked_before_kill," \
     "tracker at version ${tracker_v_before_kill:-?}, journal $journal_bytes bytes"
echo "after the restart: ${restored_line:-no restored line}"
echo "  first map $(awk -v a="$first_after_utime" -v b="$t_restart" 'BEGIN {printf "%.2f", (a - b) / 1e6}') s after the restart:" \
     "version $v_first_after (snapshot $snap_first_after); mapper summary: version $(split_value mapper_version "$m")," \
     "keyframes $(split_value mapper_keyframes "$m") ($(split_value mapper_restored "$m") restored), duplicates $(split_value mapper_duplicates "$m")"
echo "tracker: poses $poses/$frames, keyframes $(split_value keyframes_acked "$t")/$kfs acknowledged, map version" \
     "$(split_value map_version "$t") (newest seen $(split_value map_version_newest_seen "$t")), maps_stale $(split_value maps_stale "$t")," \
     "maps_missing_delta $(split_value maps_missing_delta "$t"), exit $(cat "$dir/tracker.exit")"
echo "ATE clean $clean_ate m, with the restart $ate m; test time $((SECONDS - t_test)) s"

[ "$(split_value keyframes_unacked "$WORK/clean/tracker.out")" = 0 ] || fail "clean: keyframes left unacknowledged"
[ -n "$restored_line" ] || fail "the restarted mapper did not report restoring its map: $(tail -5 "$dir/mapper.err")"
[ "$(split_value mapper_restored "$m")" -gt 0 ] || fail "the restarted mapper restored no keyframes"
[ "$kfs" -gt "$(split_value mapper_restored "$m")" ] || fail "no keyframe was made after the restart (nothing resumed)"
[ "$(split_value keyframes_unacked "$t")" = 0 ] || fail "keyframes left unacknowledged: $(tr '\n' ' ' < "$t")"
[ "$(split_value keyframes_acked "$t")" = "$kfs" ] || fail "$(split_value keyframes_acked "$t") of $kfs keyframes acknowledged"
[ "$(cat "$dir/tracker.exit")" = 0 ] || fail "the tracker exited with $(cat "$dir/tracker.exit")"
[ $(($(split_value mapper_keyframes "$m") + $(split_value mapper_culled "$m"))) = "$kfs" ] \
  || fail "the mapper holds $(split_value mapper_keyframes "$m") and culled $(split_value mapper_culled "$m") of $kfs keyframes"
[ "$poses" -ge $((frames * 95 / 100)) ] || fail "poses for $poses of $frames frames (< 95 %)"
[ -n "$v_first_after" ] || fail "the restarted mapper published no map"
[ "$v_first_after" -gt "$v_before_kill" ] \
  || fail "the restarted mapper's first version $v_first_after re-uses a version (<= $v_before_kill, published before the kill)"
[ "$(split_value maps_stale "$t")" = 0 ] || fail "the tracker rejected $(split_value maps_stale "$t") maps as stale"
[ "$(split_value map_version "$t")" -gt "${tracker_v_before_kill:-0}" ] \
  || fail "the tracker's map version $(split_value map_version "$t") is not above its ${tracker_v_before_kill:-0} before the kill"
[ "$(split_value map_version "$t")" = "$(split_value map_version_newest_seen "$t")" ] \
  || fail "the tracker ends on version $(split_value map_version "$t") but has seen $(split_value map_version_newest_seen "$t")"
awk -v a="$ate" -v b="$clean_ate" 'BEGIN { exit !(a <= 2 * b) }' \
  || fail "ATE with the restart $ate m is above 2x the clean run's $clean_ate m"
echo "PASS"
