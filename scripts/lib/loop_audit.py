#!/usr/bin/env python3
"""Each place rgbd-mapper recognised, its loop edge against the ground truth: what rgbd-slam
prints in batch (lib/include/rgbdslam/eval/loop_audit.h, whose bar this shares), for a split
run. Reads the "loop with keyframe ...; edge utime A -> B t X Y Z q QX QY QZ QW" lines of
mapper.err and the truth at both keyframes' times (within 0.02 s) from groundtruth.txt.

  loop_audit.py RUN_DIR [-v]   RUN_DIR: one source's folder of scripts/bench-suite (or any
                               split run): mapper.err, groundtruth.txt
"key value" lines on stdout, as rgbd-slam prints them; -v adds one line per place. Standard
library only."""
import bisect
import math
import re
import sys

from part_starts import angle_deg, relative, transpose_times, rotation

WRONG_M, WRONG_DEG, MAX_DT_S = 0.25, 5.0, 0.02  # eval/loop_audit.h, LoopAuditOptions

LINE = re.compile(r"keyframe (\d+): loop with keyframe (\d+): ([a-z_ ]+?)[,;].*edge utime (\d+) -> (\d+) "
                  r"t (\S+) (\S+) (\S+) q (\S+) (\S+) (\S+) (\S+)")


def read_truth(path):
    times, poses = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            v = [float(x) for x in line.split()]
            times.append(v[0])
            poses.append(v[1:])
    order = sorted(range(len(times)), key=times.__getitem__)
    return [times[i] for i in order], [poses[i] for i in order]


def nearest(times, poses, t):
    i = bisect.bisect_left(times, t)
    best = min((j for j in (i - 1, i) if 0 <= j < len(times)), key=lambda j: abs(times[j] - t), default=None)
    return poses[best] if best is not None and abs(times[best] - t) <= MAX_DT_S else None


def main():
    if len(sys.argv) not in (2, 3) or (len(sys.argv) == 3 and sys.argv[2] != "-v"):
        sys.exit(__doc__)
    run, verbose = sys.argv[1], len(sys.argv) == 3
    times, poses = read_truth(run + "/groundtruth.txt")
    n = {"checked": 0, "unmatched": 0, "accepted": 0, "accepted_wrong": 0, "refused": 0, "refused_wrong": 0}
    worst = {"accepted_m": 0.0, "accepted_deg": 0.0, "right_m": 0.0, "right_deg": 0.0}
    with open(run + "/mapper.err") as f:
        places = [m for m in map(LINE.search, f) if m]
    for m in places:
        query, with_, verdict = int(m.group(1)), int(m.group(2)), m.group(3)
        ga, gb = nearest(times, poses, int(m.group(4)) * 1e-6), nearest(times, poses, int(m.group(5)) * 1e-6)
        if ga is None or gb is None:
            n["unmatched"] += 1
            continue
        n["checked"] += 1
        tt, rt = relative(ga, gb)
        te = [float(m.group(i)) for i in range(6, 9)]
        re_ = rotation([float(m.group(i)) for i in range(9, 13)])
        err_m, err_deg = math.dist(te, tt), angle_deg(transpose_times(rt, re_))
        wrong = err_m > WRONG_M or err_deg > WRONG_DEG
        if not wrong:
            worst["right_m"], worst["right_deg"] = max(worst["right_m"], err_m), max(worst["right_deg"], err_deg)
        kind = "refused" if verdict == "refused" else "accepted"
        n[kind] += 1
        n[kind + "_wrong"] += wrong
        if kind == "accepted":
            worst["accepted_m"], worst["accepted_deg"] = max(worst["accepted_m"], err_m), max(worst["accepted_deg"], err_deg)
        if verbose:
            print("keyframe %d with %d: %s, edge off the truth %.3f m %.2f deg%s"
                  % (query, with_, verdict, err_m, err_deg, " WRONG" if wrong else ""))
    print("loop_audit_checked %d\nloop_audit_unmatched %d\nloops_accepted %d\nloops_accepted_wrong %d" %
          (n["checked"], n["unmatched"], n["accepted"], n["accepted_wrong"]))
    print("loops_refused_checked %d\nloops_refused_wrong %d" % (n["refused"], n["refused_wrong"]))
    print("loop_accepted_max_error_m %.6f\nloop_accepted_max_error_deg %.6f" % (worst["accepted_m"], worst["accepted_deg"]))
    print("loop_right_max_error_m %.6f\nloop_right_max_error_deg %.6f" % (worst["right_m"], worst["right_deg"]))
    print("loop_wrong_bar_m %.6f\nloop_wrong_bar_deg %.6f" % (WRONG_M, WRONG_DEG))


if __name__ == "__main__":
    main()
