#!/usr/bin/env bash
# Issue 4: bad input on every subscribed channel (truncated, oversized, wrong type, garbage, a
# frame of the wrong size, a keyframe for an unknown map, a map of another map, a map version
# from the past): each process logs it on stderr, counts it (summary and status message), and
# keeps running; after it, poses keep coming and keyframes are acknowledged; every process
# exits cleanly on SIGINT.
# One namespace (link.sh's onboard side, its local bus only): rgbd-mapper, rgbd-tracker
# (--map-id 77), pose-logger, lcm-logger of SLAM_STATUS|MAPPER_STATUS, and rgbd-capture --step
# on synth:room,frames=240 paced at ~30 Hz by this script, in two halves of 120 frames:
#   batch A (nothing tracked yet) | frames 0-119 | batch B (a map exists, version > 1) |
#   frames 120-239
# Batches (send-messages, one message each; A and B alike unless said):
#   RGBD_FRAME     (tracker)      truncated, oversized, wrongtype, garbage, frame-wrong-size
#   SLAM_MAP       (tracker)      truncated, oversized, wrongtype, garbage, map-foreign-map;
#                                 B also map-stale (version 1 of map 77)
#   SLAM_KEYFRAME  (mapper)       truncated, oversized, wrongtype, garbage;
#                                 B also keyframe-foreign-map (after keyframe 0 exists)
#   SLAM_MAP_RECEIPT (mapper)     garbage
#   SLAM_POSE      (pose-logger)  truncated, oversized, wrongtype, garbage
source "$(dirname "$0")/common.sh"
source "$(dirname "$0")/link.sh"
source "$(dirname "$0")/split.sh"
require_netns
require_lcm_log
link_up
dir=$WORK/bad
mkdir -p "$dir"
cam=$SRC/config/cameras/synthetic.yaml
half=120
t_test=$SECONDS

bg_onboard MAPPER "$PROCS/rgbd-mapper" --camera "$cam" --state-dir "$dir/mapper-state" --lcm-url "$LOCAL_URL" \
    > "$dir/mapper.out" 2> "$dir/mapper.err"
bg_onboard TRACKER "$PROCS/rgbd-tracker" --camera "$cam" --map-id 77 --lcm-url "$LOCAL_URL" \
    > "$dir/tracker.out" 2> "$dir/tracker.err"
bg_onboard LOGGER "$PROCS/pose-logger" --output "$dir/trajectory.txt" --lcm-url "$LOCAL_URL" 2> "$dir/logger.err"
bg_onboard STATUSLOG lcm-logger -q -f -c 'SLAM_STATUS|MAPPER_STATUS' --lcm-url="$LOCAL_URL" "$dir/status.lcm"
mkfifo "$dir/step"
bg_onboard CAPTURE bash -c 'f=$1 e=$2; shift 2; exec "$@" < "$f" 2> "$e"' step "$dir/step" "$dir/capture.err" \
    "$PROCS/rgbd-capture" --source "synth:room,frames=$((2 * half))" --step --clock host --depth raw \
    --groundtruth-out "$dir/groundtruth.txt" --lcm-url "$LOCAL_URL"
exec 4<> "$dir/step"  # the capture's Enter key (opened after every long-lived process)
for ((i = 0; i < 100; i++)); do grep -q "press Enter" "$dir/capture.err" 2>/dev/null && break; sleep 0.1; done
grep -q "press Enter" "$dir/capture.err" || fail "rgbd-capture did not start: $(cat "$dir/capture.err")"
sleep 1  # the subscribers are up

alive() {
  local name pid
  for name in MAPPER TRACKER LOGGER STATUSLOG CAPTURE; do
    pid=${!name}
    kill -0 "$pid" 2>/dev/null || fail "$1: $name (pid $pid) is not running any more"
  done
}
bad() {  # bad CHANNEL KIND [ARGS...]: one bad message, then a moment for it to be handled
  local channel=$1 kind=$2
  shift 2
  on_onboard "$TOOLS/send-messages" --channel "$channel" --bad "$kind" "$@" --lcm-url "$LOCAL_URL" \
    || fail "send-messages --channel $channel --bad $kind failed"
  sleep 0.1
}
batch() {
  local kind
  for kind in truncated oversized wrongtype garbage; do bad RGBD_FRAME $kind --type frame; done
  bad RGBD_FRAME frame-wrong-size
  for kind in truncated oversized wrongtype garbage; do bad SLAM_MAP $kind --type map; done
  bad SLAM_MAP map-foreign-map
  for kind in truncated oversized wrongtype garbage; do bad SLAM_KEYFRAME $kind --type keyframe; done
  bad SLAM_MAP_RECEIPT garbage
  for kind in truncated oversized wrongtype garbage; do bad SLAM_POSE $kind --type pose; done
}
frames() {  # frames N: N presses of Enter at ~30 Hz
  local i
  for ((i = 0; i < $1; i++)); do echo >&4; sleep 0.033; done
}

batch
alive "after batch A"
frames $half
sleep 2.5  # keyframes acknowledged, map versions > 1
date +%s%6N > "$dir/batch_b_start"
bad SLAM_MAP map-stale --map-id 77
bad SLAM_KEYFRAME keyframe-foreign-map
batch
date +%s%6N > "$dir/batch_b_end"
alive "after batch B"
frames $half
exec 4>&-  # end of input: the capture stops and writes the ground truth
sleep 2.5
for ((i = 0; i < 100; i++)); do kill -0 "$CAPTURE" 2>/dev/null || break; sleep 0.1; done
wait "$CAPTURE" || fail "rgbd-capture failed: $(tail -3 "$dir/capture.err")"
for name in MAPPER TRACKER LOGGER STATUSLOG; do
  kill -0 "${!name}" 2>/dev/null || fail "after the run: $name is not running any more"
done

# SIGINT, in the order of a normal shutdown; each must exit 0 within 10 s.
stop() {  # stop NAME: SIGINT, bounded wait, exit status into $dir/NAME.exit
  local pid=${!1} i status=0
  kill -INT "$pid"
  for ((i = 0; i < 100; i++)); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
  kill -0 "$pid" 2>/dev/null && { kill -KILL "$pid"; echo "hung" > "$dir/$1.exit"; wait "$pid" || true; return; }
  wait "$pid" || status=$?
  echo "$status" > "$dir/$1.exit"
}
stop TRACKER; sleep 0.3; stop MAPPER; stop LOGGER; stop STATUSLOG

t=$dir/tracker.out
value() { awk -v k="$1" '$1 == k {print $2}' "$2"; }
count() { grep -c -- "$1" "$2" || true; }
$LCMLOG status "$dir/status.lcm" SLAM_STATUS 2> /dev/null | awk '$2 == "rgbd-tracker"' > "$dir/tracker-status.txt"
$LCMLOG status "$dir/status.lcm" MAPPER_STATUS 2> /dev/null | awk '$2 == "rgbd-mapper"' > "$dir/mapper-status.txt"
status_value() { tail -1 "$2" | tr ' ' '\n' | awk -F= -v k="$1" '$1 == k {print $2}'; }
tb=$(cat "$dir/batch_b_start") te=$(cat "$dir/batch_b_end")
kf_before_b=$(awk -v u="$tb" '$1 <= u' "$dir/tracker-status.txt" | tail -1 | tr ' ' '\n' | awk -F= '$1 == "keyframes" {print $2}')
frames_after=$(awk -v u="$te" '!/^#/ && $1 * 1e6 > u' "$dir/groundtruth.txt" | wc -l)
poses_after=$(awk -F, -v u="$te" 'NR > 1 && $1 > u' "$dir/trajectory.csv" | wc -l)
poses=$(tail -n +2 "$dir/trajectory.csv" | wc -l)
"$PROCS/slam-eval" "$dir/groundtruth.txt" "$dir/trajectory.txt" --frames $((2 * half)) > "$dir/eval.txt" || fail "slam-eval failed"
summary=$(grep '^rgbd-mapper: map ' "$dir/mapper.err" | tail -1)
mapper_bad=$(sed -nE 's/.*, bad messages ([0-9]+),.*/\1/p' <<< "$summary")
mapper_foreign=$(sed -nE 's/.*, foreign map ([0-9]+),.*/\1/p' <<< "$summary")
logger_bad=$(sed -nE 's/^pose-logger: .* ([0-9]+) bad messages.*/\1/p' "$dir/logger.err")

echo "tracker: frames $(value frames "$t") (skipped $(value frames_skipped "$t")), poses $(value poses "$t") (CSV $poses/$((2 * half)); after batch B $poses_after of $frames_after frames)," \
     "keyframes $(value keyframes_acked "$t")/$(value keyframes "$t") acknowledged (${kf_before_b:-?} before batch B)," \
     "map version $(value map_version "$t"), ATE $(value ate_rmse_m "$dir/eval.txt") m"
echo "tracker counts: bad_messages $(value bad_messages "$t") (stderr: RGBD_FRAME $(count 'bad message on RGBD_FRAME' "$dir/tracker.err")," \
     "SLAM_MAP $(count 'bad message on SLAM_MAP' "$dir/tracker.err")), bad_frames $(value bad_frames "$t")" \
     "(stderr $(count 'skipped:' "$dir/tracker.err")), maps_foreign $(value maps_foreign "$t") (stderr $(count 'of map 424242' "$dir/tracker.err"))," \
     "maps_stale $(value maps_stale "$t") (stderr $(grep -ciE 'stale|version 1 of map 77|map version 1 ' "$dir/tracker.err" || true));" \
     "SLAM_STATUS: bad_frame_messages $(status_value bad_frame_messages "$dir/tracker-status.txt")" \
     "bad_map_messages $(status_value bad_map_messages "$dir/tracker-status.txt") bad_frames $(status_value bad_frames "$dir/tracker-status.txt")" \
     "maps_stale $(status_value maps_stale "$dir/tracker-status.txt") maps_foreign $(status_value maps_foreign "$dir/tracker-status.txt")"
echo "mapper: $summary"
echo "mapper counts: stderr SLAM_KEYFRAME $(count 'bad message on SLAM_KEYFRAME' "$dir/mapper.err"), foreign $(count 'of map 424242' "$dir/mapper.err")," \
     "SLAM_MAP_RECEIPT $(count 'bad message on SLAM_MAP_RECEIPT' "$dir/mapper.err"); MAPPER_STATUS: bad_messages $(status_value bad_messages "$dir/mapper-status.txt")" \
     "foreign_map_keyframes $(status_value foreign_map_keyframes "$dir/mapper-status.txt") bad_receipts $(status_value bad_receipts "$dir/mapper-status.txt")"
echo "pose-logger: $(grep '^pose-logger: [0-9]' "$dir/logger.err") (stderr SLAM_POSE $(count 'bad message on SLAM_POSE' "$dir/logger.err"))"
echo "exit on SIGINT: tracker $(cat "$dir/TRACKER.exit"), mapper $(cat "$dir/MAPPER.exit"), pose-logger $(cat "$dir/LOGGER.exit"), lcm-logger $(cat "$dir/STATUSLOG.exit"); test time $((SECONDS - t_test)) s"

# Each process exited cleanly.
for name in TRACKER MAPPER LOGGER STATUSLOG; do
  [ "$(cat "$dir/$name.exit")" = 0 ] || fail "$name exited with $(cat "$dir/$name.exit") on SIGINT"
done
# Still working after the bad input.
# (the tracker's frames count the two wrong-size frames too: they decode, then fail the
# camera; frames_skipped counts those overtaken in its backlog, never decoded)
[ $(($(value frames "$t") - $(value bad_frames "$t") + $(value frames_skipped "$t"))) = $((2 * half)) ] \
  || fail "the tracker took $(value frames "$t") frames ($(value bad_frames "$t") bad, $(value frames_skipped "$t") skipped) for $((2 * half)) real ones"
[ "$frames_after" -ge $((half - 5)) ] || fail "only $frames_after frames were captured after batch B"
[ "$poses_after" -ge $((frames_after * 95 / 100)) ] || fail "poses for $poses_after of $frames_after frames after batch B"
[ "$poses" -ge $((2 * half * 95 / 100)) ] || fail "poses for $poses of $((2 * half)) frames"
[ "$(value keyframes_unacked "$t")" = 0 ] && [ "$(value keyframes_acked "$t")" = "$(value keyframes "$t")" ] \
  || fail "keyframes: $(value keyframes_acked "$t") of $(value keyframes "$t") acknowledged"
[ -n "$kf_before_b" ] && [ "$kf_before_b" -gt 0 ] || fail "no keyframe before batch B (keyframe-foreign-map needs one)"
[ "$(value keyframes "$t")" -gt "$kf_before_b" ] || fail "no keyframe made after batch B"
awk -v a="$(value ate_rmse_m "$dir/eval.txt")" 'BEGIN { exit !(a <= 0.005) }' || fail "ATE above 5 mm"
# rgbd-tracker: logged and counted.
[ "$(count 'bad message on RGBD_FRAME' "$dir/tracker.err")" = 8 ] || fail "the tracker logged $(count 'bad message on RGBD_FRAME' "$dir/tracker.err") of 8 bad RGBD_FRAME messages"
[ "$(count 'bad message on SLAM_MAP' "$dir/tracker.err")" = 8 ] || fail "the tracker logged $(count 'bad message on SLAM_MAP' "$dir/tracker.err") of 8 bad SLAM_MAP messages"
[ "$(value bad_messages "$t")" = 16 ] || fail "the tracker counted $(value bad_messages "$t") of 16 bad messages"
[ "$(count 'skipped:' "$dir/tracker.err")" = 2 ] && [ "$(value bad_frames "$t")" = 2 ] \
  || fail "wrong-size frames: $(count 'skipped:' "$dir/tracker.err") logged, $(value bad_frames "$t") counted, of 2"
[ "$(count 'of map 424242' "$dir/tracker.err")" = 2 ] && [ "$(value maps_foreign "$t")" = 2 ] \
  || fail "foreign maps: $(count 'of map 424242' "$dir/tracker.err") logged, $(value maps_foreign "$t") counted, of 2"
[ "$(status_value bad_frame_messages "$dir/tracker-status.txt")" = 8 ] && [ "$(status_value bad_map_messages "$dir/tracker-status.txt")" = 8 ] \
  && [ "$(status_value bad_frames "$dir/tracker-status.txt")" = 2 ] && [ "$(status_value maps_foreign "$dir/tracker-status.txt")" = 2 ] \
  || fail "the tracker's last SLAM_STATUS does not count the bad input: $(tail -1 "$dir/tracker-status.txt")"
[ "$(value maps_stale "$t")" -ge 1 ] && [ "$(status_value maps_stale "$dir/tracker-status.txt")" -ge 1 ] \
  || fail "the stale map was not counted (maps_stale $(value maps_stale "$t"))"
[ "$(value map_version "$t")" -gt 1 ] || fail "the tracker's map version went back to $(value map_version "$t")"
grep -qiE 'stale|version 1 of map 77|map version 1 ' "$dir/tracker.err" \
  || fail "the tracker counted the stale map (version 1 of map 77) but did not log it on stderr"
# rgbd-mapper.
[ "$(count 'bad message on SLAM_KEYFRAME' "$dir/mapper.err")" = 8 ] && [ "$mapper_bad" = 8 ] \
  && [ "$(status_value bad_messages "$dir/mapper-status.txt")" = 8 ] \
  || fail "bad keyframe messages: $(count 'bad message on SLAM_KEYFRAME' "$dir/mapper.err") logged, $mapper_bad in the summary, of 8"
[ "$(count 'of map 424242' "$dir/mapper.err")" = 1 ] && [ "$mapper_foreign" = 1 ] \
  && [ "$(status_value foreign_map_keyframes "$dir/mapper-status.txt")" = 1 ] \
  || fail "foreign keyframe: $(count 'of map 424242' "$dir/mapper.err") logged, $mapper_foreign in the summary, of 1"
[ "$(count 'bad message on SLAM_MAP_RECEIPT' "$dir/mapper.err")" = 2 ] && [ "$(status_value bad_receipts "$dir/mapper-status.txt")" = 2 ] \
  || fail "bad SLAM_MAP_RECEIPT: $(count 'bad message on SLAM_MAP_RECEIPT' "$dir/mapper.err") logged, $(status_value bad_receipts "$dir/mapper-status.txt") counted, of 2"
# pose-logger.
[ "$(count 'bad message on SLAM_POSE' "$dir/logger.err")" = 8 ] && [ "$logger_bad" = 8 ] \
  || fail "bad poses: $(count 'bad message on SLAM_POSE' "$dir/logger.err") logged, $logger_bad counted, of 8"
echo "PASS"
