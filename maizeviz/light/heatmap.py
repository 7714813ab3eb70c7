"""Transmission maps: one PNG and one CSV per height (matplotlib's Agg canvas, no GUI)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from maizeviz.errors import MaizevizError


def transmission_map(result, height: float, bin_cm: float = 5.0):
    """Binned transmission at ``height`` over where the rays cross that plane.

    Returns x edges (a+1,), y edges (b+1,) cm, transmission (a, b) (NaN in empty bins) and
    ray counts (a, b).
    """
    if bin_cm <= 0:
        raise MaizevizError(f"heatmap bin must be > 0 cm, got {bin_cm}")
    xy = result.crossings(height)
    reached = result.first_z < height
    x0, y0, x1, y1 = result.rect
    sx, sy = xy[:, 0].min() - x0, xy[:, 1].min() - y0          # the rectangle, shifted
    nx = max(1, int(round((x1 - x0) / bin_cm)))
    ny = max(1, int(round((y1 - y0) / bin_cm)))
    xe = np.linspace(x0, x1, nx + 1) + sx
    ye = np.linspace(y0, y1, ny + 1) + sy
    counts, _, _ = np.histogram2d(xy[:, 0], xy[:, 1], [xe, ye])
    lit, _, _ = np.histogram2d(xy[reached, 0], xy[reached, 1], [xe, ye])
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(counts > 0, lit / counts, np.nan)
    return xe, ye, t, counts


def write_heatmaps(folder: str | Path, result, bin_cm: float = 5.0) -> list[Path]:
    """One ``transmission_h<h>cm.png`` and ``.csv`` per height in ``folder``; returns paths."""
    from matplotlib.figure import Figure

    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise MaizevizError(f"{folder}: cannot create the folder ({exc.strerror})") from None
    written = []
    tag = "".join(c if c.isalnum() else "_" for c in result.level).strip("_") or "level"
    for h, total in zip(result.heights_cm, result.transmission):
        xe, ye, t, counts = transmission_map(result, h, bin_cm)
        stem = folder / f"transmission_{tag}_h{h:g}cm"
        fig = Figure(figsize=(8, 8 * (ye[-1] - ye[0]) / (xe[-1] - xe[0]) * 0.8 + 1.6), dpi=110)
        ax = fig.add_subplot()
        im = ax.pcolormesh(xe, ye, t.T, vmin=0, vmax=1, cmap="viridis", shading="flat")
        ax.set_aspect("equal")
        ax.set_xlabel("x (cm, across rows)")
        ax.set_ylabel("y (cm, along rows)")
        ax.set_title(f"direct-light transmission at {h:g} cm: {total:.3f}\n"
                     f"sun zenith {result.sun.zenith_deg:.1f} deg, azimuth "
                     f"{result.sun.azimuth_deg:.1f} deg; level {result.level}; "
                     f"{result.rays:,} rays, {bin_cm:g} cm bins", fontsize=9)
        fig.colorbar(im, ax=ax, label="transmission (fraction of rays reaching this height)",
                     shrink=0.8)
        fig.tight_layout()
        try:
            fig.savefig(stem.with_suffix(".png"))
            with open(stem.with_suffix(".csv"), "w", newline="") as fh:
                w = csv.writer(fh)
                w.writerow(["x_cm", "y_cm", "height_cm", "transmission", "rays"])
                xc, yc = 0.5 * (xe[1:] + xe[:-1]), 0.5 * (ye[1:] + ye[:-1])
                for i, x in enumerate(xc):
                    for j, y in enumerate(yc):
                        w.writerow([f"{x:.2f}", f"{y:.2f}", f"{h:g}",
                                    "" if np.isnan(t[i, j]) else f"{t[i, j]:.4f}",
                                    int(counts[i, j])])
        except OSError as exc:
            raise MaizevizError(f"{stem}: cannot write ({exc.strerror})") from None
        written += [stem.with_suffix(".png"), stem.with_suffix(".csv")]
    return written
