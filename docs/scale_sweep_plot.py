#!/usr/bin/env python3
"""Draws docs/scale-sweep.svg from `nlrt bench ... --json FILE` outputs of the mountain at
several map sides (docs/measurements.md, "Scale"): rays per second of the recorded stream,
acceleration memory and build time against the map side, log-log, one line per method.

    python3 docs/scale_sweep_plot.py docs/data/scale-sweep/*.json > docs/scale-sweep.svg

Standard library only."""
import json
import math
import re
import sys

series = {}  # method name -> {side: (mrays, memory MiB, init s)}
for path in sys.argv[1:]:
    with open(path) as f:
        bench = json.load(f)
    size = bench["settings"]["scene_size"]
    m = re.search(r"(\d+)", size)
    side = int(m.group(1)) if m else 4096  # "paper": the mountain's 4096^2
    for row in bench["rows"]:
        if row["scene"] != "mountain" or "native" in row["method"]:
            continue
        stream = row.get("stream") or {}
        rate = stream.get("all", {}).get("mrays_per_s")
        # The first file to give a method at a side is kept (the sweep's own runs come
        # before the grid runs, which repeat nonlinear tracing beside Embree's grids).
        series.setdefault(row["method_name"], {}).setdefault(
            side, (rate, row["memory_bytes"] / 2**20, row["init_seconds"])
        )

panels = [
    ("stream rays/s (millions, 2 threads)", 0),
    ("acceleration memory (MiB)", 1),
    ("build time (s)", 2),
]
colours = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"]
W, H, PAD = 300, 240, 48
out = [
    f'<svg xmlns="http://www.w3.org/2000/svg" width="{len(panels) * W}" height="{H + 60}" '
    'font-family="sans-serif" font-size="11">',
    f'<rect width="{len(panels) * W}" height="{H + 60}" fill="white"/>',
]
sides = sorted({s for v in series.values() for s in v})
for p, (title, k) in enumerate(panels):
    x0 = p * W
    values = [v[s][k] for v in series.values() for s in v if v[s][k]]
    lo, hi = math.log10(min(values)), math.log10(max(values))
    lo, hi = math.floor(lo), math.ceil(hi) if hi > lo else lo + 1
    sx = lambda s: x0 + PAD + (math.log2(s) - math.log2(sides[0])) / max(
        1, math.log2(sides[-1]) - math.log2(sides[0])
    ) * (W - PAD - 16)
    sy = lambda v: H - (math.log10(v) - lo) / (hi - lo) * (H - 30)
    out.append(f'<text x="{x0 + W / 2}" y="14" text-anchor="middle">{title}</text>')
    out.append(
        f'<line x1="{x0 + PAD}" y1="{H}" x2="{x0 + W - 16}" y2="{H}" stroke="black"/>'
        f'<line x1="{x0 + PAD}" y1="30" x2="{x0 + PAD}" y2="{H}" stroke="black"/>'
    )
    for s in sides:
        out.append(
            f'<text x="{sx(s)}" y="{H + 14}" text-anchor="middle">{s}</text>'
            f'<line x1="{sx(s)}" y1="{H}" x2="{sx(s)}" y2="{H + 4}" stroke="black"/>'
        )
    for e in range(lo, hi + 1):
        out.append(
            f'<text x="{x0 + PAD - 4}" y="{sy(10**e) + 4}" text-anchor="end">1e{e}</text>'
            f'<line x1="{x0 + PAD}" y1="{sy(10**e)}" x2="{x0 + W - 16}" y2="{sy(10**e)}" '
            'stroke="#ddd"/>'
        )
    out.append(f'<text x="{x0 + W / 2}" y="{H + 30}" text-anchor="middle">map side (texels)</text>')
    for c, (name, points) in enumerate(sorted(series.items())):
        pts = [(sx(s), sy(points[s][k])) for s in sorted(points) if points[s][k]]
        colour = colours[c % len(colours)]
        out.append(
            '<polyline fill="none" stroke="%s" stroke-width="2" points="%s"/>'
            % (colour, " ".join(f"{x:.1f},{y:.1f}" for x, y in pts))
        )
        for x, y in pts:
            out.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="3" fill="{colour}"/>')
for c, name in enumerate(sorted(series)):
    colour = colours[c % len(colours)]
    out.append(
        f'<rect x="{10 + 300 * c}" y="{H + 44}" width="12" height="8" fill="{colour}"/>'
        f'<text x="{26 + 300 * c}" y="{H + 52}">{name}</text>'
    )
# Where the pre-tessellated surface stopped fitting (the measured out-of-memory kill).
embree = [s for n, v in series.items() if "Embree" in n for s in v]
if embree and max(embree) < sides[-1]:
    out.append(
        f'<text x="{W + W / 2}" y="{H - 8}" text-anchor="middle" fill="#1f77b4">'
        f"Embree: out of memory at {2 * max(embree)}^2 (24 GiB)</text>"
    )
out.append("</svg>")
print("\n".join(out))
