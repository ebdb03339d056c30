#!/usr/bin/env python3
"""Where each new part of the map started, against the truth: for every "a new part of the
map started" line in a suite run's tracker.err, the last pose before the loss and the
first pose the part published (the first frame after the start not answered lost), each relative to the other, in the estimate and in the
ground truth. "truth moved" is how far the camera went and turned while lost; "start off"
is how far the part's first pose is from where it should be relative to the last pose
(what a join must correct, before any drift within the part).

  part_starts.py RUN_DIR   RUN_DIR: one source's folder of scripts/bench-suite (or any
                           split run): tracker.err, trajectory.csv, groundtruth.txt
One line per part start on stdout. Standard library only."""
import csv
import math
import re
import sys


def rotation(q):
    x, y, z, w = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


def transpose_times(a, b):  # a^T b
    return [[sum(a[k][i] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def angle_deg(r):
    return math.degrees(math.acos(max(-1.0, min(1.0, (r[0][0] + r[1][1] + r[2][2] - 1) / 2))))


def relative(a, b):
    """b relative to a (both tx ty tz qx qy qz qw): translation in a's frame, rotation."""
    ra, rb = rotation(a[3:]), rotation(b[3:])
    d = [b[i] - a[i] for i in range(3)]
    return [sum(ra[r][c] * d[r] for r in range(3)) for c in range(3)], transpose_times(ra, rb)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    run = sys.argv[1]
    estimate = {}
    with open(run + "/trajectory.csv") as f:
        for row in csv.DictReader(f):
            try:
                estimate[int(row["seq"])] = (int(row["utime"]), [float(row[k]) for k in ("tx", "ty", "tz", "qx", "qy", "qz", "qw")],
                                             row["state"])
            except (KeyError, ValueError, TypeError):
                continue  # a line cut when the logger was stopped
    truth = {}
    with open(run + "/groundtruth.txt") as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            v = [float(x) for x in line.split()]
            truth[round(v[0], 4)] = v[1:]
    pattern = re.compile(r"frame (\d+): a new part .* after (\d+) lost frames \(lost at frame (\d+)")
    with open(run + "/tracker.err") as f:
        starts = [(int(m.group(1)), int(m.group(3))) for m in map(pattern.search, f) if m]
    for i, (start, lost) in enumerate(starts):
        end = starts[i + 1][0] if i + 1 < len(starts) else float("inf")
        before = [k for k in estimate if k <= lost]
        # The part's first pose: the first frame after it, before the next part, that has
        # one (rgbd-tracker answers frames lost, at the last published pose, while its
        # relocaliser thread works).
        after = [k for k in estimate if start < k < end and estimate[k][2] in ("tracking", "dodgy", "relocalised")]
        if not before or not after:
            print("part at frame %d: lost again before its first pose" % start)
            continue
        a, b = estimate[max(before)], estimate[min(after)]
        ta, tb = truth.get(round(a[0] / 1e6, 4)), truth.get(round(b[0] / 1e6, 4))
        if ta is None or tb is None:
            print("part at frame %d: no ground truth at its poses" % start)
            continue
        te, re_ = relative(a[1], b[1])
        tt, rt = relative(ta, tb)
        print("part at frame %d: last pose %d, first %d; truth moved %.2f m %.1f deg; start off %.2f m %.1f deg"
              % (start, max(before), min(after), math.dist(tt, [0, 0, 0]), angle_deg(rt), math.dist(te, tt),
                 angle_deg(transpose_times(re_, rt))))


if __name__ == "__main__":
    main()
