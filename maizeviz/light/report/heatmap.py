"""Transmission maps: binned transmission over a sensor plane (the sample rectangle raised to a
height, in its own x, y), as a matplotlib figure, PNG and CSV (matplotlib's Agg canvas: no GUI
toolkit; the app shows the same figure)."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import TYPE_CHECKING, TypeAlias, cast

import numpy as np

from maizeviz.io.atomic import atomic_open, atomic_path, file_tag, make_folder
from maizeviz.light.results.direct import LightResult
from maizeviz.light.results.maps import TransmissionMap, bin_edges, binned
from maizeviz.light.sources.sky import SKY_KINDS

if TYPE_CHECKING:                                   # matplotlib is imported when drawing
    from matplotlib.figure import Figure

    from maizeviz.light.results.diffuse import PeriodLight, SkyLight

    AnyLight: TypeAlias = LightResult | SkyLight | PeriodLight

#: The kinds of light results mapped (the app calls a period a ``day``), and the file-name
#: prefix of each kind's maps.
MAP_PREFIXES = {"sun": "transmission", "sky": "diffuse", "period": "period", "day": "period"}


def transmission_map(result: LightResult, height: float, bin_cm: float = 5.0) -> TransmissionMap:
    """Binned transmission on the sensor plane at ``height`` (one of the traced heights), in the
    rectangle's own x, y."""
    xe, ye = bin_edges(result.rect, bin_cm)
    k = result.height_index(height)
    counts, lit = binned(result.sensor_xy(k), result.lit(k), xe, ye)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(counts > 0, lit / counts, np.nan)
    return TransmissionMap(float(result.heights_cm[k]), xe, ye, t, counts.astype(np.int64),
                           float(result.transmission[k]))


def heatmap_figure(tmap: TransmissionMap, result: LightResult | None = None,
                   width_in: float = 8.0, dpi: float = 110, title: str | None = None,
                   what: str = "direct-light transmission", *, vmin: float = 0.0,
                   vmax: float = 1.0, cmap: str = "viridis", log: bool = False,
                   fit: tuple[float, float] | None = None, font_pt: float = 9.5) -> Figure:
    """A figure of one map: colour bar, axes in cm; the title names the sun angles, level and
    rays of ``result``, or is ``title`` (the first line always names ``what``, the height and
    the plane's total). The colours span ``vmin`` to ``vmax`` (values outside take the end
    colours) on matplotlib's colour map ``cmap``, spaced by the logarithm with ``log``
    (``vmin`` > 0; values of 0 take the lowest colour); bins no ray reached stay blank.

    ``fit`` (width, height), inches: the figure made that size, for a canvas of its own
    (``width_in`` ignored) with matplotlib's constrained layout and every text at ``font_pt``
    points; where it is small the labels are shortened, the second title line dropped
    (below :data:`FULL_TITLE_IN`) and the ticks fewer (one per :data:`TICK_SPACING_IN`), so
    that what is drawn stays readable at its own size rather than shrunk to fit."""
    from matplotlib.colors import LogNorm, Normalize
    from matplotlib.figure import Figure

    if not vmin < vmax or log and vmin <= 0:
        raise ValueError(f"colour range {vmin:g} to {vmax:g} is not increasing"
                         + (" and above 0 (log scale)" if log else ""))

    xe, ye = tmap.x_edges, tmap.y_edges
    aspect = (ye[-1] - ye[0]) / (xe[-1] - xe[0])
    if fit is None:
        fig = Figure(figsize=(width_in, width_in * aspect * 0.8 + 0.2 * width_in), dpi=dpi)
        small, fonts = False, {"title": 9.0}
    else:
        from matplotlib.layout_engine import ConstrainedLayoutEngine

        fig = Figure(figsize=fit, dpi=dpi,
                     layout=ConstrainedLayoutEngine(w_pad=2 / 72, h_pad=2 / 72))
        small = fit[1] < FULL_TITLE_IN or fit[0] < FULL_TITLE_IN
        fonts = {"title": font_pt, "label": font_pt, "ticks": font_pt}
    ax = fig.add_subplot()
    norm = LogNorm(vmin, vmax, clip=True) if log else Normalize(vmin, vmax)
    values = tmap.transmission.T
    if log:                                  # 0 is no light: the lowest colour, not blank
        values = np.where(values <= 0, vmin, values)
    im = ax.pcolormesh(xe, ye, values, norm=norm, cmap=cmap, shading="flat")
    ax.set_aspect("equal")
    ax.set_xlabel("x (cm)" if small else "x (cm, across rows)", fontsize=fonts.get("label"))
    ax.set_ylabel("y (cm)" if small else "y (cm, along rows)", fontsize=fonts.get("label"))
    if title is None and result is not None:
        title = map_title(result, "sun", (xe[-1] - xe[0]) / max(len(xe) - 1, 1))[1]
    import textwrap

    head = f"{what} at {tmap.height_cm:g} cm: {tmap.total:.3f}"
    if fit is None:
        ax.set_title(head + ("\n" + "\n".join(textwrap.wrap(title, 95)) if title else ""),
                     fontsize=fonts["title"])
    else:
        # over the whole figure (the map and its colour bar sit to one side of it), wrapped
        # to the figure's width at the font's size
        chars = max(int(fit[0] * 72 / (0.55 * font_pt)), 20)
        lines = textwrap.wrap(head, chars) + \
            (textwrap.wrap(title, chars) if title and not small else [])
        fig.suptitle("\n".join(lines), fontsize=fonts["title"])
    bar = fig.colorbar(im, ax=ax, shrink=0.8 if fit is None else 1.0,
                       label="transmission" if small else
                       "transmission (fraction of the light reaching this height)",
                       extend=_extend(tmap.transmission, vmin, vmax))
    if fit is None:
        fig.tight_layout()
        return fig
    from matplotlib.ticker import MaxNLocator

    bar.ax.yaxis.label.set_fontsize(fonts["label"])
    bar.ax.tick_params(labelsize=fonts["ticks"])
    ax.tick_params(labelsize=fonts["ticks"])
    # a tick per TICK_SPACING_IN of the map's room at most: labels that do not crowd
    ax.xaxis.set_major_locator(MaxNLocator(max(int(fit[0] / TICK_SPACING_IN / 2), 2)))
    ax.yaxis.set_major_locator(MaxNLocator(max(int(fit[1] / TICK_SPACING_IN), 2)))
    if not log:
        bar.locator = MaxNLocator(max(int(fit[1] / TICK_SPACING_IN), 2))
        bar.update_ticks()
    return fig


#: Below this width or height (inches) a fitted heatmap (``fit``) keeps one title line and
#: short axis and colour-bar labels.
FULL_TITLE_IN = 4.0
#: Room (inches) per tick label along a fitted heatmap's axes.
TICK_SPACING_IN = 0.5


def _extend(values: np.ndarray, vmin: float, vmax: float) -> str:
    """Which ends of the colour bar get an arrow: values lie beyond them (clipped)."""
    v = values[np.isfinite(values)]
    low, high = bool(len(v) and v.min() < vmin), bool(len(v) and v.max() > vmax)
    return {(False, False): "neither", (True, False): "min", (False, True): "max",
            (True, True): "both"}[(low, high)]


def write_map_csv(path: str | Path, tmap: TransmissionMap) -> None:
    """One line per bin: x_cm, y_cm (bin centre), height_cm, transmission (empty if no ray),
    rays (atomically)."""
    xc = 0.5 * (tmap.x_edges[1:] + tmap.x_edges[:-1])
    yc = 0.5 * (tmap.y_edges[1:] + tmap.y_edges[:-1])
    with atomic_open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["x_cm", "y_cm", "height_cm", "transmission", "rays"])
        t = tmap.transmission
        for i, x in enumerate(xc):
            for j, y in enumerate(yc):
                w.writerow([f"{x:.2f}", f"{y:.2f}", f"{tmap.height_cm:g}",
                            "" if np.isnan(t[i, j]) else f"{t[i, j]:.4f}", int(tmap.rays[i, j])])


def save_figure(fig: Figure, path: str | Path) -> None:
    """Save a figure as PNG (or the format of the extension), atomically."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=Path(path).suffix.lstrip(".") or "png")


def map_title(result: AnyLight, kind: str, bin_cm: float = 5.0) -> tuple[str, str]:
    """(what is mapped, the second title line) of the maps of a sun's ``LightResult``
    (``kind`` sun; ``bin_cm``, the bin named in the title), a ``SkyLight`` (sky) or a
    ``PeriodLight`` (period, or day)."""
    _check_kind(kind)
    if kind == "sun":
        sun_res = cast(LightResult, result)
        sun = sun_res.sun
        return ("direct-light transmission",
                f"sun zenith {sun.zenith_deg:.1f} deg, azimuth {sun.azimuth_deg:.1f} deg; "
                f"level {result.level}; {sun_res.rays:,} sensors, {bin_cm:.3g} cm bins")
    if kind == "sky":
        sky_res = cast("SkyLight", result)
        sky = sky_res.sky
        return ("diffuse transmission",
                f"{SKY_KINDS[sky.kind].split(',')[0]}, {sky.split} split of {sky.n} "
                f"directions; level {result.level}; {sky_res.rays:,} sensors per direction")
    p = cast("PeriodLight", result).period
    return ("fraction of the period's PAR",
            f"{p.start:%Y-%m-%d %H:%M} to {p.end:%Y-%m-%d %H:%M}, {p.n_steps} steps; "
            f"level {result.level}")


def _check_kind(kind: str) -> None:
    if kind not in MAP_PREFIXES:
        raise ValueError(f"unknown kind of light result {kind!r} (one of "
                         f"{', '.join(MAP_PREFIXES)})")


def result_map(result: AnyLight, height: float, kind: str = "sun",
               bin_cm: float = 5.0) -> TransmissionMap:
    """The map of one traced height of a light result: a sun's binned in ``bin_cm`` bins, a
    sky's or a period's as binned when traced."""
    _check_kind(kind)
    if kind == "sun":
        return transmission_map(cast(LightResult, result), float(height), bin_cm)
    return cast("SkyLight | PeriodLight", result).transmission_map(float(height))


def result_figure(result: AnyLight, height: float, kind: str = "sun", bin_cm: float = 5.0,
                  width_in: float = 8.0, dpi: float = 110,
                  tmap: TransmissionMap | None = None, **colours) -> Figure:
    """The figure of one height of a light result (:func:`result_map`, or ``tmap`` when
    already made), titled by :func:`map_title`; ``colours``: :func:`heatmap_figure`'s
    ``vmin``, ``vmax``, ``cmap``, ``log`` (and its ``fit``, ``font_pt``)."""
    tmap = result_map(result, height, kind, bin_cm) if tmap is None else tmap
    if kind == "sun":
        return heatmap_figure(tmap, cast(LightResult, result), width_in=width_in, dpi=dpi,
                              **colours)
    what, title = map_title(result, kind)
    return heatmap_figure(tmap, width_in=width_in, dpi=dpi, title=title, what=what, **colours)


def heatmap_stems(result: AnyLight, kind: str = "sun") -> list[str]:
    """Distinct file stems of a result's maps, one per height (see :func:`map_stems`)."""
    return map_stems(kind, result.level, result.heights_cm)


def map_stems(kind: str, level: str, heights_cm) -> list[str]:
    """Distinct file stems, one per height of ``heights_cm`` (cm) at the mesh level labelled
    ``level``: ``transmission_<level>_h<height>cm`` (a sun's maps), ``diffuse_...`` (a sky's)
    or ``period_...`` (a period's). Known before anything is traced, so output names can be
    checked first."""
    _check_kind(kind)
    level = file_tag(level) or "level"
    stems: list[str] = []
    for h in heights_cm:
        stem = f"{MAP_PREFIXES[kind]}_{level}_h{h:g}cm".replace(".", "p")
        while stem in stems:                         # heights equal to %g precision
            stem += "_"
        stems.append(stem)
    return stems


def write_heatmaps(folder: str | Path, result: AnyLight, bin_cm: float = 5.0,
                   kind: str = "sun") -> list[Path]:
    """One PNG and one CSV per height of a light result (``kind`` as for :func:`map_title`)
    in ``folder`` (created if needed); returns the paths written, PNG and CSV alternating."""
    _check_kind(kind)
    folder = make_folder(folder)
    written = []
    for h, stem in zip(result.heights_cm, heatmap_stems(result, kind)):
        tmap = result_map(result, float(h), kind, bin_cm)
        png, csv_path = folder / f"{stem}.png", folder / f"{stem}.csv"
        save_figure(result_figure(result, float(h), kind, tmap=tmap), png)
        write_map_csv(csv_path, tmap)
        written += [png, csv_path]
    return written
