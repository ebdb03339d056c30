#!/usr/bin/env bash
# rgbd-capture on bad input: each case ends with a clear message naming the file, line or
# size, and frames that can be read are still published (inside a private namespace).
source "$(dirname "$0")/common.sh"
require_netns
CAMERA=$SRC/config/cameras/synthetic.yaml
SEQ=$WORK/seq

# A small valid TUM sequence from the renderer (the capture's own tum: reader reads it back).
"$PROCS/synth-write" room,frames=6 "$SEQ" 2> /dev/null || fail "could not write a sequence"

expect_error() {  # expect_error EXIT_CODE PATTERN ARGS...
  local code=$1 pattern=$2; shift 2
  set +e
  "$NETNS_RUN" "$PROCS/rgbd-capture" --rate 0 --lcm-url "$LCM_URL" "$@" > "$WORK/out.log" 2>&1
  local got=$?
  set -e
  [ "$got" -eq "$code" ] || fail "exit $got, expected $code for: $* ($(cat "$WORK/out.log"))"
  grep -q -- "$pattern" "$WORK/out.log" || fail "no '$pattern' in: $(cat "$WORK/out.log")"
  echo "ok ($code): $(grep -m1 -- "$pattern" "$WORK/out.log")"
}

expect_error 2 "/nonexistent/dir" --source tum:/nonexistent/dir --camera "$CAMERA"
grep -v '^fy:' "$CAMERA" > "$WORK/nofy.yaml"
expect_error 2 "missing key 'fy'" --source "tum:$SEQ" --camera "$WORK/nofy.yaml"
cp -r "$SEQ" "$WORK/badline"; echo "9999.0 rgb/none.png" >> "$WORK/badline/rgb.txt"
expect_error 2 "rgb.txt:[0-9]*: names rgb/none.png" --source "tum:$WORK/badline" --camera "$CAMERA"
cp -r "$SEQ" "$WORK/trunc"; f=$(ls "$WORK/trunc/rgb" | sed -n 3p); truncate -s 100 "$WORK/trunc/rgb/$f"
expect_error 1 "rgb/$f: cannot decode" --source "tum:$WORK/trunc" --camera "$CAMERA"
grep -q "published 5 frames, 1 bad" "$WORK/out.log" || fail "the other frames were not published"
cp -r "$SEQ" "$WORK/depth8"; f=$(ls "$WORK/depth8/depth" | sed -n 2p)
"$TOOLS/eight-bit-depth" "$WORK/depth8/depth/$f"
expect_error 1 "must be a 16-bit" --source "tum:$WORK/depth8" --camera "$CAMERA"
sed 's/^image_width: 640/image_width: 320/' "$CAMERA" > "$WORK/small.yaml"
expect_error 1 "but the camera file says 320x480" --source "tum:$SEQ" --camera "$WORK/small.yaml"
expect_error 2 "unknown source kind" --source bogus:thing
expect_error 2 "unknown key" --source "synth:room,colour=blue"
echo "PASS"
