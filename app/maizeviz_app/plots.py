"""Light figures drawn off the GUI thread (matplotlib's Agg canvas; no Qt here).

The heatmaps are the core's own figures (:func:`maizeviz.light.report.heatmap.result_figure`, the
same as ``maizeviz light --heatmaps``) for a sun, a sky or a day; the transmission-vs-height
plot compares the mesh levels and lights traced with the same sampling (the paper's Table 3 as
a plot, with the diffuse sky and the day's PAR beside it). Figures are drawn to RGBA arrays in
a worker thread, so the window only wraps pixels.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

#: Line styles per level, fine to coarse, so levels keep their look as curves are added.
_STYLES = ("-o", "--s", "-.^", ":D", "-v", "--P", "-.X", ":*")
#: With several lights: a line style per light, a colour per level.
_KIND_STYLES = {"sun": "-o", "sky": "--s", "day": "-.^"}
_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
            "tab:pink", "tab:gray", "tab:olive", "tab:cyan")


@dataclass(frozen=True)
class Curve:
    """One result's transmission by height: label, heights (H,) cm, transmission (H,), the
    light (``kind``: sun, sky or day) and the mesh level (``level``, default the label)."""

    label: str
    heights_cm: tuple[float, ...]
    transmission: tuple[float, ...]
    kind: str = "sun"
    level: str = ""


#: Side of a heatmap bin drawn in the window, cm.
HEATMAP_BIN_CM = 5.0


def transmission_figure(curves: Sequence[Curve], title: str = "", width_in: float = 5.0,
                        dpi: int = 90):
    """Transmission (x, 0..1) against height (y, cm), one curve per mesh level and light."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, width_in * 0.72), dpi=dpi)
    ax = fig.add_subplot()
    kinds = {c.kind for c in curves}
    levels = list(dict.fromkeys(c.level or c.label for c in curves))
    for k, c in enumerate(curves):
        if kinds == {"sun"}:
            style, colour = _STYLES[k % len(_STYLES)], None
        else:
            style = _KIND_STYLES.get(c.kind, "-o")
            colour = _COLOURS[levels.index(c.level or c.label) % len(_COLOURS)]
        ax.plot(c.transmission, c.heights_cm, style, label=c.label, markersize=4,
                linewidth=1.3, color=colour)
    ax.set_xlim(0, 1)
    ax.set_xlabel("direct-light transmission (fraction of rays reaching the height)"
                  if kinds <= {"sun"} else
                  "transmission (fraction of the light reaching the height)")
    ax.set_ylabel("height (cm)")
    ax.grid(True, alpha=0.3)
    if curves:
        ax.legend(title="mesh level" if kinds == {"sun"} else "mesh level, light", fontsize=8,
                  title_fontsize=8, loc="lower right")
    else:
        ax.text(0.5, 0.5, "compute light to see transmission by height",
                ha="center", va="center", transform=ax.transAxes, fontsize=9, color="0.4")
    default = ("transmission by height, per mesh level (the paper's Table 3)"
               if kinds <= {"sun"} else "transmission by height, per mesh level and light")
    import textwrap

    lines = textwrap.wrap(title or default, int(11 * width_in))
    ax.set_title("\n".join(lines), fontsize=9)
    fig.subplots_adjust(left=0.12, right=0.97, bottom=0.14,            # tight_layout: 2 draws
                        top=0.9 - 0.05 * (len(lines) - 1))
    return fig


def rgba(fig) -> np.ndarray:
    """Draw a figure with Agg: (height, width, 4) uint8."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba()).copy()


def heatmap_figure_of(result, height: float, kind: str = "sun", width_in: float = 8.0,
                      dpi: int = 110, bin_cm: float = HEATMAP_BIN_CM):
    """The core's heatmap figure of one height of a light result (a sun's ``LightResult``, a
    ``SkyLight`` or a ``PeriodLight``; ``kind`` sun, sky or day), a sun's in ``bin_cm`` bins
    (:func:`maizeviz.light.report.heatmap.result_figure`, titled as
    ``maizeviz light --heatmaps``)."""
    from maizeviz.light.report.heatmap import result_figure

    return result_figure(result, float(height), kind, bin_cm, width_in=width_in, dpi=dpi)


def heatmap_image(result, height: float, bin_cm: float = HEATMAP_BIN_CM, width_in: float = 8.0,
                  dpi: int = 64, kind: str = "sun") -> np.ndarray:
    """The core's heatmap of one height of a light result (:func:`heatmap_figure_of`),
    drawn (RGBA)."""
    return rgba(heatmap_figure_of(result, height, kind, width_in, dpi, bin_cm))


def heatmap_images(result, first: int = 0, all_heights: bool = False, check=None,
                   kind: str = "sun") -> list[tuple[float, np.ndarray | None]]:
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
        out.append((h, heatmap_image(result, h, kind=kind) if drawn else None))
    return out
