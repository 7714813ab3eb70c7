"""Light figures drawn off the GUI thread (matplotlib's Agg canvas; no Qt here).

The heatmaps are the core's own figures (:func:`maizeviz.light.heatmap.heatmap_figure`, the
same as ``maizeviz light --heatmaps``); the transmission-vs-height plot compares the mesh
levels traced under the same sun (the paper's Table 3 as a plot). Figures are drawn to RGBA
arrays in a worker thread, so the window only wraps pixels.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

#: Line styles per level, fine to coarse, so levels keep their look as curves are added.
_STYLES = ("-o", "--s", "-.^", ":D", "-v", "--P", "-.X", ":*")


@dataclass(frozen=True)
class Curve:
    """One level's transmission by height: label, heights (H,) cm, transmission (H,)."""

    label: str
    heights_cm: tuple[float, ...]
    transmission: tuple[float, ...]


def transmission_figure(curves: Sequence[Curve], title: str = "", width_in: float = 5.0,
                        dpi: int = 90):
    """Transmission (x, 0..1) against height (y, cm), one curve per mesh level."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, width_in * 0.72), dpi=dpi)
    ax = fig.add_subplot()
    for k, c in enumerate(curves):
        ax.plot(c.transmission, c.heights_cm, _STYLES[k % len(_STYLES)], label=c.label,
                markersize=4, linewidth=1.3)
    ax.set_xlim(0, 1)
    ax.set_xlabel("direct-light transmission (fraction of rays reaching the height)")
    ax.set_ylabel("height (cm)")
    ax.grid(True, alpha=0.3)
    if curves:
        ax.legend(title="mesh level", fontsize=8, title_fontsize=8, loc="lower right")
    else:
        ax.text(0.5, 0.5, "compute direct light to see transmission by height",
                ha="center", va="center", transform=ax.transAxes, fontsize=9, color="0.4")
    ax.set_title(title or "transmission by height, per mesh level (the paper's Table 3)",
                 fontsize=9)
    fig.subplots_adjust(left=0.12, right=0.97, bottom=0.14, top=0.9)   # tight_layout: 2 draws
    return fig


def rgba(fig) -> np.ndarray:
    """Draw a figure with Agg: (height, width, 4) uint8."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba()).copy()


def heatmap_image(result, height: float, bin_cm: float = 5.0, width_in: float = 8.0,
                  dpi: int = 64) -> np.ndarray:
    """The core's heatmap of one height of a light result, drawn (RGBA)."""
    from maizeviz.light.heatmap import heatmap_figure, transmission_map

    tmap = transmission_map(result, float(height), bin_cm)
    return rgba(heatmap_figure(tmap, result, width_in=width_in, dpi=dpi))


def heatmap_images(result, first: int = 0, all_heights: bool = False,
                   check=None) -> list[tuple[float, np.ndarray | None]]:
    """[(height, RGBA or None)] for every height of a light result: the ``first`` one drawn
    (each figure takes 0.3-1 s), the others too with ``all_heights``, else drawn when asked
    for. ``check()`` is called between figures (it may raise InterruptedError)."""
    heights = [float(h) for h in result.heights_cm]
    first = first if 0 <= first < len(heights) else 0
    out: list[tuple[float, np.ndarray | None]] = []
    for k, h in enumerate(heights):
        if check is not None:
            check()
        drawn = k == first or all_heights
        out.append((h, heatmap_image(result, h) if drawn else None))
    return out
