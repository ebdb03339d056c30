#!/usr/bin/env bash
# rgbd-capture plays tum_fr3_teddy_200 over LCM inside a private network namespace; a
# subscriber checks that every frame arrives and equals the pixels on disk. The run is
# recorded with lcm-logger, replayed with lcm-logplayer, and must yield the same frames;
# rgbd-capture reading the log (lcmlog:) must too.
source "$(dirname "$0")/common.sh"
require_netns
DATA=$(require_shared_data tum_fr3_teddy_200)
CAMERA=$SRC/config/cameras/tum_fr3.yaml
# Frames whose colour has a depth partner within 0.02 s (one-to-one): what the source publishes.
N=$(python3 - "$DATA" <<'PY'
import sys
d = sys.argv[1]
def read(name):
    return [float(l.split()[0]) for l in open(f"{d}/{name}") if l.strip() and not l.startswith("#")]
rgb, depth = read("rgb.txt"), read("depth.txt")
pairs = sorted((abs(a - b), i, j) for i, a in enumerate(rgb) for j, b in enumerate(depth) if abs(a - b) <= 0.02)
used_r, used_d = set(), set()
for _, i, j in pairs:
    if i not in used_r and j not in used_d:
        used_r.add(i); used_d.add(j)
print(len(used_r))
PY
)
echo "expecting $N frames"

"$NETNS_RUN" bash -c "
set -euo pipefail
cd '$WORK'
'$TOOLS/frame-check' --expect 'tum:$DATA' --camera '$CAMERA' --count $N --timeout 120 \
    --ready ready1 --lcm-url '$LCM_URL' > live.txt &
checker=\$!
lcm-logger -q -f -c RGBD_FRAME --lcm-url='$LCM_URL' run.lcm &
logger=\$!
for i in \$(seq 100); do [ -e ready1 ] && break; sleep 0.1; done
sleep 0.5  # lcm-logger gives no ready signal; it subscribes within milliseconds
'$PROCS/rgbd-capture' --source 'tum:$DATA' --camera '$CAMERA' --rate 30 --lcm-url '$LCM_URL'
wait \$checker
sleep 0.5; kill -INT \$logger; wait \$logger || true

'$TOOLS/frame-check' --expect 'tum:$DATA' --camera '$CAMERA' --count $N --timeout 120 \
    --ready ready2 --lcm-url '$LCM_URL' > replay.txt &
checker=\$!
for i in \$(seq 100); do [ -e ready2 ] && break; sleep 0.1; done
lcm-logplayer --lcm-url='$LCM_URL' run.lcm
wait \$checker

'$TOOLS/frame-check' --expect 'tum:$DATA' --camera '$CAMERA' --count $N --timeout 120 \
    --ready ready3 --lcm-url '$LCM_URL' > fromlog.txt &
checker=\$!
for i in \$(seq 100); do [ -e ready3 ] && break; sleep 0.1; done
'$PROCS/rgbd-capture' --source 'lcmlog:run.lcm' --camera '$CAMERA' --rate 30 --lcm-url '$LCM_URL'
wait \$checker
" || fail "a stage failed: live=$(cat "$WORK/live.txt" 2>/dev/null) replay=$(cat "$WORK/replay.txt" 2>/dev/null) fromlog=$(cat "$WORK/fromlog.txt" 2>/dev/null)"
for stage in live replay fromlog; do
  echo "$stage: $(cat "$WORK/$stage.txt")"
  grep -q "received $N matched $N bad 0" "$WORK/$stage.txt" || fail "$stage did not deliver all $N frames intact"
done
echo "PASS"
