"""The window's state to and from a project file (:mod:`maizeviz.io.project`); no Qt here.

A project holds the points (embedded, with their original path and hash), the layout (as a
layout document plus its ground cells, so a tiling keeps its exact ground area), the canopy
and light settings, and every light result of the comparison: sun, sky and day (transmission
by height, and the arrays that colour the canopy and draw the heatmaps; a sky's or day's in
:mod:`maizeviz_app.project_light`).

Opening uses the original points file when it is still there with the same content, and the
project's own copy otherwise (written to a cache folder, said to the user).
"""

from __future__ import annotations

import hashlib
import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.io.project import Project, ProjectError, Record, get, get_numbers, load_project

#: Settings groups of a project, as the window writes them.
CANOPY, LIGHT = "canopy", "light"


def light_record(label: str, result) -> Record:
    """One light result (a ``LightResult`` traced on the canopy labelled ``label``)."""
    meta = {"label": label, "level": result.level,
            "sun": {"zenith_deg": float(result.sun.zenith_deg),
                    "azimuth_deg": float(result.sun.azimuth_deg), "when": result.sun.when},
            "heights_cm": [float(h) for h in result.heights_cm],
            "transmission": [float(t) for t in result.transmission],
            "rays": int(result.rays), "rect": [float(v) for v in result.rect],
            "ray_area_cm2": float(result.ray_area_cm2), "density": float(result.density),
            "direction": [float(v) for v in result.direction],
            "seconds": {k: float(v) for k, v in result.seconds.items()},
            "warnings": [str(w) for w in result.warnings],
            "periodic": bool(getattr(result, "periodic", False))}
    arrays = {"first_z": np.asarray(result.first_z, np.float32)}
    for name, dtype in (("sensor_lit", np.uint8), ("sensor_offset_cm", np.float64)):
        a = getattr(result, name, None)
        if a is not None:
            arrays[name] = np.asarray(a, dtype)
    for name in ("first_hits", "second_hits"):
        a = getattr(result, name)
        if a is not None:
            arrays[name] = np.asarray(a, np.int32 if a.max(initial=0) < 2**31 else np.int64)
    return Record("light", meta, arrays)


def light_from_record(rec: Record, where: str) -> tuple[str, Any]:
    """(label, LightResult) from a stored record; refused with ProjectError if malformed."""
    from maizeviz.light.sun import Sun
    from maizeviz.light.transmission import LightResult

    m = rec.meta
    sun = get(m, "sun", dict, where=where)
    heights = get_numbers(m, "heights_cm", where=where)
    transmission = get_numbers(m, "transmission", where=where)
    rect = get_numbers(m, "rect", where=where)
    direction = get_numbers(m, "direction", where=where)
    rays = get(m, "rays", int, where=where)
    if len(heights) != len(transmission) or len(rect) != 4 or len(direction) != 3:
        raise ProjectError(f"{where}: a light result has inconsistent sizes; the project is "
                           "damaged")
    first_z = rec.arrays.get("first_z")
    if first_z is None or first_z.ndim != 1 or len(first_z) != rays:
        raise ProjectError(f"{where}: a light result's rays are missing or do not match; the "
                           "project is damaged")
    hits = {}
    for name in ("first_hits", "second_hits"):
        a = rec.arrays.get(name)
        if a is not None and (a.ndim != 1 or a.dtype.kind not in "iu"):
            raise ProjectError(f"{where}: '{name}' of a light result is not a list of counts")
        hits[name] = None if a is None else a.astype(np.int64)
    planes = {}
    lit, offset = rec.arrays.get("sensor_lit"), rec.arrays.get("sensor_offset_cm")
    if lit is not None:
        if lit.dtype != np.uint8 or lit.shape != (len(heights), -(-rays // 8)) or \
                offset is None or offset.shape != (len(heights), 2):
            raise ProjectError(f"{where}: a light result's sensor planes do not match its "
                               "heights and rays; the project is damaged")
        planes = {"sensor_lit": lit, "sensor_offset_cm": offset.astype(np.float64),
                  "periodic": bool(get(m, "periodic", bool, False, where))}
    try:
        result = LightResult(
            sun=Sun(float(get(sun, "zenith_deg", (int, float), where=where)),
                    float(get(sun, "azimuth_deg", (int, float), where=where)),
                    str(get(sun, "when", str, "", where=where))),
            heights_cm=np.array(heights), transmission=np.array(transmission), rays=rays,
            rect=tuple(rect), ray_area_cm2=float(get(m, "ray_area_cm2", (int, float),
                                                     where=where)),
            first_z=first_z.astype(np.float32), direction=np.array(direction),
            seconds={str(k): float(v) for k, v in get(m, "seconds", dict, {}, where).items()
                     if isinstance(v, (int, float))},
            warnings=tuple(str(w) for w in get(m, "warnings", list, [], where)),
            level=str(get(m, "level", str, "", where)),
            density=float(get(m, "density", (int, float), where=where)), **hits, **planes)
    except (ValueError, MaizevizError) as exc:     # e.g. a sun below the horizon
        raise ProjectError(f"{where}: a stored light result cannot be used ({exc})") from None
    return str(get(m, "label", str, result.level, where)), result


def layout_parts(layout) -> tuple[dict, dict[str, np.ndarray]]:
    """A layout as a document plus its ground arrays (cells, centre cells, ground area)."""
    from maizeviz.canopy.layout import layout_to_dict

    arrays = {"layout_cells": np.asarray(layout.cells, np.float64),
              "layout_centre_cells": np.asarray(layout.centre_cells, np.float64).reshape(-1, 4),
              "layout_ground_area": np.array([layout.ground_area_cm2], np.float64)}
    return layout_to_dict(layout), arrays


def layout_from_parts(doc: dict, arrays: dict[str, np.ndarray], plants: set[int], where: str):
    """The layout a project stored, validated like a layout file against the plants read."""
    from maizeviz.canopy.layout import layout_from_dict

    layout = layout_from_dict(doc, plants, f"{where}: layout")
    cells = arrays.get("layout_cells")
    centre = arrays.get("layout_centre_cells")
    area = arrays.get("layout_ground_area")
    if cells is None or centre is None or area is None:
        return layout
    ok = (cells.ndim == 2 and cells.shape[1:] == (4,) and len(cells) >= 1 and
          centre.ndim == 2 and centre.shape[1:] == (4,) and area.shape == (1,) and
          np.all(np.isfinite(cells)) and np.all(np.isfinite(centre)) and
          float(area[0]) > 0 and np.isfinite(area[0]))
    if not ok:
        raise ProjectError(f"{where}: the layout's ground cells are damaged")
    return replace(layout, cells=np.array(cells, np.float64),
                   centre_cells=np.array(centre, np.float64), ground_area=float(area[0]))


#: Record kind of a sun result (the only kind of maizeviz 0.2's projects).
SUN_KIND = "light"


class StoredRun(NamedTuple):
    """A light result read from a project: the level it was traced on, the result, its light
    (``kind``: sun, sky or day) and the light panel's settings it was computed with, as the
    window compares them (a ``SkySpec``, ``(DaySpec, SkySpec)``; None for a sun, or a day of
    a project that did not store them)."""

    label: str
    result: Any
    kind: str = "sun"
    settings: Any = None


def run_record(label: str, result, settings: dict | None = None) -> Record:
    """The record of any light result: a sun's ``LightResult``, a ``SkyLight`` or a
    ``PeriodLight`` (``settings``: the app's settings of a sky or day as JSON,
    :func:`~maizeviz_app.project_light.settings_doc`)."""
    from maizeviz_app import project_light

    rec = project_light.record_of(label, result, settings)
    return rec if rec is not None else light_record(label, result)


def make_project(points_path: str, points_bytes: bytes, layout, canopy: dict, light: dict,
                 runs: list[tuple]) -> Project:
    """The project of the window's state: ``runs`` are (label, result) or (label, result,
    settings) tuples, results of any light (see :func:`run_record`)."""
    doc, arrays = layout_parts(layout) if layout is not None else (None, {})
    return Project(points_bytes, str(points_path), doc, {CANOPY: canopy, LIGHT: light}, arrays,
                   tuple(run_record(*run) for run in runs))


def run_from_record(rec: Record, where: str) -> StoredRun | None:
    """The light result of a record, or None for a kind this maizeviz does not know."""
    from maizeviz_app import project_light as pl

    if rec.kind == SUN_KIND:
        return StoredRun(*light_from_record(rec, where))
    if rec.kind == pl.SKY_KIND:
        label, result, stored = pl.sky_from_record(rec, where)
        return StoredRun(label, result, "sky", pl.run_settings("sky", result, stored, where))
    if rec.kind == pl.DAY_KIND:
        label, result, stored = pl.day_from_record(rec, where)
        return StoredRun(label, result, "day", pl.run_settings("day", result, stored, where))
    return None


@dataclass
class Opened:
    """A project read and checked, ready for the window: the points file to load (the original
    or the project's copy), what to tell the user, settings and results."""

    path: str
    project: Project
    points_path: str
    shown_name: str
    notes: list[str] = field(default_factory=list)
    canopy: dict = field(default_factory=dict)
    light: dict = field(default_factory=dict)
    runs: list[StoredRun] = field(default_factory=list)


def open_project(path: str | Path, cache: str | Path | None = None) -> Opened:
    """Read a project and decide which points file to load.

    Raises
    ------
    ProjectError
        The project cannot be used (one line).
    """
    where = str(path)
    project = load_project(path)
    notes = []
    original = Path(project.points_path)
    digest = project.points_sha256
    points_path = None
    try:
        if original.is_file() and hashlib.sha256(original.read_bytes()).hexdigest() == digest:
            points_path = str(original)
    except OSError:
        points_path = None
    if points_path is None:
        folder = Path(cache) if cache else Path(tempfile.gettempdir()) / "maizeviz-projects"
        try:
            folder.mkdir(parents=True, exist_ok=True)
            copy = folder / f"{digest[:16]}-{original.name or 'points.csv'}"
            if not copy.exists():
                copy.write_bytes(project.points_csv)
        except OSError as exc:
            raise ProjectError(f"{where}: cannot unpack its points to {folder} "
                               f"({exc.strerror or exc})") from None
        points_path = str(copy)
        why = "has changed" if original.is_file() else "is not there"
        notes.append(f"the points file {original} {why}; using the copy saved in the project")
    settings = project.settings
    canopy = get(settings, CANOPY, dict, {}, where)
    light = get(settings, LIGHT, dict, {}, where)
    runs = []
    for i, rec in enumerate(project.results):
        run = run_from_record(rec, where)
        if run is None:
            notes.append(f"result {i + 1} is of a kind this maizeviz does not know "
                         f"('{rec.kind}'); left out")
            continue
        runs.append(run)
    shown = f"{original.name} (project {Path(path).name})"
    return Opened(where, project, points_path, shown, notes, canopy, light, runs)


def canopy_settings(opened: Opened) -> tuple[int, str, bool]:
    """Tiling, slider stop and area preservation stored in a project (checked)."""
    from maizeviz.mesh.levels import COMPLEXITY_STOPS

    c, where = opened.canopy, opened.path
    from maizeviz_app.options import TILINGS

    tile = get(c, "tile", int, 3, where)
    level = get(c, "level", str, "36", where)
    preserve = get(c, "preserve_area", bool, True, where)
    if tile not in TILINGS:
        raise ProjectError(f"{where}: tiling {tile} is not one the app offers "
                           f"({', '.join(map(str, TILINGS))})")
    if level not in COMPLEXITY_STOPS:
        raise ProjectError(f"{where}: mesh level '{level}' is not one of the slider's "
                           f"({', '.join(COMPLEXITY_STOPS)})")
    return tile, level, preserve


#: Light settings a project may hold, with their JSON types: the sun's (the first six, all a
#: project of maizeviz 0.2 has), then the light chosen (``mode``: sun, sky or day), the sky's
#: and the day's. A project without the later ones opens in sun mode with the defaults.
LIGHT_SETTINGS = (("zenith_deg", (int, float)), ("azimuth_deg", (int, float)), ("place", str),
                  ("heights", str), ("density", (int, float)), ("periodic", bool),
                  ("mode", str), ("sky_kind", str), ("sky_split", str),
                  ("sky_directions", int), ("day_date", str), ("latitude", (int, float)),
                  ("longitude", (int, float)), ("tz", str), ("step_min", (int, float)),
                  ("from", str), ("to", str), ("source", str),
                  ("linke_turbidity", (int, float)), ("weather", str),
                  ("par_factor", (int, float)))
#: Allowed values of the light settings that name a choice.
LIGHT_CHOICES = {"mode": ("sun", "sky", "day"), "sky_kind": ("soc", "uoc"),
                 "sky_split": ("auto", "equal"), "source": ("clear", "weather")}


def light_settings(opened: Opened) -> dict:
    """Light settings stored in a project, checked field by field (keys it does not know are
    left out: a newer maizeviz may store more)."""
    s, where = opened.light, opened.path
    out = {}
    for key, kind in LIGHT_SETTINGS:
        if key in s:
            out[key] = get(s, key, kind, where=where)
            allowed = LIGHT_CHOICES.get(key)
            if allowed is not None and out[key] not in allowed:
                raise ProjectError(f"{where}: light setting '{key}' is '{out[key]}', not one "
                                   f"of {', '.join(allowed)}")
    return out
