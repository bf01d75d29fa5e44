"""Plots of a run's `stats.jsonl` as PNG (issue 5, "plots"): per-phase volume and its drift
against time, and every other numeric series the scene measures (surge front, bubble and spike
heights, …) against time, plus the time per frame of each stage. Comparisons with experiments
are `polyphase validate`'s (it knows each case's scaling and reference)."""

import json
import math
import os

#: Keys every frame line has; everything else numeric is a scene measurement.
STANDARD = {"frame", "time", "steps", "phase_volumes", "timings", "mesh", "cells", "interface_cells",
            "volume_error", "hausdorff"}


class StatsError(Exception):
    """`stats.jsonl` cannot be read."""


def read_stats(path):
    """Frame lines (dicts with `frame` and `time`) and the summary (or None); lines that are not
    JSON objects are skipped and counted."""
    lines, summary, bad = [], None, 0
    try:
        with open(path, "r", encoding="utf-8") as f:
            raw = f.readlines()
    except OSError as e:
        raise StatsError(f"cannot read {path}: {e.strerror or e}") from None
    for text in raw:
        text = text.strip()
        if not text:
            continue
        try:
            obj = json.loads(text)
        except ValueError:
            bad += 1
            continue
        if not isinstance(obj, dict):
            bad += 1
        elif "summary" in obj:
            summary = obj["summary"]
        elif isinstance(obj.get("time"), (int, float)):
            lines.append(obj)
        else:
            bad += 1
    lines.sort(key=lambda o: o["time"])
    return lines, summary, bad


def _number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def measurements(lines) -> dict:
    """Series name -> (times, values) for every numeric non-standard key, nested dicts flattened
    as `key.sub`; only series with at least two points."""
    series = {}
    for obj in lines:
        t = obj["time"]
        for key, value in obj.items():
            if key in STANDARD:
                continue
            items = value.items() if isinstance(value, dict) else [(None, value)]
            for sub, v in items:
                if _number(v):
                    name = key if sub is None else f"{key}.{sub}"
                    ts, vs = series.setdefault(name, ([], []))
                    ts.append(t)
                    vs.append(float(v))
    return {k: v for k, v in sorted(series.items()) if len(v[0]) >= 2}


def _colors(scene):
    return {p.name: tuple(min(max(c, 0.0), 1.0) ** (1 / 2.2) for c in p.color) for p in scene.phases} if scene else {}


def plot_all(stats_path, out_dir, scene=None) -> list:
    """Writes the plots into `out_dir`; returns their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lines, _, _ = read_stats(stats_path)
    if len(lines) < 1:
        return []
    os.makedirs(out_dir, exist_ok=True)
    written = []
    colors = _colors(scene)
    background = scene.phases[scene.background].name if scene else None
    times = [o["time"] for o in lines]

    names = sorted({n for o in lines for n in o.get("phase_volumes", {}) if n != background})
    if names:
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
        for n in names:
            pts = [(o["time"], o["phase_volumes"][n]) for o in lines if _number(o.get("phase_volumes", {}).get(n))]
            if not pts:
                continue
            t, v = zip(*pts)
            c = colors.get(n)
            ax1.plot(t, v, marker="o", ms=3, label=n, color=c)
            if v[0] != 0:
                ax2.plot(t, [100.0 * (x / v[0] - 1.0) for x in v], marker="o", ms=3, label=n, color=c)
        ax1.set(xlabel="time [s]", ylabel="volume [m³]", title="Volume per phase")
        ax2.set(xlabel="time [s]", ylabel="change since first frame [%]", title="Volume drift")
        ax2.axhline(0.0, color="0.5", lw=0.8)
        for ax in (ax1, ax2):
            ax.grid(alpha=0.3)
            ax.legend(fontsize=8)
        fig.tight_layout()
        path = os.path.join(out_dir, "volumes.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)

    series = measurements(lines)
    if series:
        k = len(series)
        cols = min(k, 2)
        rows = (k + cols - 1) // cols
        fig, axes = plt.subplots(rows, cols, figsize=(5.5 * cols, 3.6 * rows), squeeze=False)
        for ax, (name, (t, v)) in zip(axes.ravel(), series.items()):
            ax.plot(t, v, marker="o", ms=3, color="tab:blue")
            ax.set(xlabel="time [s]", title=name.replace("_", " "))
            ax.grid(alpha=0.3)
        for ax in axes.ravel()[k:]:
            ax.axis("off")
        fig.tight_layout()
        path = os.path.join(out_dir, "measurements.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)

    stages = sorted({s for o in lines for s, v in o.get("timings", {}).items() if _number(v)})
    if stages and len(lines) >= 2:
        fig, ax = plt.subplots(figsize=(7, 4))
        bottom = [0.0] * len(lines)
        for s in stages:
            v = [float(o.get("timings", {}).get(s, 0.0)) if _number(o.get("timings", {}).get(s, 0.0)) else 0.0 for o in lines]
            ax.bar(times, v, bottom=bottom, width=0.8 * (times[-1] - times[0]) / max(len(times) - 1, 1), label=s)
            bottom = [a + b for a, b in zip(bottom, v)]
        ax.set(xlabel="time [s]", ylabel="wall time per frame [s]", title="Time per stage")
        ax.legend(fontsize=8)
        fig.tight_layout()
        path = os.path.join(out_dir, "timings.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written
