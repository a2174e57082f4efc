#!/usr/bin/env python3
"""Draws a `profile --trace` file as a timeline (docs/trace.png): the host track (setup phases,
each batch's submit-and-wait) above, the device track (every pass) below, the whole run on the
left and its first timed batch enlarged on the right. Perfetto (ui.perfetto.dev) opens the same
file interactively; this is for the docs, where no browser runs.

    antiradiance profile --frames 8 --trace trace.json
    python3 scripts/plot-trace.py trace.json docs/trace.png      # needs matplotlib
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

events = json.load(open(sys.argv[1]))["traceEvents"]
names = {e["tid"]: e["args"]["name"] for e in events if e.get("ph") == "M" and e["name"] == "thread_name"}
spans = [e for e in events if e.get("ph") == "X"]
colours = {}
palette = plt.get_cmap("tab10").colors


def colour(n):
    return colours.setdefault(n, palette[len(colours) % len(palette)])


first = min((e for e in spans if e["tid"] == 1), key=lambda e: e["ts"])
batch = [e for e in spans if e["args"].get("batch") == first["args"].get("batch")]
lo = min(e["ts"] for e in batch) / 1e3
hi = max(e["ts"] + e["dur"] for e in batch) / 1e3
fig, axes = plt.subplots(1, 2, figsize=(12, 2.8), gridspec_kw={"width_ratios": [1, 1]})
for ax, title, window in [(axes[0], "whole run", None), (axes[1], "first timed batch", (lo, hi))]:
    for e in spans:
        y = 1 if e["tid"] == 2 else 0
        x, w = e["ts"] / 1e3, e["dur"] / 1e3
        if window and (x + w < window[0] or x > window[1]):
            continue
        ax.broken_barh([(x, w)], (y - 0.4, 0.8), color=colour(e["name"]), edgecolor="black", linewidth=0.3)
        if window and w > (window[1] - window[0]) * 0.06:
            ax.text(x + w / 2, y, e["name"], ha="center", va="center", fontsize=7)
    ax.set_yticks([0, 1], [names.get(1, "device"), names.get(2, "host")], fontsize=8)
    ax.set_xlabel("ms", fontsize=8)
    ax.set_title(title, fontsize=9)
    ax.tick_params(axis="x", labelsize=7)
    if window:
        ax.set_xlim(*window)
handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in colours.values()]
fig.legend(handles, list(colours), fontsize=7, ncol=min(len(colours), 8), loc="lower center")
fig.tight_layout(rect=(0, 0.12, 1, 1))
fig.savefig(sys.argv[2], dpi=110)
print("wrote", sys.argv[2])
