# The onboard/ground split over the link of link.sh, for the suite's integration tests.
# Sourced after common.sh and link.sh (and after link_up). One run:
#   split_start DIR [DELAY_MS] [MAPPER_ARGS...]   ground: rgbd-mapper on the link, lcm-logger
#                                                 of the link; onboard: two lcm-link-relay
#                                                 (the link's delay each way), rgbd-tracker
#                                                 and pose-logger on the onboard bus
#   split_capture DIR SOURCE                      rgbd-capture onboard (foreground, 30 Hz)
#   split_finish DIR                              waits for the tracker (it finishes once the
#                                                 frames stop and every keyframe is
#                                                 acknowledged, or after 20 s), stops the rest,
#                                                 evaluates: DIR/eval.txt, DIR/link.json
# The tracker publishes keyframes and status on the onboard bus; the relays carry
# SLAM_KEYFRAME|SLAM_MAP_RECEIPT|SLAM_STATUS to the link and SLAM_MAP|MAPPER_STATUS back, each after the delay.
SPLIT_MAP_ID=77  # fixed, so the tests can address the map
SPLIT_TRACKER_ARGS=()  # more rgbd-tracker arguments for the next split_start
# The relays' own time bound [s]. 300 s covers every test; a longer run must raise it (a
# relay that stops cuts the link: bench-suite's ten-minute flight lost it at 300 s until
# 2026-11-26, and the mapper then heard nothing of the last five minutes).
SPLIT_RELAY_TIMEOUT_S=${SPLIT_RELAY_TIMEOUT_S:-300}

split_value() { awk -v k="$1" '$1 == k {print $2}' "$2"; }

split_start() {
  local dir=$1 delay=${2:-0}
  shift 2 || shift $#
  mkdir -p "$dir"
  bg_ground SPLIT_MAPPER "$PROCS/rgbd-mapper" --camera "$SRC/config/cameras/synthetic.yaml" \
      --state-dir "$dir/mapper-state" --lcm-url "$LINK_URL" "$@" > "$dir/mapper.out" 2> "$dir/mapper.err"
  bg_ground SPLIT_LINKLOG lcm-logger -q -f --lcm-url="$LINK_URL" "$dir/link.lcm"
  bg_onboard SPLIT_UP "$TOOLS/lcm-link-relay" --from "$LOCAL_URL" --to "$LINK_URL" \
      --channels 'SLAM_KEYFRAME|SLAM_MAP_RECEIPT|SLAM_STATUS' --delay-ms "$delay" --timeout "$SPLIT_RELAY_TIMEOUT_S" --name up 2> "$dir/relay-up.err"
  bg_onboard SPLIT_DOWN "$TOOLS/lcm-link-relay" --from "$LINK_URL" --to "$LOCAL_URL" \
      --channels 'SLAM_MAP|MAPPER_STATUS' --delay-ms "$delay" --timeout "$SPLIT_RELAY_TIMEOUT_S" --name down 2> "$dir/relay-down.err"
  bg_onboard SPLIT_LOGGER "$PROCS/pose-logger" --output "$dir/trajectory.txt" --map-output "$dir/map_trajectory.txt" \
      --lcm-url "$LOCAL_URL" 2> "$dir/logger.err"
  bg_onboard SPLIT_TRACKER "$PROCS/rgbd-tracker" --camera "$SRC/config/cameras/synthetic.yaml" \
      --map-id "$SPLIT_MAP_ID" --set tracker_node.exit_after_idle_s=2,tracker_node.ack_wait_s=20 --lcm-url "$LOCAL_URL" \
      ${SPLIT_TRACKER_ARGS[@]+"${SPLIT_TRACKER_ARGS[@]}"} > "$dir/tracker.out" 2> "$dir/tracker.err"
  sleep 1
}

split_capture() {
  on_onboard "$PROCS/rgbd-capture" --source "$2" --rate 30 --clock host --depth raw \
      --groundtruth-out "$1/groundtruth.txt" --lcm-url "$LOCAL_URL" 2> "$1/capture.err" \
    || fail "rgbd-capture failed: $(cat "$1/capture.err")"
}

# _split_link_cut: prints why the link was cut if a relay stopped before the run's end (its
# --timeout passed, or it failed), nothing otherwise. The finish functions stop every
# process first, then fail: such a run measured something else.
_split_link_cut() {
  kill -0 "$SPLIT_UP" 2>/dev/null && kill -0 "$SPLIT_DOWN" 2>/dev/null && return 0
  echo "a link relay stopped before the run ended (SPLIT_RELAY_TIMEOUT_S=$SPLIT_RELAY_TIMEOUT_S s)"
}

split_finish() { split_finish_frames "$1" 300; }

# split_report DIR NAME [FRAMES]: one line of figures (FRAMES published, default 300).
split_report() {
  local dir=$1 t=$1/tracker.out
  echo "$2: poses $(tail -n +2 "$dir/trajectory.csv" | wc -l)/${3:-300}," \
       "keyframes $(split_value keyframes_acked "$t")/$(split_value keyframes "$t") acknowledged" \
       "($(split_value keyframe_sends "$t") sends)," \
       "map version $(split_value map_version "$t") of $(split_value map_version_newest_seen "$t") seen," \
       "ATE $(split_value ate_rmse_m "$dir/eval.txt") m," \
       "keyframe->map median $(split_value keyframe_in_map_ms_median "$t") ms max $(split_value keyframe_in_map_ms_max "$t") ms," \
       "latency median $(split_value latency_ms_median "$t") ms p99 $(split_value latency_ms_p99 "$t") ms," \
       "track median $(split_value track_ms_median "$t") ms"
  grep -v '^#' "$dir/link.txt" 2>/dev/null | sed "s/^/  link: /" || true
}

# --- Additions for the outage / mapper-restart tests (the functions above are unchanged) ---

# split_finish_frames DIR FRAMES: split_finish for a run of FRAMES frames (slam-eval's
# coverage counts against FRAMES; split_finish assumes 300). Also writes DIR/tracker.exit
# (the tracker's exit status) and DIR/tracker_exit_utime (when it was seen gone, host clock).
split_finish_frames() {
  local dir=$1 frames=$2 i status=0 cut
  for ((i = 0; i < 400; i++)); do  # the tracker's own bound is 2 s idle + 20 s for acks
    kill -0 "$SPLIT_TRACKER" 2>/dev/null || break
    sleep 0.05
  done
  date +%s%6N > "$dir/tracker_exit_utime"
  cut=$(_split_link_cut)
  kill -INT "$SPLIT_TRACKER" 2>/dev/null || true
  wait "$SPLIT_TRACKER" || status=$?
  echo "$status" > "$dir/tracker.exit"
  sleep 0.3
  kill -INT "$SPLIT_MAPPER" "$SPLIT_LINKLOG" "$SPLIT_UP" "$SPLIT_DOWN" "$SPLIT_LOGGER" 2>/dev/null || true
  wait "$SPLIT_MAPPER" "$SPLIT_LINKLOG" "$SPLIT_UP" "$SPLIT_DOWN" "$SPLIT_LOGGER" 2>/dev/null || true
  [ -z "$cut" ] || fail "$cut"
  "$PROCS/slam-eval" "$dir/groundtruth.txt" "$dir/trajectory.txt" --frames "$frames" > "$dir/eval.txt" \
    || fail "slam-eval failed on $dir"
  "$PROCS/slam-eval" "$dir/groundtruth.txt" "$dir/map_trajectory.txt" --frames "$frames" > "$dir/eval_map.txt" \
    || fail "slam-eval failed on $dir/map_trajectory.txt"
  "$TOOLS/lcm-log-stats" "$dir/link.lcm" --json "$dir/link.json" > "$dir/link.txt" || true
}

# split_kill_mapper: SIGKILL to the mapper of split_start (nothing flushed, no summary).
split_kill_mapper() {
  kill -KILL "$SPLIT_MAPPER" 2>/dev/null || fail "the mapper (pid $SPLIT_MAPPER) was not running"
  wait "$SPLIT_MAPPER" 2>/dev/null || true
}

# split_restart_mapper DIR [MAPPER_ARGS...]: starts the mapper again as split_start does (same
# --state-dir, so it resumes from its journal); its output is appended to DIR/mapper.{out,err}.
# SPLIT_MAPPER becomes the new pid, so split_finish stops this one.
split_restart_mapper() {
  local dir=$1
  shift
  bg_ground SPLIT_MAPPER "$PROCS/rgbd-mapper" --camera "$SRC/config/cameras/synthetic.yaml" \
      --state-dir "$dir/mapper-state" --lcm-url "$LINK_URL" "$@" >> "$dir/mapper.out" 2>> "$dir/mapper.err"
}

# split_mapper_summary DIR: the mapper's last summary line (printed at SIGINT) as key-value
# lines: mapper_map, mapper_version, mapper_keyframes (in the map), mapper_culled (keyframes
# culled as redundant since the mapper started, its journal's included), mapper_restored, mapper_points,
# mapper_received, mapper_duplicates, mapper_out_of_order, mapper_foreign, mapper_bad_messages,
# mapper_bad_keyframes, mapper_maps_published, mapper_snapshots.
split_mapper_summary() {
  grep '^rgbd-mapper: map ' "$1/mapper.err" | tail -1 | sed -E \
    's/^rgbd-mapper: map ([0-9]+) version ([0-9]+): ([0-9]+) keyframes \(([0-9]+) restored, [0-9]+ culled\), ([0-9]+) points; received ([0-9]+), duplicates ([0-9]+), out of order ([0-9]+), foreign map ([0-9]+), bad messages ([0-9]+), bad keyframes ([0-9]+); ([0-9]+) maps published \(([0-9]+) snapshots.*/mapper_map \1\nmapper_version \2\nmapper_keyframes \3\nmapper_restored \4\nmapper_points \5\nmapper_received \6\nmapper_duplicates \7\nmapper_out_of_order \8\nmapper_foreign \9/;t more;d;:more' \
    || true
  # sed has nine back-references at most: the rest from a second pass.
  grep '^rgbd-mapper: map ' "$1/mapper.err" | tail -1 | sed -E \
    's/.* keyframes \([0-9]+ restored, ([0-9]+) culled\).*, bad messages ([0-9]+), bad keyframes ([0-9]+); ([0-9]+) maps published \(([0-9]+) snapshots.*/mapper_culled \1\nmapper_bad_messages \2\nmapper_bad_keyframes \3\nmapper_maps_published \4\nmapper_snapshots \5/;t;d' \
    || true
}

# require_lcm_log: sets LCMLOG, the command reading lcm-logger files (tests/integration/lcm_log.py).
require_lcm_log() {
  command -v python3 > /dev/null || fail "python3 is missing (scripts/setup installs it; tests/integration/lcm_log.py needs it)"
  LCMLOG="python3 $(dirname "${BASH_SOURCE[0]}")/lcm_log.py"
}
