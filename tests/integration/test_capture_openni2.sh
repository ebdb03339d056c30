#!/usr/bin/env bash
# rgbd-capture streams OpenNI2's Dummy device over LCM inside a private network namespace;
# a subscriber checks that every published frame arrives and decodes; --list-devices works
# without hardware; a missing device is a clear error, promptly.
source "$(dirname "$0")/common.sh"
require_netns
N=45

"$PROCS/rgbd-capture" --list-devices > "$WORK/devices.txt" || fail "--list-devices failed"
grep -qi "openni2" "$WORK/devices.txt" || fail "--list-devices printed no OpenNI2 section: $(cat "$WORK/devices.txt")"

start=$(date +%s)
if "$NETNS_RUN" "$PROCS/rgbd-capture" --source openni2:/nonexistent/recording.oni 2> "$WORK/missing.log"; then
  fail "a missing recording was accepted"
fi
[ $(( $(date +%s) - start )) -le 10 ] || fail "a missing device took more than 10 s to report"
grep -q "/nonexistent/recording.oni" "$WORK/missing.log" || fail "the error does not name the device: $(cat "$WORK/missing.log")"

"$NETNS_RUN" bash -c "
set -euo pipefail
cd '$WORK'
'$TOOLS/frame-check' --count $N --timeout 60 --ready ready --lcm-url '$LCM_URL' > dummy.txt &
checker=\$!
for i in \$(seq 100); do [ -e ready ] && break; sleep 0.1; done
'$PROCS/rgbd-capture' --source openni2:Dummy --max-frames $N --lcm-url '$LCM_URL' 2> capture.log
wait \$checker
" || fail "Dummy capture failed: $(cat "$WORK/dummy.txt" "$WORK/capture.log" 2>/dev/null)"
echo "dummy: $(cat "$WORK/dummy.txt")"
grep -q "received $N matched 0 bad 0" "$WORK/dummy.txt" || fail "not every Dummy frame arrived intact"
echo "PASS"
