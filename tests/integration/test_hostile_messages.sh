#!/usr/bin/env bash
# Issue 13, messages: small hostile messages on every subscribed channel, each of which
# crashed a process or cost gigabytes before (a map claiming 2^28 acknowledged ids, a keyframe
# claiming 10^8 measurements, a status claiming 10^8 counters sent where the mapper reads the
# tracker's map receipts, a keyframe with pyramid level 4, a keyframe at 1e155 m), then poses of two maps on SLAM_POSE. rgbd-tracker, rgbd-mapper
# and pose-logger must log and count every one, stay small and alive, and exit 0 on SIGINT;
# pose-logger keeps the first map's poses and reports the other map's.
# All inside a private network namespace (scripts/netns-run).
source "$(dirname "$0")/common.sh"
require_netns
CAMERA=$SRC/config/cameras/synthetic.yaml

"$NETNS_RUN" bash -c "
set -euo pipefail
cd '$WORK'
'$PROCS/rgbd-tracker' --camera '$CAMERA' --map-id 77 --lcm-url '$LCM_URL' > tracker.out 2> tracker.err &
tracker=\$!
'$PROCS/rgbd-mapper' --camera '$CAMERA' --state-dir state --lcm-url '$LCM_URL' > mapper.out 2> mapper.err &
mapper=\$!
'$PROCS/pose-logger' --output poses.txt --lcm-url '$LCM_URL' 2> logger.err &
logger=\$!
sleep 1
send() { '$TOOLS/send-messages' --lcm-url '$LCM_URL' --channel \$1 --bad \$2 --map-id 77; sleep 0.2; }
send SLAM_MAP map-huge-count
send SLAM_KEYFRAME keyframe-huge-counts
send SLAM_MAP_RECEIPT status-huge-counts
send SLAM_KEYFRAME keyframe-level-4
send SLAM_KEYFRAME keyframe-far
'$TOOLS/send-messages' --lcm-url '$LCM_URL' --poses 20 --map-id 5
'$TOOLS/send-messages' --lcm-url '$LCM_URL' --poses 10 --map-id 6
sleep 0.5
for pid in \$tracker \$mapper \$logger; do kill -0 \$pid; done  # all alive
# Resident memory stays small: nothing was allocated from the claimed counts.
for pid in \$tracker \$mapper \$logger; do awk '/VmHWM/ {print \$2}' /proc/\$pid/status; done > peak_kb.txt
kill -INT \$tracker \$mapper \$logger
wait \$tracker; wait \$mapper; wait \$logger  # each must exit 0
" || fail "a process crashed or failed: $(tail -3 "$WORK"/*.err 2>/dev/null)"

cd "$WORK"
count() { grep -c -- "$1" "$2" || true; }
echo "tracker: $(grep -m1 'num_keyframes' tracker.err | cut -c1-160)"
echo "mapper:  $(grep 'bad message on SLAM_KEYFRAME' mapper.err | cut -c1-160 | tr '\n' '|')"
echo "mapper:  $(grep -m1 'bad message on SLAM_STATUS' mapper.err | cut -c1-160)"
echo "pose-logger: $(grep '^pose-logger: [0-9]' logger.err)"
echo "peak resident memory [kB]: $(tr '\n' ' ' < peak_kb.txt)"
[ "$(count 'num_keyframes is 268435456' tracker.err)" = 1 ] || fail "the tracker did not report the map: $(cat tracker.err)"
[ "$(count 'num_measurements is 100000000' mapper.err)" = 1 ] || fail "the huge keyframe was not reported: $(cat mapper.err)"
[ "$(count 'pyramid level 4' mapper.err)" = 1 ] || fail "the level-4 keyframe was not reported"
[ "$(count 'beyond the world bound' mapper.err)" = 1 ] || fail "the far keyframe was not reported"
[ "$(count 'bad message on SLAM_MAP_RECEIPT' mapper.err)" = 1 ] || fail "the huge status on the receipt channel was not reported"
awk '{ if ($1 > 1500000) bad = 1 } END { exit bad }' peak_kb.txt || fail "a process grew past 1.5 GB: $(cat peak_kb.txt)"
[ "$(grep -vc '^#' poses.txt)" = 20 ] || fail "expected map 5's 20 poses, got $(grep -vc '^#' poses.txt)"
grep -q "20 poses (20 in the trajectory) of map 5, 0 bad messages, 10 poses of other maps (6)" logger.err \
  || fail "pose-logger summary: $(grep '^pose-logger: [0-9]' logger.err)"
grep -q "ignoring poses of map 6 (logging map 5)" logger.err || fail "the other map was not reported"
echo "PASS"
