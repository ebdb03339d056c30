#!/usr/bin/env bash
# Issue 4: a run recorded with lcm-logger and replayed with lcm-logplayer gives the same
# trajectory within a stated tolerance. scripts/run-local --record runs the suite on the
# synthetic room (300 frames, 30 Hz, frames stamped with the host clock at capture and the
# ground truth with the same stamps) and records every channel; scripts/replay plays the
# recorded RGBD_FRAME messages (lcm-logplayer, real time) through a fresh tracker, mapper and
# pose-logger. The replayed frames keep their recorded stamps, so the two trajectories share
# timestamps. Asserts:
#   - the recording holds every frame (300 RGBD_FRAME messages) and the original run is sound
#     (poses for >= 90 % of the frames: recording 1.5 MB frames costs the loaded machine a few
#     skipped frames, 285/300 measured; every keyframe acknowledged);
#   - the replay tracks >= 95 % of the frames and acknowledges every keyframe;
#   - replay against the original trajectory (slam-eval with the original as ground truth):
#     every frame posed in both runs matched by its timestamp, ATE <= REPLAY_TOL_M (3 mm;
#     measured here: 0.44, 0.55, 1.21 mm RMSE, at most 3.8 mm for one pose: tracking is not
#     bit-for-bit repeatable, since which map version a frame is tracked against, and which
#     frames a busy tracker skips, depend on timing);
#   - replay against the ground truth: ATE <= 1.5x the original run's and <= 5 mm.
source "$(dirname "$0")/common.sh"
require_netns
REPLAY_TOL_M=0.003
frames=300
seq=synth:room,frames=$frames
t_test=$SECONDS

RGBDSLAM_BUILD_DIR=$BUILD "$SRC/scripts/run-local" --source "$seq" --rate 30 --record --out "$WORK/run" \
    > "$WORK/run.out" 2>&1 || fail "run-local failed: $(cat "$WORK/run.out")"
t_run=$((SECONDS - t_test))
[ -s "$WORK/run/run.lcm" ] || fail "run-local --record wrote no log"
RGBDSLAM_BUILD_DIR=$BUILD "$SRC/scripts/replay" "$WORK/run/run.lcm" --out "$WORK/replay" \
    --groundtruth "$WORK/run/groundtruth.txt" > "$WORK/replay.out" 2>&1 \
  || fail "replay failed: $(cat "$WORK/replay.out")"
t_replay=$((SECONDS - t_test - t_run))
"$TOOLS/lcm-log-stats" "$WORK/run/run.lcm" > "$WORK/run/log.txt" || fail "lcm-log-stats failed on the recording"
"$PROCS/slam-eval" "$WORK/run/trajectory.txt" "$WORK/replay/trajectory.txt" --frames "$frames" > "$WORK/replay-vs-run.txt" \
  || fail "slam-eval of the replay against the run failed"

value() { awk -v k="$1" '$1 == k {print $2}' "$2"; }
recorded_frames=$(awk '$1 == "RGBD_FRAME" {print $2}' "$WORK/run/log.txt")
log_mb=$(( $(stat -c %s "$WORK/run/run.lcm") / 1000000 ))
run_poses=$(tail -n +2 "$WORK/run/trajectory.csv" | wc -l)
replay_poses=$(tail -n +2 "$WORK/replay/trajectory.csv" | wc -l)
run_ate=$(value ate_rmse_m "$WORK/run/eval.txt")
replay_ate=$(value ate_rmse_m "$WORK/replay/eval.txt")
diff_ate=$(value ate_rmse_m "$WORK/replay-vs-run.txt")
diff_max=$(value ate_max_m "$WORK/replay-vs-run.txt")
matched=$(value num_associated "$WORK/replay-vs-run.txt")
run_traj=$(grep -vc '^#' "$WORK/run/trajectory.txt")
replay_traj=$(grep -vc '^#' "$WORK/replay/trajectory.txt")
echo "recording: $recorded_frames RGBD_FRAME messages, $log_mb MB"
echo "run:    poses $run_poses/$frames, keyframes $(value keyframes_acked "$WORK/run/rgbd-tracker.out")/$(value keyframes "$WORK/run/rgbd-tracker.out") acknowledged, ATE $run_ate m ($t_run s)"
echo "replay: poses $replay_poses/$frames, keyframes $(value keyframes_acked "$WORK/replay/rgbd-tracker.out")/$(value keyframes "$WORK/replay/rgbd-tracker.out") acknowledged, ATE $replay_ate m ($t_replay s)"
echo "replay against the run: $matched of the run's $run_traj poses matched (replay $replay_traj), ATE $diff_ate m (max $diff_max m), tolerance $REPLAY_TOL_M m"
echo "test time $((SECONDS - t_test)) s"

[ "$recorded_frames" = "$frames" ] || fail "the recording holds $recorded_frames of $frames frames"
[ "$run_poses" -ge $((frames * 90 / 100)) ] || fail "run: poses for $run_poses of $frames frames"
[ "$(value keyframes_unacked "$WORK/run/rgbd-tracker.out")" = 0 ] || fail "run: keyframes left unacknowledged"
[ "$replay_poses" -ge $((frames * 95 / 100)) ] || fail "replay: poses for $replay_poses of $frames frames"
[ "$(value keyframes_unacked "$WORK/replay/rgbd-tracker.out")" = 0 ] || fail "replay: keyframes left unacknowledged"
# Each side skips a few frames (a busy tracker drops the oldest of its backlog), not the same
# ones; every frame posed in both must be matched by its timestamp.
[ "$matched" -ge $((run_traj + replay_traj - frames)) ] \
  || fail "only $matched of the run's $run_traj poses have a replayed pose at the same time ($replay_traj replayed)"
awk -v a="$diff_ate" -v t="$REPLAY_TOL_M" 'BEGIN { exit !(a <= t) }' \
  || fail "the replay's trajectory is $diff_ate m (ATE) from the run's, above the tolerance $REPLAY_TOL_M m"
awk -v a="$replay_ate" -v b="$run_ate" 'BEGIN { exit !(a <= 1.5 * b && a <= 0.005) }' \
  || fail "the replay's ATE $replay_ate m is above 1.5x the run's $run_ate m or above 5 mm"
echo "PASS"
