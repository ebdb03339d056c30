# A radio link between two private network namespaces, for tests of the onboard/ground split
# (issue 4). Sourced by integration tests after common.sh:
#
#   source "$(dirname "$0")/common.sh"; source "$(dirname "$0")/link.sh"
#   require_netns; link_up
#   bg_ground  RX  "$TOOLS/lcm-ping" recv --lcm-url "$LINK_URL" ...   # RX := its pid
#   on_onboard "$TOOLS/lcm-ping" send --lcm-url "$LINK_URL" ...
#   link_loss 10; link_down; link_up_again; link_cap 800    # impair the link
#   (link_teardown runs on EXIT)
#
# Layout: namespaces "onboard" and "ground", each with lo up and a veth end (ob0
# 10.213.76.1/30, gd0 10.213.76.2/30) joined to the other. Two LCM buses per namespace:
#   LOCAL_URL  239.255.76.67:7667 ttl=0, route on lo: stays inside the namespace;
#   LINK_URL   239.255.76.68:7668 ttl=1, route via the veth: crosses to the other side.
# LCM's udpm provider binds its port on INADDR_ANY and joins the group with INADDR_ANY as the
# interface, so the kernel picks the interface from the route of the group: the /32 routes
# below put the local group on lo and the link group on the veth. The two buses use
# different ports, so a socket of one never receives the other's datagrams.
# Nothing is routed anywhere else: a third group has no route and fails to send.
#
# Why unshare-held namespaces and not `ip netns add`: `ip netns` works here (it creates and
# bind-mounts /run/netns), but its names are global and outlive a test killed by SIGKILL
# (ctest's timeout), leaving namespaces for someone to delete by hand. Here each namespace
# is held by one process (`unshare -n sleep`), is entered with `nsenter -t PID -n`, and
# disappears with its last process, veth pair included; nothing is written outside the test.
# The holder's sleep (LINK_HOLD_S, longer than ctest's 600 s timeout) bounds how long a
# killed test's namespace can survive, together with the --timeout of whatever the test
# left running inside (give every background tool one).
# The veth pair is created inside onboard with its peer moved straight into ground, so it
# never appears in the host's namespace. Every entry checks that the PID still holds the
# namespace this test created (and not the host's), so a reused PID cannot redirect a
# command to the host.
#
# Impairments (each direction gets it; see each function for how):
#   link_loss P            P % random drops of the link's datagrams (nftables numgen)
#   link_cap KBIT          tc tbf on each veth end's egress
#   link_down [--admin]    an outage (default a silent blackout; --admin: ip link set down)
#   link_up_again          ends the outage
# Delay is not a kernel feature here (no netem): tests run tests/tools/lcm-link-relay.

LINK_LOCAL_GROUP=239.255.76.67
LINK_GROUP=239.255.76.68
LINK_PORT=7668
LOCAL_URL="udpm://$LINK_LOCAL_GROUP:7667?ttl=0&recv_buf_size=4194304"
LINK_URL="udpm://$LINK_GROUP:$LINK_PORT?ttl=1&recv_buf_size=4194304"
LINK_ONBOARD_IF=ob0
LINK_GROUND_IF=gd0
LINK_ONBOARD_ADDR=10.213.76.1/30
LINK_GROUND_ADDR=10.213.76.2/30
LINK_HOLD_S=${LINK_HOLD_S:-900}  # longest life of a namespace whose test was killed [s]
LINK_ONBOARD_PID="" LINK_GROUND_PID="" LINK_ONBOARD_NS="" LINK_GROUND_NS=""
LINK_HOST_NS=$(readlink /proc/$$/ns/net)
LINK_NFT_TABLE=rgbdslam_link
LINK_LOSS_PCT=0 LINK_BLACKOUT=0 LINK_ADMIN_DOWN=0  # current impairments

trap 'link_teardown; rm -rf "$WORK"' EXIT  # replaces common.sh's trap, doing both
trap 'exit 130' INT TERM                    # so that the EXIT trap runs

# _link_enter SIDE: checks that SIDE's holder still holds our namespace; prints its pid.
_link_enter() {
  local pid ns
  case $1 in
    onboard) pid=$LINK_ONBOARD_PID ns=$LINK_ONBOARD_NS ;;
    ground) pid=$LINK_GROUND_PID ns=$LINK_GROUND_NS ;;
    *) fail "link.sh: no namespace '$1'" ;;
  esac
  [ -n "$pid" ] || fail "link.sh: $1 namespace not up (call link_up first)"
  [ "$(readlink "/proc/$pid/ns/net" 2>/dev/null)" = "$ns" ] && [ "$ns" != "$LINK_HOST_NS" ] \
    || fail "link.sh: the $1 namespace is gone (holder $pid)"
  echo "$pid"
}

# on_onboard / on_ground CMD [ARGS...]: runs CMD inside that namespace and returns its status.
# `on_onboard CMD &` works, but $! is then a wrapper shell; use bg_* to get CMD's own pid.
on_onboard() { local pid; pid=$(_link_enter onboard) || exit 1; nsenter -t "$pid" -n -- "$@"; }
on_ground() { local pid; pid=$(_link_enter ground) || exit 1; nsenter -t "$pid" -n -- "$@"; }

# bg_onboard / bg_ground VAR CMD [ARGS...]: starts CMD in the background inside that
# namespace and stores its pid in VAR (nsenter execs CMD, so it is CMD's pid to signal).
bg_onboard() { _link_bg onboard "$@"; }
bg_ground() { _link_bg ground "$@"; }
_link_bg() {
  local _link_side=$1 _link_var=$2 _link_pid
  shift 2
  _link_pid=$(_link_enter "$_link_side") || exit 1
  nsenter -t "$_link_pid" -n -- "$@" &
  printf -v "$_link_var" '%s' "$!"
}

# _link_hold VAR_PID VAR_NS: starts a process holding a new network namespace.
_link_hold() {
  local pid ns="" i
  unshare -n sleep "$LINK_HOLD_S" &
  pid=$!
  for ((i = 0; i < 100; i++)); do  # at most 2 s for unshare to switch namespaces
    ns=$(readlink "/proc/$pid/ns/net" 2>/dev/null) || fail "link.sh: namespace holder died"
    [ "$ns" != "$LINK_HOST_NS" ] && break
    sleep 0.02
  done
  [ "$ns" != "$LINK_HOST_NS" ] || fail "link.sh: holder $pid never left the host namespace"
  printf -v "$1" '%s' "$pid"
  printf -v "$2" '%s' "$ns"
}

# _link_routes: the link group's route in each namespace (lost whenever the veth goes down).
_link_routes() {
  on_onboard ip route replace "$LINK_GROUP/32" dev "$LINK_ONBOARD_IF"
  on_ground ip route replace "$LINK_GROUP/32" dev "$LINK_GROUND_IF"
}

# _link_wait_carrier: waits (bounded, 5 s) until both veth ends are up with carrier.
_link_wait_carrier() {
  local i
  for ((i = 0; i < 100; i++)); do
    if on_onboard ip -o link show "$LINK_ONBOARD_IF" | grep -q "state UP" &&
       on_ground ip -o link show "$LINK_GROUND_IF" | grep -q "state UP"; then
      return 0
    fi
    sleep 0.05
  done
  fail "link.sh: the veth did not come up within 5 s"
}

# link_up: creates both namespaces and the link between them.
link_up() {
  command -v nsenter > /dev/null || skip "nsenter (util-linux) is missing"
  _link_hold LINK_ONBOARD_PID LINK_ONBOARD_NS
  _link_hold LINK_GROUND_PID LINK_GROUND_NS
  on_onboard ip link add "$LINK_ONBOARD_IF" type veth peer name "$LINK_GROUND_IF" netns "$LINK_GROUND_PID" \
    || fail "link.sh: cannot create the veth pair"
  on_onboard ip link set lo up
  on_ground ip link set lo up
  on_onboard ip route add "$LINK_LOCAL_GROUP/32" dev lo
  on_ground ip route add "$LINK_LOCAL_GROUP/32" dev lo
  on_onboard ip addr add "$LINK_ONBOARD_ADDR" dev "$LINK_ONBOARD_IF"
  on_ground ip addr add "$LINK_GROUND_ADDR" dev "$LINK_GROUND_IF"
  on_onboard ip link set "$LINK_ONBOARD_IF" up
  on_ground ip link set "$LINK_GROUND_IF" up
  _link_wait_carrier
  _link_routes
}

# _link_nft: writes the impairment table of both namespaces from LINK_LOSS_PCT and
# LINK_BLACKOUT. Rules sit on the input hook of the receiving side (iifname = its veth end),
# so each direction is impaired once and the sender never notices: a drop on the output hook
# makes sendmsg fail with EPERM, and LCM's publish then returns -1, which a radio never does.
_link_nft() {
  local side ifname
  for side in onboard ground; do
    ifname=$LINK_ONBOARD_IF
    [ $side = ground ] && ifname=$LINK_GROUND_IF
    "on_$side" nft delete table inet "$LINK_NFT_TABLE" 2>/dev/null || true
    [ "$LINK_LOSS_PCT" -eq 0 ] && [ "$LINK_BLACKOUT" -eq 0 ] && continue
    {
      echo "table inet $LINK_NFT_TABLE {"
      echo "  chain input {"
      echo "    type filter hook input priority 0; policy accept;"
      [ "$LINK_BLACKOUT" -eq 1 ] && echo "    iifname \"$ifname\" counter drop"
      [ "$LINK_LOSS_PCT" -gt 0 ] &&
        echo "    iifname \"$ifname\" udp dport $LINK_PORT numgen random mod 100 < $LINK_LOSS_PCT counter drop"
      echo "  }"
      echo "}"
    } | "on_$side" nft -f - || fail "link.sh: nft refused the impairment rules"
  done
  # Measured here: datagrams sent within ~15 ms after deleting the table were still dropped;
  # settle, so that a change is in force when the function returns.
  sleep 0.25
}

# link_loss PERCENT: drops PERCENT % (integer 0..100) of the link's datagrams each way
# (random, independent per datagram: a fragmented message is lost if any fragment is).
# link_loss 0 removes it.
link_loss() {
  [[ "$1" =~ ^[0-9]+$ ]] && [ "$1" -le 100 ] || fail "link_loss: '$1' is not 0..100"
  LINK_LOSS_PCT=$1
  _link_nft
}

# link_cap KBIT: caps each direction at KBIT kbit/s with a token bucket; 0 removes the cap.
link_cap() {
  local kbit=$1
  [[ "$kbit" =~ ^[0-9]+$ ]] || fail "link_cap: '$kbit' is not a whole number of kbit/s"
  on_onboard tc qdisc del dev "$LINK_ONBOARD_IF" root 2>/dev/null || true
  on_ground tc qdisc del dev "$LINK_GROUND_IF" root 2>/dev/null || true
  [ "$kbit" -eq 0 ] && return 0
  # burst: 32 kB; latency 400 ms: tbf queues up to rate * latency + burst bytes, so a packet
  # waits at most latency + burst / rate (720 ms at 800 kbit/s) and is dropped beyond that.
  on_onboard tc qdisc add dev "$LINK_ONBOARD_IF" root tbf rate "${kbit}kbit" burst 32kb latency 400ms
  on_ground tc qdisc add dev "$LINK_GROUND_IF" root tbf rate "${kbit}kbit" burst 32kb latency 400ms
}

# link_down [--admin] / link_up_again: an outage of the link, and its end.
# Default: a blackout, like a radio out of range: the interfaces stay up, everything arriving
# over the veth is dropped (nftables), publishers see no error, subscribers stay joined, and
# a process (re)started during the outage can open LCM.
# --admin: `ip link set down` on both ends. The kernel then deletes the routes through the
# veth: publish() on LINK_URL fails (ENETUNREACH) and a process starting during the outage
# cannot open LCM on LINK_URL at all ("No route", lcm_create fails). link_up_again brings
# the ends up and restores the routes; running subscribers keep their group membership.
link_down() {
  if [ "${1:-}" = --admin ]; then
    LINK_ADMIN_DOWN=1
    on_onboard ip link set "$LINK_ONBOARD_IF" down
    on_ground ip link set "$LINK_GROUND_IF" down
  else
    LINK_BLACKOUT=1
    _link_nft
  fi
}
link_up_again() {
  if [ "$LINK_ADMIN_DOWN" -eq 1 ]; then
    on_onboard ip link set "$LINK_ONBOARD_IF" up
    on_ground ip link set "$LINK_GROUND_IF" up
    _link_wait_carrier
    _link_routes
    LINK_ADMIN_DOWN=0
  fi
  LINK_BLACKOUT=0
  _link_nft
}

# link_packets SIDE rx|tx: packets the veth end of SIDE has received / sent so far.
link_packets() {
  local ifname=$LINK_ONBOARD_IF field=3
  [ "$1" = ground ] && ifname=$LINK_GROUND_IF
  [ "$2" = tx ] && field=11
  "on_$1" cat /proc/net/dev | awk -v dev="$ifname:" -v f="$field" '$1 == dev { print $f }'
}

# link_teardown: ends every process left in the two namespaces (TERM, then KILL after 2 s),
# then their holders; the namespaces and the veth pair go with them. Safe to call twice, and
# never stops half-way (it runs from the EXIT trap, under set -e).
link_teardown() {
  local side pid ns p i left
  local -a pids=()
  for side in onboard ground; do
    if [ $side = onboard ]; then pid=$LINK_ONBOARD_PID ns=$LINK_ONBOARD_NS
    else pid=$LINK_GROUND_PID ns=$LINK_GROUND_NS; fi
    if [ -z "$pid" ] || [ -z "$ns" ] || [ "$ns" = "$LINK_HOST_NS" ]; then continue; fi
    for p in /proc/[0-9]*; do
      p=${p#/proc/}
      if [ "$p" != "$pid" ] && [ "$(readlink "/proc/$p/ns/net" 2>/dev/null)" = "$ns" ]; then
        pids+=("$p")
      fi
    done
  done
  if [ ${#pids[@]} -gt 0 ]; then
    kill -TERM "${pids[@]}" 2>/dev/null || true
    for ((i = 0; i < 40; i++)); do
      left=0
      for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && left=1 || true; done
      [ $left -eq 0 ] && break
      sleep 0.05
    done
    kill -KILL "${pids[@]}" 2>/dev/null || true
  fi
  for side in "$LINK_ONBOARD_PID $LINK_ONBOARD_NS" "$LINK_GROUND_PID $LINK_GROUND_NS"; do
    read -r pid ns <<< "$side"
    if [ -n "$ns" ] && [ "$ns" != "$LINK_HOST_NS" ] && [ "$(readlink "/proc/$pid/ns/net" 2>/dev/null)" = "$ns" ]; then
      kill -KILL "$pid" 2>/dev/null || true
      wait "$pid" 2>/dev/null || true
    fi
  done
  LINK_ONBOARD_PID="" LINK_GROUND_PID="" LINK_ONBOARD_NS="" LINK_GROUND_NS=""
  return 0
}
