#!/usr/bin/env python3
"""Latency figures over a whole run, from pose-logger's CSV (its latency_ms column: a frame's
timestamp to its pose's publication, every SLAM_POSE message, whatever its state).

  latency_report.py TRAJECTORY_CSV   key-value figures on stdout [ms]:
    latency_ms_median, latency_ms_p99, latency_ms_max     every frame
    latency_ms_p99_tracking                               frames tracking or dodgy (not lost,
                                                          relocalised or initialising)
    latency_ms_p99_lost                                   frames lost (relocalising or passed)
Rows that do not parse (a line cut when the logger was stopped) are skipped.
The tracker's own summary covers its last 1000 frames only (common/samples.h).
Standard library only."""
import csv
import sys


def quantile(values, q):
    ordered = sorted(values)
    return ordered[int(q * (len(ordered) - 1) + 0.5)] if ordered else float("nan")


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    rows = []
    with open(sys.argv[1]) as f:
        for r in csv.DictReader(f):
            try:
                rows.append((r["state"], float(r["latency_ms"])))
            except (KeyError, TypeError, ValueError):
                continue
    every = [latency for _, latency in rows]
    tracking = [latency for state, latency in rows if state in ("tracking", "dodgy")]
    print("latency_ms_median %.3f" % quantile(every, 0.5))
    print("latency_ms_p99 %.3f" % quantile(every, 0.99))
    print("latency_ms_max %.3f" % (max(every) if every else float("nan")))
    print("latency_ms_p99_tracking %.3f" % quantile(tracking, 0.99))
    print("latency_ms_p99_lost %.3f" % quantile([latency for state, latency in rows if state == "lost"], 0.99))


if __name__ == "__main__":
    main()
