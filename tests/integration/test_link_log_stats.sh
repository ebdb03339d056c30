#!/usr/bin/env bash
# lcm-log-stats, the tool for the link's closing figures: on a log of known traffic (50
# pose_t at 50 Hz on SLAM_POSE, one status_t on SLAM_STATUS, recorded by lcm-logger inside a
# private network namespace) it reports the right counts and bytes per channel, rates over
# the log's duration, and JSON that parses to the same figures. The recording waits until
# lcm-logger is seen writing (warm-up messages on WARMUP) and until the log stops growing,
# rather than for fixed times: on a loaded machine it once missed 14 poses and the status.
source "$(dirname "$0")/common.sh"
require_netns
command -v lcm-logger > /dev/null || skip "lcm-logger (liblcm-bin) is missing"
"$NETNS_RUN" bash -c "
set -euo pipefail
cd '$WORK'
timeout 60 lcm-logger --lcm-url='$LCM_URL' run.lcm > logger.out 2>&1 &
logger=\$!
for i in \$(seq 200); do  # until the logger writes (at most 20 s)
  '$TOOLS/send-messages' --poses 1 --channel WARMUP --lcm-url '$LCM_URL'
  [ -s run.lcm ] && break
  sleep 0.1
done
[ -s run.lcm ] || { echo 'lcm-logger never wrote' > logger.out; exit 1; }
'$TOOLS/send-messages' --poses 50 --rate 50 --lcm-url '$LCM_URL'
'$TOOLS/send-messages' --bad wrongtype --channel SLAM_STATUS --lcm-url '$LCM_URL'
last=-1
for i in \$(seq 100); do  # until the log stops growing for 0.5 s (at most 10 s)
  size=\$(stat -c %s run.lcm)
  [ \"\$size\" = \"\$last\" ] && break
  last=\$size
  sleep 0.5
done
kill -INT \$logger
wait \$logger || true
" || fail "recording the log failed: $(cat "$WORK/logger.out" 2>/dev/null)"

"$TOOLS/lcm-log-stats" "$WORK/run.lcm" --json "$WORK/stats.json" > "$WORK/stats.txt" || fail "lcm-log-stats failed"
cat "$WORK/stats.txt"
python3 - "$WORK/stats.json" <<'EOF' || fail "the JSON figures are wrong"
import json, sys
s = json.load(open(sys.argv[1]))
pose, status, total = s["channels"]["SLAM_POSE"], s["channels"]["SLAM_STATUS"], s["total"]
assert pose["messages"] == 50 and status["messages"] == 1, s
assert pose["bytes"] % 50 == 0 and pose["bytes"] > 0, pose   # every pose_t has the same size
channels = s["channels"].values()
assert total["messages"] == sum(c["messages"] for c in channels), s
assert total["bytes"] == sum(c["bytes"] for c in channels), s
# The log spans the warm-up and the 50 poses at 50 Hz (0.98 s between the first and last).
assert 0.9 < s["duration_s"] < 30.0, s["duration_s"]
rate = pose["bytes"] / s["duration_s"]
assert abs(pose["bytes_per_s"] - rate) < 0.1 and abs(pose["kbit_per_s"] - rate * 8e-3) < 1e-3, pose
print("json ok: SLAM_POSE %d B in %.3f s = %.1f kbit/s" % (pose["bytes"], s["duration_s"], pose["kbit_per_s"]))
EOF
# The table says the same.
awk '$1 == "SLAM_POSE" && $2 == 50 { ok = 1 } END { exit !ok }' "$WORK/stats.txt" || fail "table row for SLAM_POSE wrong"
"$TOOLS/lcm-log-stats" "$WORK/missing.lcm" > /dev/null 2>&1 && fail "a missing log was not an error"
echo "PASS"
