#!/usr/bin/env bash
# The onboard/ground link harness itself (tests/integration/link.sh, issue 4), with lcm-ping
# and lcm-link-relay: the local bus stays in its namespace while the link bus crosses the
# veth, both at once; 10 % loss loses about 10 %; the relay adds at least its 50 ms; during
# an outage nothing arrives and afterwards traffic flows again (blackout and --admin); a
# bandwidth cap lets through about its rate. Needs lcm-ping and lcm-link-relay; about 20 s.
# Measured 2026-11-22: loss 9.6-11.6 % of 2000; relay delay min 50.1, median 51.0 ms;
# 800 kbit/s cap: 287 of 2000 x 1000 B.
source "$(dirname "$0")/common.sh"
source "$(dirname "$0")/link.sh"
require_netns
PING=$TOOLS/lcm-ping
[ -x "$PING" ] && [ -x "$TOOLS/lcm-link-relay" ] || fail "build lcm-ping and lcm-link-relay first"

# value FILE KEY: the value of "KEY value" in FILE.
value() { awk -v k="$2" '$1 == k { print $2 }' "$1"; }

link_up

# 1. Both buses at once: onboard publishes on each; the local one reaches onboard only, the
#    link one reaches ground, and only the link one moves packets over the veth.
bg_onboard RX_LOCAL "$PING" recv --channel LOCAL_PING --lcm-url "$LOCAL_URL" --count 200 --timeout 5 --idle 1 > "$WORK/local_onboard.out"
bg_ground RX_LOCAL_G "$PING" recv --channel LOCAL_PING --lcm-url "$LOCAL_URL" --count 200 --timeout 3 --idle 1 > "$WORK/local_ground.out" 2>&1
bg_ground RX_LINK "$PING" recv --channel LINK_PING --lcm-url "$LINK_URL" --count 200 --timeout 5 --idle 1 > "$WORK/link_ground.out"
sleep 0.5
tx0=$(link_packets onboard tx)
bg_onboard TX_LOCAL "$PING" send --channel LOCAL_PING --lcm-url "$LOCAL_URL" --count 200 --rate 1000 > /dev/null
on_onboard "$PING" send --channel LINK_PING --lcm-url "$LINK_URL" --count 200 --rate 1000 > /dev/null
wait "$TX_LOCAL"
wait "$RX_LOCAL" && wait "$RX_LOCAL_G" && wait "$RX_LINK" || fail "a receiver failed"
tx1=$(link_packets onboard tx)
echo "local bus: onboard $(value "$WORK/local_onboard.out" received)/200, ground $(value "$WORK/local_ground.out" received); link bus: ground $(value "$WORK/link_ground.out" received)/200; veth tx +$((tx1 - tx0)) packets"
[ "$(value "$WORK/local_onboard.out" received)" -eq 200 ] || fail "the local bus lost messages inside onboard"
[ "$(value "$WORK/local_ground.out" received)" -eq 0 ] || fail "the local bus reached ground"
[ "$(value "$WORK/link_ground.out" received)" -eq 200 ] || fail "the link bus lost messages without impairment"
[ $((tx1 - tx0)) -ge 200 ] && [ $((tx1 - tx0)) -lt 260 ] || fail "veth sent $((tx1 - tx0)) packets for 200 link messages"

# 2. 10 % loss each way: 2000 small messages, bounds wide enough not to be flaky (binomial
#    sd 0.7 %).
link_loss 10
bg_ground RX "$PING" recv --lcm-url "$LINK_URL" --count 2000 --timeout 15 --idle 1.5 > "$WORK/loss.out" 2>&1
sleep 0.5
on_onboard "$PING" send --lcm-url "$LINK_URL" --count 2000 --rate 1000 > "$WORK/loss_send.out"
wait "$RX" || fail "receiver failed"
link_loss 0
loss=$(value "$WORK/loss.out" lost_pct)
echo "loss 10 %: lost $loss % of 2000, publish errors $(value "$WORK/loss_send.out" publish_errors)"
awk -v l="$loss" 'BEGIN { exit !(l >= 4 && l <= 18) }' || fail "lost $loss %, expected 4..18 %"
[ "$(value "$WORK/loss_send.out" publish_errors)" -eq 0 ] || fail "loss showed up as publish errors"

# 3. The relays as onboard runs them: local bus -> link for SLAM_KEYFRAME|SLAM_STATUS and
#    link -> local bus for SLAM_MAP|MAPPER_STATUS, 50 ms each, both at once. Each must see
#    exactly what was sent its way (no echo of the other's output, nothing unrelated).
bg_onboard UP "$TOOLS/lcm-link-relay" --from "$LOCAL_URL" --to "$LINK_URL" \
  --channels 'SLAM_KEYFRAME|SLAM_STATUS' --delay-ms 50 --timeout 30 --name up > "$WORK/up.out" 2> "$WORK/up.err"
bg_onboard DOWN "$TOOLS/lcm-link-relay" --from "$LINK_URL" --to "$LOCAL_URL" \
  --channels 'SLAM_MAP|MAPPER_STATUS' --delay-ms 50 --timeout 30 --name down > "$WORK/down.out" 2> "$WORK/down.err"
bg_ground RX "$PING" recv --channel SLAM_KEYFRAME --lcm-url "$LINK_URL" --count 200 --timeout 8 --idle 1.5 > "$WORK/up_rx.out"
bg_onboard RX2 "$PING" recv --channel SLAM_MAP --lcm-url "$LOCAL_URL" --count 100 --timeout 8 --idle 1.5 > "$WORK/down_rx.out"
sleep 0.5
bg_ground TX "$PING" send --channel SLAM_MAP --lcm-url "$LINK_URL" --count 100 --rate 100 > /dev/null
on_onboard "$PING" send --channel SLAM_KEYFRAME --lcm-url "$LOCAL_URL" --count 200 --rate 200 > /dev/null
# Not relayed: another channel on the local bus.
on_onboard "$PING" send --channel SLAM_POSE --lcm-url "$LOCAL_URL" --count 20 --rate 200 > /dev/null
wait "$TX" && wait "$RX" && wait "$RX2" || fail "a sender or receiver failed"
kill -INT "$UP" "$DOWN"
wait "$UP" && wait "$DOWN" || fail "a relay did not exit cleanly on SIGINT"
for dir in up down; do
  rx=$WORK/${dir}_rx.out
  echo "relay $dir: $(value "$rx" received) arrived, delay min $(value "$rx" delay_ms_min) median $(value "$rx" delay_ms_median) max $(value "$rx" delay_ms_max) ms; $(cat "$WORK/$dir.out")"
  awk -v d="$(value "$rx" delay_ms_min)" 'BEGIN { exit !(d >= 50) }' || fail "relay $dir: delay below 50 ms"
done
[ "$(value "$WORK/up_rx.out" received)" -eq 200 ] || fail "the up relay lost messages"
[ "$(value "$WORK/down_rx.out" received)" -eq 100 ] || fail "the down relay lost messages"
grep -q "received 200 forwarded 200 dropped_full 0 publish_errors 0" "$WORK/up.out" || fail "up relay counts: $(cat "$WORK/up.out")"
grep -q "received 100 forwarded 100 dropped_full 0 publish_errors 0" "$WORK/down.out" || fail "down relay counts: $(cat "$WORK/down.out")"

# 4. Outage, blackout (default): messages 0-99 sent during it are lost, 100-199 after it arrive.
bg_ground RX "$PING" recv --lcm-url "$LINK_URL" --count 200 --timeout 8 --idle 3 > "$WORK/out1.out" 2> "$WORK/out1.err"
sleep 0.5
link_down
on_onboard "$PING" send --lcm-url "$LINK_URL" --count 100 --rate 1000 > "$WORK/out1_send.out"
link_up_again
on_onboard "$PING" send --lcm-url "$LINK_URL" --start 100 --count 100 --rate 1000 > /dev/null
wait "$RX" || fail "receiver failed"
echo "blackout: $(value "$WORK/out1.out" received)/200 arrived, $(cat "$WORK/out1.err")"
[ "$(value "$WORK/out1.out" received)" -eq 100 ] && grep -q "missing 0-99$" "$WORK/out1.err" \
  || fail "blackout: expected exactly 0-99 missing, got $(cat "$WORK/out1.out" "$WORK/out1.err")"
[ "$(value "$WORK/out1_send.out" publish_errors)" -eq 0 ] || fail "the blackout showed up as publish errors"

# 5. Outage with the interfaces down (--admin): LCM cannot even open on the link meanwhile;
#    a subscriber that was running receives again afterwards.
bg_ground RX "$PING" recv --lcm-url "$LINK_URL" --count 100 --timeout 8 --idle 3 > "$WORK/out2.out"
sleep 0.5
link_down --admin
if on_onboard "$PING" send --lcm-url "$LINK_URL" --count 10 > /dev/null 2>&1; then
  fail "LCM opened on the link while it was down"
fi
link_up_again
on_onboard "$PING" send --lcm-url "$LINK_URL" --count 100 --rate 1000 > /dev/null
wait "$RX" || fail "receiver failed"
echo "admin down: publisher could not open LCM; afterwards $(value "$WORK/out2.out" received)/100 arrived"
[ "$(value "$WORK/out2.out" received)" -eq 100 ] || fail "after the admin outage only $(value "$WORK/out2.out" received)/100 arrived"
# 6. A bandwidth cap: 2000 messages of 1000 bytes in 2 s (8 Mbit/s) through 800 kbit/s; what
#    gets through is about 0.8 Mbit/s for ~2.7 s plus the bucket (measured 287).
link_cap 800
bg_ground RX "$PING" recv --lcm-url "$LINK_URL" --count 2000 --timeout 10 --idle 1.5 > "$WORK/cap.out" 2> /dev/null
sleep 0.5
on_onboard "$PING" send --lcm-url "$LINK_URL" --count 2000 --rate 1000 --size 1000 > /dev/null
wait "$RX" || fail "receiver failed"
link_cap 0
capped=$(value "$WORK/cap.out" received)
echo "cap 800 kbit/s: $capped/2000 messages of 1000 B arrived (offered 8 Mbit/s), median delay $(value "$WORK/cap.out" delay_ms_median) ms"
[ "$capped" -ge 100 ] && [ "$capped" -le 500 ] || fail "cap: $capped of 2000 arrived, expected 100..500"
echo "PASS"
