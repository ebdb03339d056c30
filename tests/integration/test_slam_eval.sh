#!/usr/bin/env bash
# Runs the real slam-eval binary: known-answer ATE, exit code 2 with file and line for a
# malformed file, JSON that parses, a PNG plot. Needs no network and no shared data (the
# TUM teddy sanity check runs only when ../shared/data is present).
# Env: RGBDSLAM_BUILD_DIR (required), RGBDSLAM_SHARED_DIR (optional).
set -euo pipefail

build_dir="${RGBDSLAM_BUILD_DIR:?RGBDSLAM_BUILD_DIR must point at the build directory}"
slam_eval="$build_dir/procs/slam-eval"
[[ -d "$slam_eval" ]] && slam_eval="$slam_eval/slam-eval"  # if executables get their own folder
if [[ ! -x "$slam_eval" ]]; then
  echo "FAIL: slam-eval not built at $slam_eval" >&2
  exit 1
fi

work="$(mktemp -d "${TMPDIR:-/tmp}/test_slam_eval.XXXXXX")"
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*" >&2
  exit 1
}

# Ground truth: 20 s at 20 Hz on a helix with changing orientation. Estimate: the same poses
# seen from another world frame (a rotation of 0.7 rad about z and a translation), 5 ms later.
python3 - "$work" <<'EOF'
import math, sys
work = sys.argv[1]
def quat_mul(a, b):
    ax, ay, az, aw = a; bx, by, bz, bw = b
    return (aw*bx + ax*bw + ay*bz - az*by, aw*by - ax*bz + ay*bw + az*bx,
            aw*bz + ax*by - ay*bx + az*bw, aw*bw - ax*bx - ay*by - az*bz)
def rotate(q, p):
    x, y, z, w = quat_mul(quat_mul(q, (p[0], p[1], p[2], 0.0)), (-q[0], -q[1], -q[2], q[3]))
    return (x, y, z)
def yaw(angle):
    return (0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2))
q_est_gt, t_est_gt = yaw(0.7), (1.0, -2.0, 0.5)
with open(f"{work}/gt.txt", "w") as gt, open(f"{work}/est.txt", "w") as est:
    gt.write("# timestamp tx ty tz qx qy qz qw\n")
    for k in range(400):
        t = 1341841873.0 + 0.05 * k
        s = 0.05 * k
        p = (2 * math.cos(0.3 * s), 2 * math.sin(0.3 * s), 1.0 + 0.2 * math.sin(s))
        q = quat_mul(yaw(0.3 * s), (math.sin(0.05), 0.0, 0.0, math.cos(0.05)))
        gt.write("%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n" % ((t,) + p + q))
        pe = tuple(a + b for a, b in zip(rotate(q_est_gt, p), t_est_gt))
        qe = quat_mul(q_est_gt, q)
        est.write("%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n" % ((t + 0.005,) + pe + qe))
EOF

# 1. Known answer: ATE ~ 0, all 400 poses associated.
out="$("$slam_eval" "$work/gt.txt" "$work/est.txt" --frames 400)"
echo "$out"
ate="$(awk '$1 == "ate_rmse_m" { print $2 }' <<<"$out")"
[[ -n "$ate" ]] || fail "no 'ate_rmse_m VALUE' line"
awk -v v="$ate" 'BEGIN { exit !(v < 1e-5) }' || fail "ate_rmse_m $ate, expected ~0"
grep -qx "num_associated 400" <<<"$out" || fail "expected num_associated 400"
grep -qx "coverage 1.000000" <<<"$out" || fail "expected coverage 1.000000"

# 2. A malformed line: exit code 2 and a message naming file and line.
cp "$work/gt.txt" "$work/bad.txt"
sed -i '4s/.*/1341841873.2 1.0 2.0 oops 0 0 0 1/' "$work/bad.txt"
set +e
err="$("$slam_eval" "$work/bad.txt" "$work/est.txt" 2>&1 >/dev/null)"
code=$?
set -e
[[ $code -eq 2 ]] || fail "malformed file: exit code $code, expected 2"
grep -q "bad.txt:4" <<<"$err" || fail "malformed file: message does not name bad.txt:4: $err"

# 3. Missing file and a bad option value: exit code 2.
set +e
"$slam_eval" "$work/missing.txt" "$work/est.txt" >/dev/null 2>&1; code_missing=$?
"$slam_eval" "$work/gt.txt" "$work/est.txt" --max-dt -1 >/dev/null 2>&1; code_option=$?
"$slam_eval" "$work/gt.txt" >/dev/null 2>&1; code_args=$?
set -e
[[ $code_missing -eq 2 ]] || fail "missing file: exit code $code_missing, expected 2"
[[ $code_option -eq 2 ]] || fail "--max-dt -1: exit code $code_option, expected 2"
[[ $code_args -eq 2 ]] || fail "one positional argument: exit code $code_args, expected 2"

# 4. --json parses and carries the ATE; --json-out writes the same; --plot writes a PNG.
"$slam_eval" "$work/gt.txt" "$work/est.txt" --json --json-out "$work/out.json" \
  --plot "$work/plot.png" --errors-out "$work/errors.csv" >"$work/stdout.json"
# --errors-out: a header and one row per associated pose, each error ~0 (a rigid motion).
[[ $(wc -l <"$work/errors.csv") -eq 401 ]] || fail "errors.csv should have 401 lines"
awk -F, 'NR > 1 && $2 > 1e-5 { bad = 1 } END { exit bad }' "$work/errors.csv" \
  || fail "errors.csv holds a non-zero error for a rigidly moved trajectory"
python3 - "$work" <<'EOF' || fail "JSON or PNG check failed"
import json, struct, sys
work = sys.argv[1]
printed = json.load(open(f"{work}/stdout.json"))
written = json.load(open(f"{work}/out.json"))
assert printed == written, "printed and written JSON differ"
assert printed["ate_rmse_m"] < 1e-5, printed["ate_rmse_m"]
assert printed["alignment"] == "rigid" and printed["coverage"] is None, printed
assert printed["num_associated"] == 400, printed
png = open(f"{work}/plot.png", "rb").read()
assert png[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
width, height = struct.unpack(">II", png[16:24])
assert (width, height) == (1200, 600), (width, height)
EOF

# 5. --help documents the options and exits 0.
help="$("$slam_eval" --help)"
for option in --json --json-out --plot --errors-out --similarity --max-dt --frames --frames-from; do
  grep -q -- "$option" <<<"$help" || fail "--help does not mention $option"
done

# 6. Sanity check on real data when present: the TUM ground truth against itself.
teddy="${RGBDSLAM_SHARED_DIR:-}/data/tum_fr3_teddy_200"
if [[ -n "${RGBDSLAM_SHARED_DIR:-}" && -f "$teddy/groundtruth.txt" ]]; then
  out="$("$slam_eval" "$teddy/groundtruth.txt" "$teddy/groundtruth.txt" --frames-from "$teddy/rgb.txt")"
  ate="$(awk '$1 == "ate_rmse_m" { print $2 }' <<<"$out")"
  [[ "$ate" == "0.000000" ]] || fail "teddy ground truth against itself: ate_rmse_m $ate"
else
  echo "note: tum_fr3_teddy_200 not found; skipping the real-data sanity check"
fi

echo "PASS: test_slam_eval"
