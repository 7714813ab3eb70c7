"""The window's state to and from a project file; no Qt here.

What a project holds and how it is read is the core's (:mod:`maizeviz.project.study`: points,
layout with its stands in order, settings, and sun, sky and day results tagged with the stands
they were traced on); the sky and day specs of each result are the core's too
(:mod:`maizeviz.project.settings`). This module adds only what belongs to the window: the
checks of the settings the window offers (tilings, slider stops, light choices).
"""

from __future__ import annotations

from typing import Any, NamedTuple

from maizeviz.io.archive import ProjectError, get
from maizeviz.project.settings import run_settings, settings_doc  # noqa: F401 - re-exported
from maizeviz.project.study import CANOPY, LIGHT, Opened, StoredResult

__all__ = ["CANOPY", "LIGHT", "Opened", "StoredRun", "canopy_settings", "light_settings",
           "run_settings", "settings_doc", "stored_run", "view_settings"]


class StoredRun(NamedTuple):
    """A light result read from a project: the level it was traced on, the result, its light
    (``kind``: sun, sky or day) and the light panel's settings it was computed with, as the
    window compares them (a ``SkySpec``, ``(DaySpec, SkySpec)``; None for a sun, or a day of
    a project that did not store them)."""

    label: str
    result: Any
    kind: str = "sun"
    settings: Any = None


def stored_run(stored: StoredResult, where: str) -> StoredRun:
    """The window's run of a result read from a project (its settings as the panel's)."""
    return StoredRun(stored.label, stored.result, stored.kind, stored.specs(where))


def canopy_settings(opened: Opened) -> tuple[int, str, bool]:
    """Tiling, slider stop and area preservation stored in a project (checked)."""
    from maizeviz.mesh.levels import COMPLEXITY_STOPS
    from maizeviz_app.options import TILINGS

    c, where = opened.canopy, opened.path

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
                  ("mode", str), ("stalks", bool), ("sky_kind", str), ("sky_split", str),
                  ("sky_directions", int), ("day_date", str), ("latitude", (int, float)),
                  ("longitude", (int, float)), ("tz", str), ("step_min", (int, float)),
                  ("from", str), ("to", str), ("source", str),
                  ("linke_turbidity", (int, float)), ("weather", str),
                  ("par_factor", (int, float)), ("optics", bool), ("band", str),
                  ("reflectance", (int, float)), ("transmittance", (int, float)),
                  ("ground_reflectance", (int, float)), ("direct_w_m2", (int, float)),
                  ("diffuse_w_m2", (int, float)), ("depth", int), ("day_diffuse", str),
                  ("photosynthesis", str), ("leaf_temperature_c", (int, float)),
                  ("c4_vmax", (int, float)), ("c4_alpha", (int, float)),
                  ("co2_ppm", (int, float)), ("wofost_amax", (int, float)),
                  ("wofost_eff", (int, float)), ("c4_temperature", str))
#: Allowed values of the light settings that name a choice.
LIGHT_CHOICES = {"mode": ("sun", "sky", "day"), "sky_kind": ("soc", "uoc"),
                 "sky_split": ("auto", "equal"), "source": ("clear", "weather"),
                 "band": ("par", "nir"), "day_diffuse": ("sky", "perez"),
                 "photosynthesis": ("none", "c4", "wofost"),
                 "c4_temperature": ("collatz", "clm45")}


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


def view_settings(opened: Opened) -> dict:
    """How the views colour light, stored in a project (checked; ``{}`` in a project saved
    before colours were kept: the defaults); a value that cannot be used is a ProjectError."""
    from maizeviz_app.colour import ColourError, ColourSettings

    try:
        ColourSettings().update_from_doc(opened.view, opened.path)
    except ColourError as exc:
        raise ProjectError(str(exc)) from None
    return dict(opened.view)
