#!/usr/bin/env bash
# lcm-log-stats, the tool for the link's closing figures: on a log of known traffic (50
# pose_t at 50 Hz on SLAM_POSE, one status_t on SLAM_STATUS, recorded by lcm-logger inside a
# private network namespace) it reports the right counts and bytes per channel, rates over
# the log's duration, and JSON that parses to the same figures.
source "$(dirname "$0")/common.sh"
require_netns
command -v lcm-logger > /dev/null || skip "lcm-logger (liblcm-bin) is missing"
"$NETNS_RUN" bash -c "
set -euo pipefail
cd '$WORK'
timeout 30 lcm-logger --lcm-url='$LCM_URL' run.lcm > logger.out 2>&1 &
logger=\$!
sleep 0.5
'$TOOLS/send-messages' --poses 50 --rate 50 --lcm-url '$LCM_URL'
'$TOOLS/send-messages' --bad wrongtype --channel SLAM_STATUS --lcm-url '$LCM_URL'
sleep 0.5
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
assert total["messages"] == 51 and total["bytes"] == pose["bytes"] + status["bytes"], s
# 50 messages at 50 Hz span about 1 s (0.98 s between the first and the last pose_t).
assert 0.9 < s["duration_s"] < 3.0, s["duration_s"]
rate = pose["bytes"] / s["duration_s"]
assert abs(pose["bytes_per_s"] - rate) < 0.1 and abs(pose["kbit_per_s"] - rate * 8e-3) < 1e-3, pose
print("json ok: SLAM_POSE %d B in %.3f s = %.1f kbit/s" % (pose["bytes"], s["duration_s"], pose["kbit_per_s"]))
EOF
# The table says the same.
awk '$1 == "SLAM_POSE" && $2 == 50 { ok = 1 } END { exit !ok }' "$WORK/stats.txt" || fail "table row for SLAM_POSE wrong"
"$TOOLS/lcm-log-stats" "$WORK/missing.lcm" > /dev/null 2>&1 && fail "a missing log was not an error"
echo "PASS"
