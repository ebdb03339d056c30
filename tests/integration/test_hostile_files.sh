#!/usr/bin/env bash
# Issue 13, files and options: each hostile file or option value makes every process that
# reads it exit with a clear message naming the file or option (status 2, or 1 for a source
# that fails while reading), within 20 s: no crash (status > 128), no hang, no exit 0.
# Each process runs inside a private network namespace (scripts/netns-run), since some open
# LCM before or after the check.
source "$(dirname "$0")/common.sh"
require_netns
CAMERA=$SRC/config/cameras/synthetic.yaml
SEQ=$WORK/seq
"$PROCS/synth-write" room,frames=4 "$SEQ" 2> /dev/null || fail "could not write a sequence"

expect() {  # expect CODE PATTERN PROCESS ARGS...: exit CODE, PATTERN in its output
  local code=$1 pattern=$2 process=$3
  shift 3
  set +e
  timeout -s KILL 20 "$NETNS_RUN" "$PROCS/$process" --lcm-url "$LCM_URL" "$@" > "$WORK/out.log" 2>&1
  local got=$?
  set -e
  [ "$got" -eq "$code" ] || fail "$process $*: exit $got, expected $code ($(tail -3 "$WORK/out.log"))"
  grep -q -- "$pattern" "$WORK/out.log" || fail "$process $*: no '$pattern' in: $(tail -3 "$WORK/out.log")"
  echo "ok $process ($code): $(grep -m1 -- "$pattern" "$WORK/out.log" | cut -c1-150)"
}

# A camera or configuration file whose top level is a list: every process that reads it.
printf '%%YAML:1.0\n- fx: 500\n- fy: 500\n' > "$WORK/list.yaml"
for process in rgbd-tracker rgbd-mapper; do
  expect 2 "list.yaml: the top level must be a mapping" $process --camera "$WORK/list.yaml"
  expect 2 "list.yaml: the top level must be a mapping" $process --camera "$CAMERA" --config "$WORK/list.yaml"
done
expect 2 "list.yaml: the top level must be a mapping" rgbd-capture --source "tum:$SEQ" --camera "$WORK/list.yaml"
expect 2 "list.yaml: the top level must be a mapping" rgbd-slam --source "tum:$SEQ" --camera "$WORK/list.yaml" --output "$WORK/t.txt"
expect 2 "list.yaml: the top level must be a mapping" rgbd-slam --source synth:room,frames=3 --config "$WORK/list.yaml" --output "$WORK/t.txt"
expect 2 "keyframe-rung: 6 is outside" rgbd-slam --source synth:room,frames=3 --output "$WORK/t.txt" --keyframe-rung 6
expect 2 "keyframe-rung" rgbd-slam --source synth:room,frames=3 --output "$WORK/t.txt" --keyframe-rung x
sed 's/^image_width: .*/image_width: 1e12/' "$CAMERA" > "$WORK/wide.yaml"
expect 2 "key 'image_width' is 1e+12, must be a whole number" rgbd-tracker --camera "$WORK/wide.yaml"

# Options: overflowing, non-finite, contradictory.
expect 2 "tracker_node.max_backlog_frames: 4294967296 is outside" rgbd-tracker --camera "$CAMERA" --set tracker_node.max_backlog_frames=4294967296
expect 2 "tracker_node.status_period_s: 'nan' is not a number" rgbd-tracker --camera "$CAMERA" --set tracker_node.status_period_s=nan
expect 2 "sync.resend_period_s: 'inf' is not a number" rgbd-tracker --camera "$CAMERA" --set sync.resend_period_s=inf
expect 2 "sync.resend_max_period_s must not be below sync.resend_period_s" rgbd-tracker --camera "$CAMERA" --set sync.resend_period_s=2,sync.resend_max_period_s=0.5
expect 2 "sync.map_period_s: 'inf' is not a number" rgbd-mapper --camera "$CAMERA" --set sync.map_period_s=inf --state-dir none
expect 2 "mapper.keyframe_min_depth_m must be below mapper.keyframe_max_depth_m" rgbd-mapper --camera "$CAMERA" --set mapper.keyframe_min_depth_m=9 --state-dir none
expect 2 "tracker.keyframe_min_depth_m must be below" rgbd-slam --source synth:room,frames=3 --set tracker.keyframe_max_depth_m=0.2 --output "$WORK/t.txt"
expect 2 "rate: 'nan' is not a finite number" rgbd-capture --source synth:room,frames=3 --rate nan

# Messages that named the wrong problem.
expect 2 "unknown key 'bogus'" rgbd-slam --source synth:room,bogus=1 --output "$WORK/t.txt"
expect 2 "camera is required for tum: sources" rgbd-slam --source "tum:$SEQ" --output "$WORK/t.txt"

# The mapper's journal is a directory.
mkdir -p "$WORK/state/map.journal"
expect 2 "map.journal: is not a regular file" rgbd-mapper --camera "$CAMERA" --state-dir "$WORK/state"

# TUM: a symlink loop; timestamps of 1e13 s.
cp -r "$SEQ" "$WORK/loop"; ln -s b.png "$WORK/loop/rgb/a.png"; ln -s a.png "$WORK/loop/rgb/b.png"
echo "9999.0 rgb/a.png" >> "$WORK/loop/rgb.txt"
expect 2 "names rgb/a.png, which cannot be reached" rgbd-capture --source "tum:$WORK/loop" --camera "$CAMERA"
cp -r "$SEQ" "$WORK/late"; awk '!/^#/ {$1 = $1 + 1e13} {print}' "$SEQ/rgb.txt" > "$WORK/late/rgb.txt"
expect 2 "is outside \[0," rgbd-slam --source "tum:$WORK/late" --camera "$CAMERA" --output "$WORK/t.txt"

# lcmlog: garbage, empty, truncated, an event length of 0x7fffffff.
head -c 5000 /dev/urandom > "$WORK/garbage.lcm"; : > "$WORK/empty.lcm"
expect 2 "not an LCM log" rgbd-capture --source "lcmlog:$WORK/garbage.lcm"
expect 2 "is empty" rgbd-slam --source "lcmlog:$WORK/empty.lcm" --camera "$CAMERA" --output "$WORK/t.txt"
python3 - "$WORK" <<'PY'
import struct, sys
work = sys.argv[1]
def event(n, channel, data, length=None):
    return struct.pack(">IqqII", 0xEDA1DA01, n, 1700000000000000 + n, len(channel),
                       len(data) if length is None else length) + channel + data
open(work + "/huge.lcm", "wb").write(event(0, b"RGBD_FRAME", b"\0" * 64, 0x7fffffff))
open(work + "/torn.lcm", "wb").write(event(0, b"OTHER", b"abc") + event(1, b"RGBD_FRAME", b"\0" * 64)[:50])
PY
expect 1 "claims 2147483647 data bytes" rgbd-capture --source "lcmlog:$WORK/huge.lcm"
expect 1 "claims 64 data bytes" rgbd-slam --source "lcmlog:$WORK/torn.lcm" --camera "$CAMERA" --output "$WORK/t.txt"

# Pacing by recorded timestamps across a 31-year gap: reported, not waited for.
cp -r "$SEQ" "$WORK/gap"; awk '!/^#/ && ++n > 2 {$1 = sprintf("%.6f", $1 + 1e9)} {print}' "$SEQ/rgb.txt" > "$WORK/gap/rgb.txt"
awk '!/^#/ && ++n > 2 {$1 = sprintf("%.6f", $1 + 1e9)} {print}' "$SEQ/depth.txt" > "$WORK/gap/depth.txt"
expect 0 "not waiting for it, pacing restarts" rgbd-capture --source "tum:$WORK/gap" --camera "$CAMERA"
grep -q "published 4 frames, 0 bad, pacing restarted 1 times" "$WORK/out.log" || fail "$(tail -2 "$WORK/out.log")"
echo "PASS"
