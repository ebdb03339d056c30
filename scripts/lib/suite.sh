# Shared by scripts/run-local, run-onboard, replay: starting and stopping the suite's
# processes, and the evaluation at the end. Sourced, not run.
DEFAULT_LCM_URL="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
BUILD=${RGBDSLAM_BUILD_DIR:-build}
PROCS=$BUILD/procs
PIDS=()

die() { echo "$(basename "$0"): error: $*" >&2; exit 2; }

# Re-runs the calling script inside a private network namespace (only lo, multicast routed
# on lo) when this machine allows one, so nothing reaches the host's interfaces.
enter_netns() {
  [ -n "${RGBDSLAM_IN_NETNS:-}" ] && return 0
  [ "${RGBDSLAM_NO_NETNS:-}" = 1 ] && return 0
  if unshare -n true 2>/dev/null; then
    echo "$(basename "$0"): running in a private network namespace" >&2
    RGBDSLAM_IN_NETNS=1 exec scripts/netns-run "$0" "$@"
  fi
  echo "$(basename "$0"): no private network namespace here; LCM stays on this host (ttl=0)" >&2
}

# start NAME COMMAND...: runs COMMAND in the background, output to $OUT/NAME.{out,err}.
start() {
  local name=$1
  shift
  "$@" > "$OUT/$name.out" 2> "$OUT/$name.err" &
  PIDS+=($!)
  eval "PID_${name//-/_}=$!"
}

# sample_memory PERIOD_S FILE NAME...: in the background, every PERIOD_S seconds (an
# integer), appends "t_s NAME_rss_mb..." to FILE: the resident memory (VmRSS) of each
# process started as NAME, "-" once it has ended. Ends when none of them is alive (checked
# each second), or after 24 h.
sample_memory() {
  local period=$1 file=$2
  shift 2
  local names=("$@") pids=() name
  for name in "${names[@]}"; do pids+=("$(eval echo "\${PID_${name//-/_}}")"); done
  echo "t_s ${names[*]/%/_rss_mb}" > "$file"
  (
    local i pid rss line alive
    for ((i = 0; i < 86400; i++)); do
      if ((i % period == 0)); then
        line=$i
        for pid in "${pids[@]}"; do
          rss=$(awk '/^VmRSS:/ { printf "%.1f", $2 / 1024 }' "/proc/$pid/status" 2> /dev/null || true)
          line+=" ${rss:--}"
        done
        echo "$line" >> "$file"
      fi
      alive=0
      for pid in "${pids[@]}"; do kill -0 "$pid" 2> /dev/null && alive=1; done
      [ $alive = 1 ] || break
      sleep 1
    done
  ) &
}

# Stops every process started with start() (SIGINT, then SIGKILL after 10 s).
stop_all() {
  local pid i
  for pid in "${PIDS[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
  for ((i = 0; i < 100; i++)); do
    local alive=0
    for pid in "${PIDS[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
    [ $alive = 0 ] && break
    sleep 0.1
  done
  for pid in "${PIDS[@]}"; do kill -KILL "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  PIDS=()
}

# evaluate GT TRAJ FRAMES: ATE with slam-eval, the plot beside the trajectory.
evaluate() {
  local gt=$1 traj=$2 frames=$3
  "$PROCS/slam-eval" "$gt" "$traj" --frames "$frames" --plot "$OUT/trajectory.png" \
      --json-out "$OUT/eval.json" > "$OUT/eval.txt"
  grep -E "^(ate_rmse_m|coverage|rpe_per_s_trans_rmse_m) " "$OUT/eval.txt"
  echo "plot: $OUT/trajectory.png"
}
