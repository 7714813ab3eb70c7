"""Colour scales of the views, without Qt: what range of values the colours span, which colour
map, linear or log, and turning values into colours.

Each view has a :class:`ColourScale` (an evented dataclass, as napari's layer contrast limits
and colormap are evented fields of the layer): the 3D view's light colouring and the light
heatmaps. :class:`ColourSettings` holds both, with whether the heatmaps of every height and
light shown share one scale, and how a sun's light is painted on the canopy
(:data:`PAINTINGS`). A project saves them (:meth:`ColourSettings.to_doc`) and reads them back
(:meth:`ColourSettings.update_from_doc`; a project without them opens with the defaults).

The colours themselves are computed here with numpy (:func:`colours_of`): values in, RGB out,
with their own colours for values that are not light (stalks, triangles not traced), so that
a clipped range clamps leaves to the ends of the map without painting them as stalks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from psygnal import evented

if TYPE_CHECKING:
    from psygnal import SignalGroup

#: JSON types of the scale's fields, by their annotation.
_KINDS: dict[str, type | tuple[type, ...]] = {"float": (int, float), "bool": bool, "str": str}

#: Colour maps offered: name -> matplotlib's name. "greys" runs from black (least) to white
#: (most), as light does (matplotlib's "Greys" runs the other way).
CMAPS = {"viridis": "viridis", "cividis": "cividis", "inferno": "inferno", "greys": "gray"}
#: How the range is chosen: name -> what the panel says.
RANGES = {"auto": "auto (min to max)", "fixed": "typed min and max",
          "percentile": "percentile clip"}
#: How a sun's light is painted on the canopy: the light class of each triangle, the sunlit
#: share of each leaf, or whichever is honest for the triangles' size (see
#: :func:`maizeviz.light.results.painting.sun_painting`).
PAINTINGS = {"auto": "auto (honest for the triangles' size)",
             "triangles": "per triangle: light class", "leaves": "per leaf: sunlit share"}


class ColourError(ValueError):
    """A colour setting that cannot be used; the message names the setting and the value."""


@evented
@dataclass
class ColourScale:
    """The colours of one view.

    Attributes
    ----------
    range : ``auto`` (the finite values' min to max), ``fixed`` (``vmin`` to ``vmax``) or
        ``percentile`` (``clip`` % of the values left out at each end)
    vmin, vmax : the typed range, in the view's unit (``fixed``)
    clip : percent clipped at each end (``percentile``), 0 to 49
    cmap : a key of :data:`CMAPS`
    log : colours spaced by the logarithm of the value (values of 0 or less take the lowest
        colour; the lower end of the range is the smallest positive value)
    """

    if TYPE_CHECKING:
        events: ClassVar[SignalGroup]

    range: str = "auto"
    vmin: float = 0.0
    vmax: float = 1.0
    clip: float = 2.0
    cmap: str = "viridis"
    log: bool = False

    def check(self) -> None:
        """Raise :class:`ColourError` naming a setting that cannot be used."""
        if self.range not in RANGES:
            raise ColourError(f"colour range '{self.range}' is not one of "
                              f"{', '.join(RANGES)}")
        if self.cmap not in CMAPS:
            raise ColourError(f"colour map '{self.cmap}' is not one of {', '.join(CMAPS)}")
        if not (math.isfinite(self.vmin) and math.isfinite(self.vmax)):
            raise ColourError(f"colour range {self.vmin} to {self.vmax}: give finite numbers")
        if self.vmin >= self.vmax:
            raise ColourError(f"colour range: the minimum ({self.vmin:g}) must be below the "
                              f"maximum ({self.vmax:g})")
        if self.range == "fixed" and self.log and self.vmin <= 0:
            raise ColourError(f"colour range: a log scale needs a minimum above 0, got "
                              f"{self.vmin:g}")
        if not 0 <= self.clip < 50:
            raise ColourError(f"percentile clip {self.clip:g} %: give 0 to 49 % at each end")

    def limits(self, values: np.ndarray) -> tuple[float, float]:
        """The (low, high) the colours span for ``values`` (any shape; NaN and infinite
        values ignored), low < high; (0, 1) when there is nothing to span."""
        self.check()
        if self.range == "fixed":
            return float(self.vmin), float(self.vmax)
        v = np.asarray(values, dtype=np.float64).ravel()
        v = v[np.isfinite(v)]
        if self.log:
            v = v[v > 0]
        if not len(v):
            return (0.1, 1.0) if self.log else (0.0, 1.0)
        if self.range == "percentile" and self.clip > 0:
            lo, hi = np.percentile(v, [self.clip, 100 - self.clip])
        else:
            lo, hi = v.min(), v.max()
        return _spread(float(lo), float(hi), self.log)

    def to_doc(self) -> dict[str, Any]:
        """The settings as JSON values (for a project)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    def update_from_doc(self, doc: dict, where: str = "project") -> None:
        """Take the settings of ``doc`` (keys it lacks keep their value; unknown keys are left
        out: a newer maizeviz may store more); ColourError naming ``where`` for a value of the
        wrong type or out of range, and then nothing changes."""
        if not isinstance(doc, dict):
            raise ColourError(f"{where}: colour settings must be a JSON object")
        new: dict[str, Any] = {}
        for f in fields(self):
            if f.name not in doc:
                continue
            value: Any = doc[f.name]
            kind = _KINDS[str(f.type)]
            if isinstance(value, bool) and kind is not bool or not isinstance(value, kind):
                raise ColourError(f"{where}: colour setting '{f.name}' is {value!r}, not a "
                                  f"{str(f.type).replace('str', 'text')}")
            new[f.name] = value if kind in (bool, str) else float(doc[f.name])
        trial = ColourScale(**{**self.to_doc(), **new})
        try:
            trial.check()
        except ColourError as exc:
            raise ColourError(f"{where}: {exc}") from None
        with self.events.paused():
            for name, value in new.items():
                setattr(self, name, value)


def _spread(lo: float, hi: float, log: bool) -> tuple[float, float]:
    """A range around equal ends (every value the same): the colour in the middle."""
    if hi > lo:
        return lo, hi
    if log:
        return lo / 2, hi * 2
    pad = max(abs(lo) * 0.05, 1e-9)
    return lo - pad, hi + pad


@evented
@dataclass
class ColourSettings:
    """What a project keeps of how the views colour light (the scales are objects of their
    own, evented: connect to ``settings.view.events`` and ``settings.heatmap.events``).

    Attributes
    ----------
    shared : the heatmaps of every height and every light shown share one scale (its range
        taken over all of them), so colours compare across heights and lights
    painting : how a sun's light is painted on the canopy, a key of :data:`PAINTINGS`
    """

    if TYPE_CHECKING:
        events: ClassVar[SignalGroup]

    shared: bool = False
    painting: str = "auto"

    def __post_init__(self) -> None:
        self.view = ColourScale(cmap="inferno")
        self.heatmap = ColourScale(cmap="viridis")

    def to_doc(self) -> dict[str, Any]:
        return {"view": self.view.to_doc(), "heatmap": self.heatmap.to_doc(),
                "shared": self.shared, "painting": self.painting}

    def update_from_doc(self, doc: dict, where: str = "project") -> None:
        """Settings read from a project (``{}``, an older project's: the defaults); a value
        that cannot be used is a ColourError naming ``where`` and nothing changes."""
        if not isinstance(doc, dict):
            raise ColourError(f"{where}: view settings must be a JSON object")
        shared = doc.get("shared", False)
        painting = doc.get("painting", "auto")
        if not isinstance(shared, bool):
            raise ColourError(f"{where}: view setting 'shared' is {shared!r}, not true or "
                              "false")
        if painting not in PAINTINGS:
            raise ColourError(f"{where}: view setting 'painting' is {painting!r}, not one of "
                              f"{', '.join(PAINTINGS)}")
        defaults = ColourSettings()
        view, heat = ColourScale(**self.view.to_doc()), ColourScale(**self.heatmap.to_doc())
        view.update_from_doc({**defaults.view.to_doc(), **doc.get("view", {})},
                             f"{where}: 3D view colours")
        heat.update_from_doc({**defaults.heatmap.to_doc(), **doc.get("heatmap", {})},
                             f"{where}: heatmap colours")
        self.view.update_from_doc(view.to_doc())
        self.heatmap.update_from_doc(heat.to_doc())
        self.shared = shared
        self.painting = painting


def colour_table(cmap: str, n: int = 256) -> np.ndarray:
    """The colour map ``cmap`` (a key of :data:`CMAPS`) as (n, 3) uint8 RGB, low to high."""
    if cmap not in CMAPS:
        raise ColourError(f"colour map '{cmap}' is not one of {', '.join(CMAPS)}")
    from matplotlib import colormaps

    rgba = colormaps[CMAPS[cmap]](np.linspace(0.0, 1.0, n))
    return np.round(rgba[:, :3] * 255).astype(np.uint8)


def normalised(values: np.ndarray, lo: float, hi: float, log: bool = False) -> np.ndarray:
    """``values`` placed in [0, 1] between ``lo`` and ``hi`` (clamped; log-spaced with
    ``log``, where values of 0 or less are 0); NaN stays NaN."""
    v = np.asarray(values, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        if log:
            t = (np.log10(np.where(v > 0, v, lo)) - math.log10(lo)) / \
                (math.log10(hi) - math.log10(lo))
        else:
            t = (v - lo) / (hi - lo)
    return np.where(np.isnan(v), np.nan, np.clip(t, 0.0, 1.0))


def colours_of(values: np.ndarray, lo: float, hi: float, table: np.ndarray, log: bool = False,
               special: dict[float, tuple[int, int, int]] | None = None,
               nan: tuple[int, int, int] = (200, 200, 200)) -> np.ndarray:
    """RGB (n, 3) uint8 of ``values`` (n,) on the colour ``table`` ((m, 3) uint8, low to
    high) between ``lo`` and ``hi``; a value that is a key of ``special`` takes its colour
    (stalks), NaN takes ``nan`` (not traced)."""
    v = np.asarray(values, dtype=np.float64)
    t = normalised(v, lo, hi, log)
    index = np.round(np.nan_to_num(t) * (len(table) - 1)).astype(np.intp)
    out = table[index]
    out[np.isnan(v)] = nan
    for value, rgb in (special or {}).items():
        out[v == value] = rgb
    return out


def tick_text(value: float) -> str:
    """A colour-bar end as people read it: 3 significant digits."""
    return f"{value:.3g}"
