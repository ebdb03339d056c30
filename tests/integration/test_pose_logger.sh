#!/usr/bin/env bash
# pose-logger inside a private network namespace: valid poses become TUM lines and CSV rows;
# truncated, oversized, wrong-type and garbage messages are reported and counted while it
# keeps running; SIGKILL mid-stream leaves only whole lines; SIGINT ends it cleanly (exit 0).
source "$(dirname "$0")/common.sh"
require_netns

"$NETNS_RUN" bash -c "
set -euo pipefail
cd '$WORK'
'$PROCS/pose-logger' --output clean.txt --map-output clean_map.txt --lcm-url '$LCM_URL' 2> clean.log &
logger=\$!
sleep 0.5
for kind in truncated oversized wrongtype garbage; do
  '$TOOLS/send-messages' --bad \$kind --lcm-url '$LCM_URL'
done
'$TOOLS/send-messages' --poses 50 --lcm-url '$LCM_URL'
sleep 0.5
kill -0 \$logger  # still running after the bad messages
kill -INT \$logger
wait \$logger  # must exit 0

'$PROCS/pose-logger' --output killed.txt --lcm-url '$LCM_URL' 2> killed.log &
logger=\$!
sleep 0.5
'$TOOLS/send-messages' --poses 2000 --rate 2000 --lcm-url '$LCM_URL' &
sender=\$!
# Kill it mid-stream: once it has written some lines, while the sender is still going.
for i in \$(seq 200); do [ \$(wc -l < killed.txt) -ge 20 ] && break; sleep 0.05; done
kill -KILL \$logger
wait \$sender || true
wait \$logger || true
" || fail "a stage failed: $(cat "$WORK"/*.log 2>/dev/null)"

cd "$WORK"
[ "$(grep -vc '^#' clean.txt)" -eq 50 ] || fail "expected 50 trajectory lines, got $(grep -vc '^#' clean.txt)"
[ "$(tail -n +2 clean.csv | wc -l)" -eq 50 ] || fail "expected 50 CSV rows"
# The map poses: the same frames, 1 m along x from the published ones (send-messages), part 5.
[ "$(grep -vc '^#' clean_map.txt)" -eq 50 ] || fail "expected 50 map trajectory lines"
paste -d' ' <(grep -v '^#' clean.txt) <(grep -v '^#' clean_map.txt) | awk '
  $1 != $9 || ($10 - $2 - 1) ^ 2 > 1e-12 || ($11 - $3) ^ 2 > 1e-12 || $8 != $16 { bad = 1 } END { exit bad }' \
  || fail "the map trajectory is not the published one moved 1 m along x"
awk -F, 'NR > 1 && $21 != 5 { bad = 1 } END { exit bad }' clean.csv || fail "the CSV's part is not 5"
grep -q "4 bad messages" clean.log || fail "bad messages not counted: $(cat clean.log)"
for kind in "truncated" "beyond" "does not decode"; do
  grep -q "$kind" clean.log || fail "no message mentioning '$kind' in: $(cat clean.log)"
done
# Every line of the killed run is whole: 8 fields, the last ending in a digit, newline-terminated.
lines=$(grep -vc '^#' killed.txt || true)
[ "$lines" -gt 0 ] || fail "the killed logger wrote nothing"
awk '!/^#/ && NF != 8 { bad = 1 } END { exit bad }' killed.txt || fail "partial line in killed.txt"
[ -z "$(tail -c 1 killed.txt)" ] || fail "killed.txt does not end with a newline"
awk -F, 'NR > 1 && NF != 21 { bad = 1 } END { exit bad }' killed.csv || fail "partial line in killed.csv"
echo "clean: 50 poses, 4 bad messages counted; killed after $lines lines, no partial line"
echo "PASS"
