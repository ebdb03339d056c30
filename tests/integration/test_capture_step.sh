#!/usr/bin/env bash
# rgbd-capture --step publishes one frame per Enter key: three key presses, three frames
# (equal to the renderer's), then end of input stops it; inside a private network namespace.
source "$(dirname "$0")/common.sh"
require_netns
"$NETNS_RUN" bash -c "
set -euo pipefail
cd '$WORK'
'$TOOLS/frame-check' --expect synth:room,frames=5 --count 3 --timeout 60 --ready ready \
    --lcm-url '$LCM_URL' > step.txt &
checker=\$!
for i in \$(seq 100); do [ -e ready ] && break; sleep 0.1; done
printf '\n\n\n' | '$PROCS/rgbd-capture' --source synth:room,frames=5 --step --lcm-url '$LCM_URL' 2> capture.log
wait \$checker
" || fail "step capture failed: $(cat "$WORK/step.txt" "$WORK/capture.log" 2>/dev/null)"
grep -q "published 3 frames" "$WORK/capture.log" || fail "expected 3 frames: $(cat "$WORK/capture.log")"
grep -q "received 3 matched 3 bad 0" "$WORK/step.txt" || fail "frames differ: $(cat "$WORK/step.txt")"
echo "PASS"
