#!/usr/bin/env bash
# rgbd-slam end to end on the synthetic corridor (the paper's Table I scene, shortened to
# 450 frames = 15 m with the hall in the middle): weakly textured walls, depth only to
# 4.5 m, strong corners where there is no depth. Both depth modes must pose every frame;
# depth-ba must end within 0.5 % of the distance travelled (the issue's Table I target)
# and drift less than depth-init (Table I's order). Mono (depth of the first frame only)
# must pose at least 95 % of the frames; its drift is not ordered against depth-init here
# (measured lower on this synthetic corridor, docs/open_work.md). The final position error is computed here from synth-write's
# ground truth as lib/eval endPointError does: both trajectories relative to their first
# pose, |t_est_rel - t_gt_rel| over the ground-truth distance.
# Measured 2026-11-22 (Release, 61 s for the whole test): depth-ba 450/450, ATE 5.7 mm,
# final 0.065 %; depth-init 450/450, ATE 67 mm, final 1.51 %; mono (measured 2026-11-22,
# 50 s) 450/450, ATE 51 mm, final 1.11 %. The bounds leave a margin for
# other machines (floating point, not timing, is the only difference).
source "$(dirname "$0")/common.sh"
SPEC=corridor,frames=450
FRAMES=450
declare -A ATE_BOUND_M=([depth-ba]=0.02 [depth-init]=0.2 [mono]=0.25)
declare -A FINAL_BOUND_PERCENT=([depth-ba]=0.5 [depth-init]=5 [mono]=5)
declare -A MIN_POSES=([depth-ba]=$FRAMES [depth-init]=$FRAMES [mono]=$((FRAMES * 95 / 100)))
declare -A FINAL

"$PROCS/synth-write" "$SPEC" "$WORK/gt" > /dev/null 2> "$WORK/synth.err" \
  || fail "synth-write failed: $(tail -5 "$WORK/synth.err")"
[ -s "$WORK/gt/groundtruth.txt" ] || fail "synth-write wrote no ground truth"

# Final position error [%] of TRAJ against the ground truth (TUM files; poses associated by
# timestamp within 0.02 s; first and last associated estimate poses).
final_error_percent() {
  awk -v est="$1" '
    function rotinv(qx, qy, qz, qw, vx, vy, vz,   tx, ty, tz) {  # R(q)^T v
      qx = -qx; qy = -qy; qz = -qz
      tx = 2 * (qy * vz - qz * vy); ty = 2 * (qz * vx - qx * vz); tz = 2 * (qx * vy - qy * vx)
      rx = vx + qw * tx + (qy * tz - qz * ty)
      ry = vy + qw * ty + (qz * tx - qx * tz)
      rz = vz + qw * tz + (qx * ty - qy * tx)
    }
    FNR == 1 { file++ }
    /^#/ { next }
    file == 1 { n++; gt_t[n] = $1; for (k = 2; k <= 8; k++) gt[n, k] = $k; next }
    file == 2 {
      best = 0; bestdt = 0.02
      while (j < n && gt_t[j + 1] <= $1 + 0.02) j++
      for (i = (j > 2 ? j - 2 : 1); i <= j && i <= n; i++) {
        dt = gt_t[i] - $1; if (dt < 0) dt = -dt
        if (dt <= bestdt) { bestdt = dt; best = i }
      }
      if (!best) next
      if (!have) { have = 1; for (k = 2; k <= 8; k++) p0[k] = $k; g0 = best }
      for (k = 2; k <= 8; k++) pn[k] = $k
      gn = best
    }
    END {
      if (!have || gn == g0) { print "nan"; exit }
      rotinv(p0[5], p0[6], p0[7], p0[8], pn[2] - p0[2], pn[3] - p0[3], pn[4] - p0[4])
      ex = rx; ey = ry; ez = rz
      rotinv(gt[g0, 5], gt[g0, 6], gt[g0, 7], gt[g0, 8],
             gt[gn, 2] - gt[g0, 2], gt[gn, 3] - gt[g0, 3], gt[gn, 4] - gt[g0, 4])
      err = sqrt((ex - rx) ^ 2 + (ey - ry) ^ 2 + (ez - rz) ^ 2)
      for (i = g0 + 1; i <= gn; i++)
        dist += sqrt((gt[i, 2] - gt[i - 1, 2]) ^ 2 + (gt[i, 3] - gt[i - 1, 3]) ^ 2 + (gt[i, 4] - gt[i - 1, 4]) ^ 2)
      printf "%.4f\n", 100 * err / dist
    }' "$WORK/gt/groundtruth.txt" "$1"
}

for mode in depth-ba depth-init mono; do
  "$PROCS/rgbd-slam" --source "synth:$SPEC" --mode "$mode" --output "$WORK/$mode.txt" \
      --deterministic --quiet > "$WORK/$mode.out" 2> "$WORK/$mode.err" \
    || fail "rgbd-slam --mode $mode failed: $(tail -5 "$WORK/$mode.err")"
  poses=$(awk '/^poses /{print $2}' "$WORK/$mode.out")
  ate=$(awk '/^ate_rmse_m /{print $2}' "$WORK/$mode.out")
  final=$(final_error_percent "$WORK/$mode.txt")
  echo "$mode: poses $poses/$FRAMES ate_rmse_m $ate final_position_error_percent $final"
  [ "$poses" -ge "${MIN_POSES[$mode]}" ] \
    || fail "$mode: only $poses of $FRAMES frames got a pose (${MIN_POSES[$mode]} needed)"
  awk -v a="$ate" -v b="${ATE_BOUND_M[$mode]}" 'BEGIN { exit !(a <= b) }' \
    || fail "$mode: ATE $ate m exceeds ${ATE_BOUND_M[$mode]} m"
  awk -v f="$final" -v b="${FINAL_BOUND_PERCENT[$mode]}" 'BEGIN { exit !(f == f + 0 && f <= b) }' \
    || fail "$mode: final position error $final % exceeds ${FINAL_BOUND_PERCENT[$mode]} %"
  FINAL[$mode]=$final
done
awk -v ba="${FINAL[depth-ba]}" -v init="${FINAL[depth-init]}" 'BEGIN { exit !(ba < init) }' \
  || fail "depth-ba ends worse (${FINAL[depth-ba]} %) than depth-init (${FINAL[depth-init]} %)"
echo "PASS"
