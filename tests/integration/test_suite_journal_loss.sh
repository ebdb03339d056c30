#!/usr/bin/env bash
# Issue 13: one corrupt byte in the mapper's journal lost the acknowledged keyframes after it
# (the journal is cut at the corrupt record), the tracker never re-sent acknowledged
# keyframes, and the restarted mapper waited for them for ever; its versions, journaled too,
# went backwards, so the tracker refused every map after the restart as stale.
# The onboard/ground split (split.sh) on the synthetic room, 600 frames: the mapper is
# SIGKILLed ~8 s into the capture, one byte in the middle of its journal is flipped, and it is
# restarted on that journal. Asserts:
#   - the restarted mapper reports the corrupt record and restored fewer keyframes than it
#     had acknowledged;
#   - the tracker noticed (mapper_losses >= 1) and sent the lost keyframes again (it retains
#     64, more than this run makes), so the mapper ends with every keyframe the tracker made
#     (none skipped), every keyframe is acknowledged and the tracker exits 0;
#   - the mapper caught its versions up with the tracker's (versions_caught_up >= 1 in its
#     status) and the tracker ends on the newest version it has seen;
#   - poses for >= 95 % of the frames, ATE under 10 mm (the clean split run: 1.5-3 mm).
source "$(dirname "$0")/common.sh"
source "$(dirname "$0")/link.sh"
source "$(dirname "$0")/split.sh"
require_netns
require_lcm_log
link_up
frames=600
dir=$WORK/loss
split_start "$dir" 0
split_capture "$dir" "synth:room,frames=$frames" &
capture=$!
sleep 8
split_kill_mapper
journal=$dir/mapper-state/map.journal
size=$(stat -c %s "$journal")
[ "$size" -gt 1000 ] || fail "the journal holds only $size bytes after 8 s"
offset=$((size / 2))
byte=$(od -An -tu1 -j "$offset" -N1 "$journal" | tr -d ' ')
printf "$(printf '\\%03o' $(( (byte + 1) % 256 )))" | dd of="$journal" bs=1 seek="$offset" conv=notrunc status=none
echo "flipped the byte at $offset of $size in the journal"
split_restart_mapper "$dir"
wait "$capture" || fail "rgbd-capture failed"
split_finish_frames "$dir" "$frames"
split_report "$dir" "journal byte flipped after a SIGKILL at 8 s" "$frames"

t=$dir/tracker.out
split_mapper_summary "$dir" > "$dir/mapper.summary"
m=$dir/mapper.summary
$LCMLOG status "$dir/link.lcm" MAPPER_STATUS > "$dir/mapper-status.txt"
caught_up=$(tail -1 "$dir/mapper-status.txt" | tr ' ' '\n' | awk -F= '$1 == "versions_caught_up" {print $2}')
skipped=$(tail -1 "$dir/mapper-status.txt" | tr ' ' '\n' | awk -F= '$1 == "keyframes_skipped" {print $2}')
kfs=$(split_value keyframes "$t")
poses=$(tail -n +2 "$dir/trajectory.csv" | wc -l)
ate=$(split_value ate_rmse_m "$dir/eval.txt")
echo "mapper: $(grep -m1 'corrupt record' "$dir/mapper.err" || echo 'no corrupt-record line')"
echo "mapper: restored $(split_value mapper_restored "$m"), keyframes $(split_value mapper_keyframes "$m") of $kfs," \
     "versions caught up ${caught_up:-?}, keyframes skipped ${skipped:-?}"
echo "tracker: mapper_losses $(split_value mapper_losses "$t"), unacked $(split_value keyframes_unacked "$t")," \
     "map version $(split_value map_version "$t") (newest seen $(split_value map_version_newest_seen "$t"))," \
     "poses $poses/$frames, ATE $ate m, exit $(cat "$dir/tracker.exit")"

grep -q 'corrupt record' "$dir/mapper.err" || fail "the mapper did not report the corrupt journal record"
[ "$(split_value mapper_restored "$m")" -lt "$kfs" ] || fail "nothing was lost from the journal"
[ "$(split_value mapper_losses "$t")" -ge 1 ] || fail "the tracker did not notice the mapper's loss"
[ "$(split_value keyframes_unacked "$t")" = 0 ] || fail "keyframes left unacknowledged: $(tr '\n' ' ' < "$t")"
[ "$(cat "$dir/tracker.exit")" = 0 ] || fail "the tracker exited with $(cat "$dir/tracker.exit")"
[ $(($(split_value mapper_keyframes "$m") + $(split_value mapper_culled "$m"))) = "$kfs" ] \
  || fail "the mapper holds $(split_value mapper_keyframes "$m") and culled $(split_value mapper_culled "$m") of $kfs keyframes"
[ "${skipped:-x}" = 0 ] || fail "the mapper skipped ${skipped:-?} keyframes the tracker still held"
[ "${caught_up:-0}" -ge 1 ] || fail "the mapper's versions did not catch up with the tracker's"
[ "$(split_value map_version "$t")" = "$(split_value map_version_newest_seen "$t")" ] \
  || fail "the tracker ends on version $(split_value map_version "$t") but has seen $(split_value map_version_newest_seen "$t")"
[ "$poses" -ge $((frames * 95 / 100)) ] || fail "poses for $poses of $frames frames (< 95 %)"
awk -v a="$ate" 'BEGIN { exit !(a < 0.010) }' || fail "ATE $ate m is not under 10 mm"
echo "PASS"
