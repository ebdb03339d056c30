#!/usr/bin/env python3
"""Figures and a plot from the memory samples of scripts/lib/suite.sh's sample_memory
("t_s rgbd-tracker_rss_mb rgbd-mapper_rss_mb" lines, "-" once a process has ended).

  memory_report.py MEMORY_TXT KEYFRAMES GROUNDTRUTH [KEYFRAMES_IN_MAP]
                                                      key-value figures on stdout
  memory_report.py --svg OUT.svg MEMORY_TXT LABEL...  memory over time, one colour per run
                                                      (tracker solid, mapper dashed)
Standard library only (no numpy on a fresh machine)."""
import math
import sys


def samples(path):
    rows = []
    with open(path) as f:
        next(f, None)
        for line in f:
            parts = line.split()
            if len(parts) != 3:
                continue
            t = float(parts[0])
            rows.append((t, *(None if p == "-" else float(p) for p in parts[1:])))
    return rows


def slope_per_min(points):
    if len(points) < 2:
        return 0.0
    n = len(points)
    mt = sum(t for t, _ in points) / n
    mv = sum(v for _, v in points) / n
    den = sum((t - mt) ** 2 for t, _ in points)
    return 60.0 * sum((t - mt) * (v - mv) for t, v in points) / den if den > 0 else 0.0


def path_length(groundtruth):
    last, total = None, 0.0
    with open(groundtruth) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            p = [float(x) for x in line.split()[1:4]]
            if last is not None:
                total += math.dist(p, last)
            last = p
    return total


def report(memory, keyframes, groundtruth, keyframes_in_map=0):
    rows = samples(memory)
    tracker = [(t, v) for t, v, _ in rows if v is not None]
    mapper = [(t, v) for t, _, v in rows if v is not None]
    out = {}
    if tracker:
        out["tracker_peak_mb"] = max(v for _, v in tracker)
        later = [v for t, v in tracker if t >= 60.0]
        if later:
            out["tracker_after_1min_min_mb"] = min(later)
            out["tracker_after_1min_max_mb"] = max(later)
        out["tracker_mb_per_min"] = slope_per_min(tracker)
    if mapper:
        out["mapper_peak_mb"] = max(v for _, v in mapper)
        if keyframes > 0:
            out["mapper_mb_per_keyframe"] = (mapper[-1][1] - mapper[0][1]) / keyframes
        out["mapper_mb_per_min"] = slope_per_min(mapper)
    out["groundtruth_path_m"] = path_length(groundtruth)
    if keyframes > 0 and out["groundtruth_path_m"] > 0:
        out["keyframes_per_groundtruth_m"] = keyframes / out["groundtruth_path_m"]
    if keyframes_in_map > 0 and out["groundtruth_path_m"] > 0:
        out["keyframes_in_map_per_groundtruth_m"] = keyframes_in_map / out["groundtruth_path_m"]
    for key, value in out.items():
        print(f"{key} {value:.3f}")


def svg(out_path, runs):
    colours = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"]
    series = [(label, samples(path)) for path, label in runs]
    t_max = max([t for _, rows in series for t, *_ in rows] + [1.0])
    v_max = max([v for _, rows in series for _, *vs in rows for v in vs if v is not None] + [1.0])
    v_max = 10 ** math.floor(math.log10(v_max)) * math.ceil(v_max / 10 ** math.floor(math.log10(v_max)))
    w, h, left, bottom, top, right = 720, 400, 60, 40, 20, 180
    x = lambda t: left + (w - left - right) * t / t_max
    y = lambda v: h - bottom - (h - bottom - top) * v / v_max
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="11">',
             f'<rect width="{w}" height="{h}" fill="white"/>',
             f'<line x1="{left}" y1="{y(0)}" x2="{x(t_max)}" y2="{y(0)}" stroke="black"/>',
             f'<line x1="{left}" y1="{y(0)}" x2="{left}" y2="{y(v_max)}" stroke="black"/>',
             f'<text x="{(left + w - right) / 2}" y="{h - 8}" text-anchor="middle">time since start [s]</text>',
             f'<text x="14" y="{(h - bottom + top) / 2}" transform="rotate(-90 14 {(h - bottom + top) / 2})" text-anchor="middle">resident memory [MB]</text>']
    for i in range(5):
        v, t = v_max * i / 4, t_max * i / 4
        parts.append(f'<text x="{left - 4}" y="{y(v) + 4}" text-anchor="end">{v:.0f}</text>')
        parts.append(f'<text x="{x(t)}" y="{y(0) + 14}" text-anchor="middle">{t:.0f}</text>')
        parts.append(f'<line x1="{left}" y1="{y(v)}" x2="{x(t_max)}" y2="{y(v)}" stroke="#ddd"/>')
    if v_max >= 150:
        parts.append(f'<line x1="{left}" y1="{y(150)}" x2="{x(t_max)}" y2="{y(150)}" stroke="black" stroke-dasharray="2,3"/>')
        parts.append(f'<text x="{x(t_max) + 4}" y="{y(150) + 4}">150 MB</text>')
    for k, (label, rows) in enumerate(series):
        colour = colours[k % len(colours)]
        for column, dash, who in ((1, "", "tracker"), (2, ' stroke-dasharray="6,4"', "mapper")):
            points = " ".join(f"{x(r[0]):.1f},{y(r[column]):.1f}" for r in rows if r[column] is not None)
            parts.append(f'<polyline points="{points}" fill="none" stroke="{colour}" stroke-width="1.5"{dash}/>')
            ly = top + 16 * (2 * k + column)
            parts.append(f'<line x1="{w - right + 10}" y1="{ly - 4}" x2="{w - right + 30}" y2="{ly - 4}" stroke="{colour}" stroke-width="1.5"{dash}/>')
            parts.append(f'<text x="{w - right + 34}" y="{ly}">{who}, {label}</text>')
    parts.append("</svg>")
    with open(out_path, "w") as f:
        f.write("\n".join(parts) + "\n")


if __name__ == "__main__":
    args = sys.argv[1:]
    if args[:1] == ["--svg"] and len(args) >= 4 and len(args) % 2 == 0:
        svg(args[1], list(zip(args[2::2], args[3::2])))
    elif len(args) in (3, 4):
        report(args[0], int(args[1] or 0), args[2], int(args[3] or 0) if len(args) == 4 else 0)
    else:
        sys.exit(__doc__)
