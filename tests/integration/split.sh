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
# SLAM_KEYFRAME|SLAM_STATUS to the link and SLAM_MAP|MAPPER_STATUS back, each after the delay.
SPLIT_MAP_ID=77  # fixed, so the tests can address the map

split_value() { awk -v k="$1" '$1 == k {print $2}' "$2"; }

split_start() {
  local dir=$1 delay=${2:-0}
  shift 2 || shift $#
  mkdir -p "$dir"
  bg_ground SPLIT_MAPPER "$PROCS/rgbd-mapper" --camera "$SRC/config/cameras/synthetic.yaml" \
      --state-dir "$dir/mapper-state" --lcm-url "$LINK_URL" "$@" > "$dir/mapper.out" 2> "$dir/mapper.err"
  bg_ground SPLIT_LINKLOG lcm-logger -q -f --lcm-url="$LINK_URL" "$dir/link.lcm"
  bg_onboard SPLIT_UP "$TOOLS/lcm-link-relay" --from "$LOCAL_URL" --to "$LINK_URL" \
      --channels 'SLAM_KEYFRAME|SLAM_STATUS' --delay-ms "$delay" --timeout 300 --name up 2> "$dir/relay-up.err"
  bg_onboard SPLIT_DOWN "$TOOLS/lcm-link-relay" --from "$LINK_URL" --to "$LOCAL_URL" \
      --channels 'SLAM_MAP|MAPPER_STATUS' --delay-ms "$delay" --timeout 300 --name down 2> "$dir/relay-down.err"
  bg_onboard SPLIT_LOGGER "$PROCS/pose-logger" --output "$dir/trajectory.txt" --lcm-url "$LOCAL_URL" 2> "$dir/logger.err"
  bg_onboard SPLIT_TRACKER "$PROCS/rgbd-tracker" --camera "$SRC/config/cameras/synthetic.yaml" \
      --map-id "$SPLIT_MAP_ID" --exit-after-idle 2 --ack-wait 20 --lcm-url "$LOCAL_URL" \
      > "$dir/tracker.out" 2> "$dir/tracker.err"
  sleep 1
}

split_capture() {
  on_onboard "$PROCS/rgbd-capture" --source "$2" --rate 30 --clock host --depth raw \
      --groundtruth-out "$1/groundtruth.txt" --lcm-url "$LOCAL_URL" 2> "$1/capture.err" \
    || fail "rgbd-capture failed: $(cat "$1/capture.err")"
}

split_finish() {
  local dir=$1 i
  for ((i = 0; i < 400; i++)); do  # the tracker's own bound is 2 s idle + 20 s for acks
    kill -0 "$SPLIT_TRACKER" 2>/dev/null || break
    sleep 0.1
  done
  kill -INT "$SPLIT_TRACKER" 2>/dev/null || true
  wait "$SPLIT_TRACKER" || true
  sleep 0.3
  kill -INT "$SPLIT_MAPPER" "$SPLIT_LINKLOG" "$SPLIT_UP" "$SPLIT_DOWN" "$SPLIT_LOGGER" 2>/dev/null || true
  wait "$SPLIT_MAPPER" "$SPLIT_LINKLOG" "$SPLIT_UP" "$SPLIT_DOWN" "$SPLIT_LOGGER" 2>/dev/null || true
  "$PROCS/slam-eval" "$dir/groundtruth.txt" "$dir/trajectory.txt" --frames 300 > "$dir/eval.txt" \
    || fail "slam-eval failed on $dir"
  "$TOOLS/lcm-log-stats" "$dir/link.lcm" --json "$dir/link.json" > "$dir/link.txt" || true
}

# split_report DIR NAME: one line of figures.
split_report() {
  local dir=$1 t=$1/tracker.out
  echo "$2: poses $(tail -n +2 "$dir/trajectory.csv" | wc -l)/300," \
       "keyframes $(split_value keyframes_acked "$t")/$(split_value keyframes "$t") acknowledged" \
       "($(split_value keyframe_sends "$t") sends)," \
       "map version $(split_value map_version "$t") of $(split_value map_version_newest_seen "$t") seen," \
       "ATE $(split_value ate_rmse_m "$dir/eval.txt") m," \
       "keyframe->map median $(split_value keyframe_in_map_ms_median "$t") ms max $(split_value keyframe_in_map_ms_max "$t") ms," \
       "latency median $(split_value latency_ms_median "$t") ms p99 $(split_value latency_ms_p99 "$t") ms," \
       "track median $(split_value track_ms_median "$t") ms"
  grep -v '^#' "$dir/link.txt" 2>/dev/null | sed "s/^/  link: /" || true
}
