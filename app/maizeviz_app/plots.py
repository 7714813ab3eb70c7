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

from maizeviz_app.figures import Canvas

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
#: Size of a figure's texts drawn for a canvas (points at the canvas's dpi): 9.5 pt is
#: 12.7 px at 96 dpi, capitals 9 px tall in DejaVu Sans.
FONT_PT = 9.5


def smallest_text_px(fig) -> float:
    """The size (pixels, at the figure's dpi) of the smallest text drawn in ``fig``."""
    from matplotlib.text import Text

    sizes = [t.get_size() for t in fig.findobj(Text) if t.get_visible() and t.get_text()
             and t.get_figure() is not None]
    return min(sizes) * fig.dpi / 72 if sizes else 0.0


def transmission_figure(curves: Sequence[Curve], title: str = "", width_in: float = 5.0,
                        dpi: float = 90, canvas: Canvas | None = None):
    """Transmission (x, 0..1) against height (y, cm), one curve per mesh level and light;
    drawn for ``canvas`` (its size and dpi, constrained layout, texts at :data:`FONT_PT`)
    when given, else ``width_in`` wide at ``dpi``."""
    from matplotlib.figure import Figure

    if canvas is None:
        fig = Figure(figsize=(width_in, width_in * 0.72), dpi=dpi)
    else:
        width_in, dpi = canvas.inches[0], canvas.dpi
        fig = Figure(figsize=canvas.inches, dpi=dpi, layout="constrained")
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
    small = canvas is not None and min(canvas.inches) < 4.0
    font = FONT_PT if canvas is not None else None
    ax.set_xlabel("transmission" if small else
                  "direct-light transmission (fraction of rays reaching the height)"
                  if kinds <= {"sun"} else
                  "transmission (fraction of the light reaching the height)", fontsize=font)
    ax.set_ylabel("height (cm)", fontsize=font)
    ax.grid(True, alpha=0.3)
    if canvas is not None:
        from matplotlib.ticker import MaxNLocator

        ax.tick_params(labelsize=font)
        w, h = canvas.inches
        ax.xaxis.set_major_locator(MaxNLocator(max(int(w / 1.0), 2)))
        ax.yaxis.set_major_locator(MaxNLocator(max(int(h / 0.5), 2)))
    if curves:
        ax.legend(title="mesh level" if kinds == {"sun"} else "mesh level, light",
                  fontsize=font or 8, title_fontsize=font or 8,
                  loc="lower right" if canvas is None else "best")
    else:
        ax.text(0.5, 0.5, "compute light to see transmission by height",
                ha="center", va="center", transform=ax.transAxes, fontsize=font or 9,
                color="0.4")
    default = ("transmission by height, per mesh level (the paper's Table 3)"
               if kinds <= {"sun"} else "transmission by height, per mesh level and light")
    import textwrap

    chars = int(11 * width_in) if canvas is None else int(width_in * 72 / (0.55 * FONT_PT))
    lines = textwrap.wrap(title or default, max(chars, 20))
    if small and len(lines) > 1:                # the room is the plot's
        lines = [lines[0] + " …"]
    ax.set_title("\n".join(lines), fontsize=font or 9)
    if canvas is None:
        fig.subplots_adjust(left=0.12, right=0.97, bottom=0.14,        # tight_layout: 2 draws
                            top=0.9 - 0.05 * (len(lines) - 1))
    return fig


def rgba(fig) -> np.ndarray:
    """Draw a figure with Agg: (height, width, 4) uint8."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba()).copy()


class Look:
    """How heatmaps are coloured, handed to the worker that draws them: a snapshot of a
    :class:`~maizeviz_app.colour.ColourScale` and, when the maps share one scale, the results
    (light -> result) over whose maps at every height the range is taken (binned once, on
    first use, in the worker). ``Look()`` is the core's own: 0 to 1, viridis."""

    def __init__(self, scale=None, shared: dict | None = None,
                 bin_cm: float = HEATMAP_BIN_CM) -> None:
        from maizeviz_app.colour import ColourScale

        self.scale = ColourScale(**scale.to_doc()) if scale is not None else \
            ColourScale(range="fixed")
        self.scale.check()
        self.shared = dict(shared) if shared is not None else None
        self.bin_cm = bin_cm
        self._shared_limits: tuple[float, float] | None = None

    @classmethod
    def of(cls, settings, shown: dict) -> Look:
        """The look of the heatmaps of ``settings`` (a ``ColourSettings``) for the results
        shown (light -> its ``Run``, or its result): every height of each shares the scale
        when ``settings.shared``. Take it on the GUI thread (a snapshot)."""
        shared = {kind: getattr(run, "result", run) for kind, run in shown.items()} \
            if settings.shared else None
        return cls(settings.heatmap, shared)

    def sharing(self, kind: str, result) -> Look:
        """This look with ``result`` as the ``kind`` shared (a new run's)."""
        if self.shared is not None:
            self.shared[kind] = result
            self._shared_limits = None
        return self

    def limits(self, tmap) -> tuple[float, float]:
        """The range of the map ``tmap`` (a ``TransmissionMap``), or of every shared map."""
        if self.shared is None:
            return self.scale.limits(tmap.transmission)
        if self._shared_limits is None:
            from maizeviz.light.report.heatmap import result_map

            values = [result_map(r, float(h), kind, self.bin_cm).transmission.ravel()
                      for kind, r in self.shared.items() for h in r.heights_cm]
            self._shared_limits = self.scale.limits(np.concatenate(values) if values
                                                    else tmap.transmission)
        return self._shared_limits

    def colours(self, tmap) -> dict:
        """The keywords of :func:`maizeviz.light.report.heatmap.heatmap_figure` for ``tmap``."""
        from maizeviz_app.colour import CMAPS

        lo, hi = self.limits(tmap)
        return {"vmin": lo, "vmax": hi, "cmap": CMAPS[self.scale.cmap], "log": self.scale.log}


@dataclass(frozen=True)
class Heatmap:
    """A heatmap drawn, and what lies under each of its pixels.

    Attributes
    ----------
    rgba : (h, w, 4) uint8, the figure
    box : (left, top, right, bottom), the map's axes in the image's pixels
    x_edges, y_edges : (nx + 1,), (ny + 1,) bin edges, cm, as the axes read
    values : (nx, ny) the map's transmission (NaN: no ray); rays : (nx, ny) rays per bin
    height_cm : the sensor plane's height; limits : (low, high) of the colours; what : what
        the values are (the figure's title)
    font_px : the smallest text's size in the image's pixels
    """

    rgba: np.ndarray
    box: tuple[float, float, float, float]
    x_edges: np.ndarray
    y_edges: np.ndarray
    values: np.ndarray
    rays: np.ndarray
    height_cm: float
    limits: tuple[float, float]
    what: str
    font_px: float = 0.0

    def value_at(self, px: float, py: float) -> tuple[float, float, float, int] | None:
        """(x cm, y cm, value, rays) of the bin under the image pixel (``px``, ``py``; from
        the top left), None off the map."""
        left, top, right, bottom = self.box
        if not (left <= px <= right and top <= py <= bottom) or right <= left or bottom <= top:
            return None
        xe, ye = self.x_edges, self.y_edges
        x = xe[0] + (px - left) / (right - left) * (xe[-1] - xe[0])
        y = ye[-1] - (py - top) / (bottom - top) * (ye[-1] - ye[0])     # y grows upwards
        i = int(np.clip(np.searchsorted(xe, x, "right") - 1, 0, len(xe) - 2))
        j = int(np.clip(np.searchsorted(ye, y, "right") - 1, 0, len(ye) - 2))
        return float(x), float(y), float(self.values[i, j]), int(self.rays[i, j])


def heatmap_figure_of(result, height: float, kind: str = "sun", width_in: float = 8.0,
                      dpi: int = 110, bin_cm: float = HEATMAP_BIN_CM, look: Look | None = None):
    """The core's heatmap figure of one height of a light result (a sun's ``LightResult``, a
    ``SkyLight`` or a ``PeriodLight``; ``kind`` sun, sky or day), a sun's in ``bin_cm`` bins
    (:func:`maizeviz.light.report.heatmap.result_figure`, titled as
    ``maizeviz light --heatmaps``), coloured as ``look`` says (None: the core's 0 to 1)."""
    from maizeviz.light.report.heatmap import result_figure, result_map

    tmap = result_map(result, float(height), kind, bin_cm)
    colours = (look or Look()).colours(tmap)
    return result_figure(result, float(height), kind, bin_cm, width_in=width_in, dpi=dpi,
                         tmap=tmap, **colours)


def heatmap_image(result, height: float, bin_cm: float = HEATMAP_BIN_CM, width_in: float = 8.0,
                  dpi: float = 64, kind: str = "sun", look: Look | None = None,
                  canvas: Canvas | None = None) -> Heatmap:
    """The core's heatmap of one height of a light result (:func:`heatmap_figure_of`),
    drawn, with where its bins lie in the picture (for the value under the mouse): for
    ``canvas`` (its size and dpi, texts at :data:`FONT_PT`) when given, else ``width_in``
    wide at ``dpi``."""
    from maizeviz.light.report.heatmap import map_title, result_figure, result_map

    tmap = result_map(result, float(height), kind, bin_cm)
    colours = (look or Look()).colours(tmap)
    if canvas is not None:
        colours.update(fit=canvas.inches, font_pt=FONT_PT)
        dpi = canvas.dpi
    fig = result_figure(result, float(height), kind, bin_cm, width_in=width_in, dpi=dpi,
                        tmap=tmap, **colours)
    pixels = rgba(fig)
    h = pixels.shape[0]
    ext = fig.axes[0].get_window_extent()              # drawn: the box after the aspect
    return Heatmap(pixels, (float(ext.x0), float(h - ext.y1), float(ext.x1), float(h - ext.y0)),
                   np.asarray(tmap.x_edges), np.asarray(tmap.y_edges),
                   np.asarray(tmap.transmission), np.asarray(tmap.rays), tmap.height_cm,
                   (colours["vmin"], colours["vmax"]), map_title(result, kind)[0],
                   smallest_text_px(fig))


def heatmap_images(result, first: int = 0, all_heights: bool = False, check=None,
                   kind: str = "sun", look: Look | None = None, canvas: Canvas | None = None
                   ) -> list[tuple[float, Heatmap | None]]:
    """[(height, Heatmap or None)] for every height of a light result: the ``first`` one drawn
    (each figure takes 0.3-1 s), the others too with ``all_heights``, else drawn when asked
    for; for ``canvas`` as :func:`heatmap_image`. ``check()`` is called between figures (it
    may raise InterruptedError)."""
    heights = [float(h) for h in result.heights_cm]
    first = first if 0 <= first < len(heights) else 0
    out: list[tuple[float, Heatmap | None]] = []
    for k, h in enumerate(heights):
        if check is not None:
            check()
        drawn = k == first or all_heights
        out.append((h, heatmap_image(result, h, kind=kind, look=look, canvas=canvas)
                       if drawn else None))
    return out
