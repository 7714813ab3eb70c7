"""The app's work, as plain functions over the core (no Qt): what worker threads and the core
process run.

Each function takes everything it needs and returns new objects; the window keeps the results
and drops stale ones by job id. Functions meant for the core process (:data:`OPS`) receive the
child's ``state`` (the canopy it holds, and the light engine keeping its Embree scenes) and a
``progress(done, total)`` callback.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from maizeviz.canopy.build import Canopy, build_canopy
from maizeviz.canopy.layout import CanopyLayout, layout_for
from maizeviz.canopy.measures import CanopyMeasures, measure_canopy
from maizeviz.errors import PointsFileError
from maizeviz.leaf.fit import Leaf, read_leaves
from maizeviz.light.engine import LightEngine
from maizeviz.light.results.direct import LightResult
from maizeviz.light.scene.request import LightRequest
from maizeviz.light.specs import DaySpec, OpticsSpec, SkySpec  # noqa: F401 - the app's names
from maizeviz.mesh.levels import parse_level
from maizeviz.progress import ProgressCallback

#: Pixel edge (cm) of the ground-cover grid in the app (the CLI's default is 0.5 cm).
APP_COVER_RESOLUTION_CM = 1.0


@dataclass(frozen=True)
class Loaded:
    """A points file read, gridded and fitted, and where its plants stand.

    Attributes
    ----------
    path : the file read (for a project: the file on disk or the project's copy of it)
    leaves : fitted leaves; skipped : leaves refused (errors naming plant, leaf, row, col)
    layout : where the plants stand; warnings : lines for the user (repairs, notes)
    shown_name : how the file is named to the user
    """

    path: str
    leaves: list[Leaf]
    skipped: list
    layout: CanopyLayout
    warnings: tuple[str, ...]
    shown_name: str = ""

    @property
    def plants(self) -> set[int]:
        return {lf.grid.plant for lf in self.leaves}


def load_points(path: str, tile: tuple[int, int] = (3, 3), row_spacing: float = 60.0,
                plant_spacing: float = 30.0, shown_name: str = "",
                layout: CanopyLayout | None = None) -> Loaded:
    """Read, grid and fit a points file; lay it out as ``layout`` or tiled ``tile`` times."""
    found = read_leaves(path)
    if not found.leaves:
        # what the command line says before 'no leaf could be processed': why, with its line
        first = [str(e) for e in found.skipped] + list(found.problems)
        more = len(first) - 1
        raise PointsFileError(f"{shown_name or path}: no leaf could be reconstructed"
                              + (f": {first[0]}" if first else "")
                              + (f" (and {more:,} more)" if more > 0 else ""))
    if layout is None:
        layout = layout_for(found.leaves, tile, row_spacing, plant_spacing)
    return Loaded(str(path), found.leaves, found.skipped, layout,
                  tuple(found.problems) + tuple(found.notes) + tuple(layout.warnings),
                  shown_name or str(path))


@dataclass(frozen=True)
class Built:
    """A canopy at one level with its Table 2 measures.

    Attributes
    ----------
    polydata : what the viewport draws, prepared off the GUI thread
    columns, row : Table 2's column names and this canopy's row
    serial : the points loaded when the canopy was asked for (a newer load makes it stale)
    """

    level: str
    label: str
    canopy: Canopy
    measures: CanopyMeasures
    build_s: float
    measure_s: float
    polydata: Any = None
    columns: tuple[tuple[str, str], ...] = ()
    row: Any = None
    serial: int = -1


def build(loaded: Loaded, level_text: str, preserve_area: bool,
          progress: ProgressCallback | None = None) -> tuple[Canopy, float, str]:
    """The canopy at a level: (canopy, seconds, the level's label in Table 2)."""
    level = parse_level(level_text)
    t0 = time.perf_counter()
    canopy = build_canopy(loaded.leaves, loaded.layout, level, preserve_area, progress)
    return canopy, time.perf_counter() - t0, level.variant_label(preserve_area)


# ------------------------------------------------------------------ in the core process
def op_measure(state: dict, progress: ProgressCallback, cover_resolution: float) -> CanopyMeasures:
    """Table 2 measures of the child's canopy (ground cover traces an Embree scene)."""
    return measure_canopy(state["canopy"], cover_resolution=cover_resolution)


def _engine(state: dict, stalks: bool = True) -> LightEngine:
    """The child's light engine over its canopy, with its stalks traced or not (``stalks``:
    ``LightEngine(with_stalks=...)``, the command line's ``--leaves-only`` when False): each
    builds its Embree scenes once and keeps them (and the last sky light) for every later
    sun, sky or day of the same choice."""
    engines = state.setdefault("engines", {})
    if stalks not in engines:
        engines[stalks] = LightEngine(state["canopy"], with_stalks=stalks)
    return engines[stalks]


def op_light(state: dict, progress: ProgressCallback, request: LightRequest,
             stalks: bool = True) -> LightResult:
    """Trace the sun through the child's canopy (on the scene its engine keeps; the result's
    ``seconds["build"]`` is 0 when the scene was kept from an earlier run); the stalks take
    light with ``stalks``."""
    return _engine(state, stalks).sun(request.sun, sampling=request.sampling,
                                      classes=request.classes, progress=progress)


def op_absorbed(state: dict, progress: ProgressCallback, request: LightRequest,
                spec: OpticsSpec, stalks: bool = True) -> Absorbed:
    """Light absorbed with scattering for the request's sun, on the engine's scene (the
    stalks' with ``stalks``), with what the window shows of it: each leaf's absorbed W per
    m2 of leaf on its triangles (copies of a plant in a periodic field take their
    representative's; NaN on plants outside the sample rectangle of an open field) and the
    plants' rows."""
    light = spec.absorbed(_engine(state, stalks), request.sun, request.sampling, progress)
    return absorbed_of(state["canopy"], light, spec)


def absorbed_of(canopy, light, spec: OpticsSpec | None = None) -> Absorbed:
    """What the window shows of absorbed light (an ``AbsorbedLight``) on the canopy it was
    traced on (also for a result read from a project); with a leaf model in ``spec``
    (``OpticsSpec.photosynthesis``), also the leaves' gross CO2 assimilation: each leaf's
    umol CO2 per m2 of leaf per s on its triangles (``gross_value``) and the plants' rows
    gaining ``gross_umol_s`` and its standard error ``gross_umol_s_se``."""
    from maizeviz.light.report.tables import leaf_values
    values = leaf_values(canopy, light.leaf_rows(canopy), "absorbed_w", light.rect,
                         light.periodic)
    frame = light.table("plant", canopy)
    assimilation = spec.assimilation(canopy, light) if spec is not None else None
    gross = None
    if assimilation is not None:
        leaves = assimilation.table("leaf", canopy)
        gross = leaf_values(canopy, leaves.to_dict("records"), "gross_umol_s", light.rect,
                            light.periodic).astype(np.float32)
        plants = assimilation.table("plant", canopy)[["instance", "gross_umol_s",
                                                      "gross_umol_s_se"]]
        frame = frame.merge(plants, on="instance", how="left").fillna(
            {"gross_umol_s": 0.0, "gross_umol_s_se": 0.0})
    return Absorbed(light, values.astype(np.float32), frame.to_dict("records"), assimilation,
                    gross)


@dataclass(frozen=True)
class Absorbed:
    """Absorbed light (:class:`maizeviz.light.results.absorbed.AbsorbedLight`) with what the window
    shows of it: ``leaf_value`` (F,) float32 W absorbed per m2 of leaf on each leaf triangle
    (its leaf's), and ``plant_rows`` (the result's ``table("plant")`` as records); both None
    for a result read from a project until computed against its canopy. With a leaf model:
    ``assimilation`` (:class:`maizeviz.light.results.assimilation.Assimilation`) and
    ``gross_value`` (F,) float32, each leaf's gross umol CO2 per m2 of leaf per s on its
    triangles."""

    light: Any
    leaf_value: np.ndarray | None
    plant_rows: list | None
    assimilation: Any = None
    gross_value: np.ndarray | None = None


@dataclass(frozen=True)
class Diffuse:
    """A sky or period result with what the window shows of it, made in the child: per-leaf
    rows (``leaf_rows``), per-plant rows (``plant_rows``), and each leaf triangle's value for
    colouring the canopy (``leaf_value`` (F,) float32: its leaf's light per unit leaf area;
    a day: PAR mol per m2 of leaf; a sky: the leaf's mean diffuse irradiance as a fraction of
    the sky's on open ground)."""

    light: Any
    leaf_rows: list
    plant_rows: list
    leaf_value: Any
    build_s: float = 0.0


def _diffuse(state: dict, light, rows: list, column: str, build_s: float) -> Diffuse:
    import numpy as np

    from maizeviz.light.report.tables import leaf_values
    from maizeviz.light.results.per_leaf import plant_light

    values = leaf_values(state["canopy"], rows, column, light.rect, light.periodic)
    if column == "diffuse_intercepted_cm2":
        values *= 1e-4          # cm2 of ground per m2 of leaf -> per unit leaf area
    return Diffuse(light, rows, plant_light(rows), values.astype(np.float32), build_s)


def diffuse_of(canopy, light, kind: str) -> Diffuse:
    """What the window shows of a sky (``kind`` "sky") or day ("day") result on the canopy it
    was traced on, as :func:`op_sky` and :func:`op_period` make it (for a result read from a
    project)."""
    state = {"canopy": canopy}
    build_s = float(light.seconds.get("build", 0.0))
    if kind == "sky":
        return _diffuse(state, light, light.leaf_rows(canopy), "diffuse_intercepted_cm2",
                        build_s)
    return _diffuse(state, light, light.leaf_rows(canopy), "par_intercepted_mol",
                    build_s)


def op_sky(state: dict, progress, sampling, spec: SkySpec, stalks: bool = True) -> Diffuse:
    """Diffuse light under a sky (one scene, every direction traced like the sun; the stalks
    take light with ``stalks``); the engine keeps the result, so a day on the same canopy,
    sampling, sky and stalks reuses it."""
    def steps(done: int, total: int):
        return progress(done, total, f"sky direction {done} of {total}")

    light = _engine(state, stalks).sky(spec.sky(), sampling=sampling, progress=steps)
    return _diffuse(state, light, light.leaf_rows(state["canopy"]),
                    "diffuse_intercepted_cm2", light.seconds["build"])


def op_period(state: dict, progress, sampling, sky: SkySpec, day: DaySpec,
              stalks: bool = True) -> Diffuse:
    """Light over a day: the sun traced at every step, the sky once (or the sky light the
    engine kept from a sky run with the same settings); the stalks take light with
    ``stalks``."""
    period = day.period()
    engine = _engine(state, stalks)
    perez = day.diffuse == "perez"             # the sky's directions, as a uniform sky
    sky_obj = SkySpec("uoc", sky.directions, sky.split).sky() if perez else sky.sky()
    n_sky = 0 if engine.kept_sky(sky_obj, sampling) is not None else sky_obj.n

    def steps(done: int, total: int):
        if done <= n_sky:
            return progress(done, total, f"sky direction {done} of {n_sky}")
        return progress(done, total, f"time step {done - n_sky} of {total - n_sky}")

    light = engine.day(period, sky="perez" if perez else sky_obj, directions=sky_obj.n,
                       sampling=sampling, progress=steps)
    return _diffuse(state, light, light.leaf_rows(state["canopy"]),
                    "par_intercepted_mol", light.seconds["build"])


def op_ping(state: dict, progress: ProgressCallback) -> str:
    return "pong"


OPS: dict[str, Callable[..., Any]] = {"measure": op_measure, "light": op_light, "sky": op_sky,
                                      "period": op_period, "absorbed": op_absorbed,
                                      "ping": op_ping}
