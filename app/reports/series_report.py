"""Extra series of the error-against-time report, written alike: CSV, a Markdown table and a
plot of RMSE against frame time (one colour per series, one marker per sample count).

Used by the texture rows (:mod:`app.reports.texture_report`) and the ray-traced rows
(:mod:`app.reports.raytrace_report`); each row is a dict with at least ``series``,
``samples``, ``time_ms`` and ``rmse``.
"""

from __future__ import annotations

import csv
from pathlib import Path

MARKERS = {1: "o", 4: "s", 16: "^"}


def write(out_dir: Path, stem: str, data: list[dict], intro: str, columns: list[tuple[str, str]],
          title: str, ylabel: str, x: tuple[str, str] = ("time_ms", "frame time, ms (median)")
          ) -> list[Path]:
    """``stem``.csv/.md/.png in ``out_dir``; ``columns`` are (key, heading) pairs of the
    Markdown table, floats shown with two decimals (time with one)."""
    paths = [out_dir / f"{stem}.csv", out_dir / f"{stem}.md", out_dir / f"{stem}.png"]
    with open(paths[0], "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(data[0]))
        w.writeheader()
        w.writerows(data)
    lines = [intro, "", "| " + " | ".join(h for _, h in columns) + " |",
             "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(_cell(r[k], k) for k, _ in columns) + " |" for r in data]
    paths[1].write_text("\n".join(lines) + "\n")
    _plot(data, paths[2], title, ylabel, x)
    return paths


def _cell(value, key: str) -> str:
    if isinstance(value, float):
        return f"{value:.1f}" if key == "time_ms" else f"{value:.2f}"
    return str(value)


def _plot(data: list[dict], path: Path, title: str, ylabel: str,
          x: tuple[str, str] = ("time_ms", "frame time, ms (median)")) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for k, name in enumerate(dict.fromkeys(r["series"] for r in data)):
        pts = [r for r in data if r["series"] == name]
        ax.plot([r[x[0]] for r in pts], [r["rmse"] for r in pts], "-", color=f"C{k}",
                label=name)
        for r in pts:
            ax.plot(r[x[0]], r["rmse"], MARKERS.get(r["samples"], "x"), color=f"C{k}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(x[1])
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
