"""Light results to and from project records (:mod:`maizeviz.io.archive`).

A sun result (:class:`~maizeviz.light.results.direct.LightResult`) is stored as a ``light``
record (the only kind of maizeviz 0.2's projects), a sky result (:class:`~maizeviz.light.results.diffuse.SkyLight`) is stored as a ``light_sky`` record,
a day (:class:`~maizeviz.light.results.diffuse.PeriodLight`, its :class:`~maizeviz.light.sources.irradiance.
Period` and the sky light of its diffuse part) as a ``light_day`` record: JSON metadata
(numbers, text, times as ISO 8601 with their UTC offset, the time zone's name) and numeric
arrays; no pickle. Reading checks every size, type and value before the objects are made
through their constructors (so :class:`~maizeviz.light.sources.sky.Sky` and ``Period`` validate
themselves too); anything wrong is a :class:`~maizeviz.io.archive.ProjectError` naming it.

Each record may also hold the settings of that light as JSON (``settings``: the sky chosen, the
day's date and place), so a reopened comparison goes on as if the runs had just been made, and
the identity of the stands it was traced on (``stands``, :mod:`maizeviz.project.stands`), so
per-plant and per-leaf values are never shown on other plants.

The command line, sweeps and notebooks read these records as the app does:
:func:`run_from_record` turns any record into (label, result, kind, settings).
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import re
from dataclasses import replace
from typing import Any

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.io.archive import ProjectError, Record, get, get_numbers
from maizeviz.light.scene.request import MAX_RAYS
from maizeviz.light.sources.clock import zone as iana_zone

#: Record kinds of a sun, a sky and a day result (a sun's is the only kind of maizeviz 0.2),
#: and of the light a sun's leaves absorbed with scattering (kept beside that sun's record).
SUN_KIND, SKY_KIND, DAY_KIND = "light", "light_sky", "light_day"
ABSORBED_KIND = "light_absorbed"
#: The light of each record kind, as results are named in tables and the app.
KINDS = {SUN_KIND: "sun", SKY_KIND: "sky", DAY_KIND: "day", ABSORBED_KIND: "absorbed"}
#: Balance fields of an absorbed-light record, W/m2 of ground.
_BALANCE = ("incident", "absorbed_leaves", "absorbed_ground", "reflected_top",
            "escaped_sides", "unresolved", "absorbed_stalks")
#: Arrays of a Sky, under the record's prefix.
_SKY_ARRAYS = ("zenith_deg", "azimuth_deg", "solid_angle_sr", "weights")
#: Arrays of a Period (each (n,) float64), stored as ``period_<name>``.
_PERIOD_ARRAYS = ("step_s", "zenith_deg", "azimuth_deg", "ghi", "dni", "dhi",
                  "direct_horizontal")
#: Arrays a Period may have (a weather file's measured PAR, air temperature; NaN allowed in
#: the temperature), stored when present.
_PERIOD_OPTIONAL = {"par_measured": False, "temp_air": True, "par_diffuse_share": False}
#: Prefix of the arrays of a day's sky light.
_DIFFUSE = "diffuse_"
#: Prefix of the arrays of a day's diffuse split by Perez's model.
_PEREZ = "perez_"
_OFFSET = re.compile(r"(Z|[+-]\d\d:?\d\d(:?\d\d(\.\d+)?)?)$")
_FIXED_ZONE = re.compile(r"UTC([+-])(\d\d):(\d\d)")
#: Fractions may exceed 1 by rounding (weighted sums): the bound checked on reading.
_ONE = 1.0 + 1e-9


# ------------------------------------------------------------------------------ writing
def _floats(values) -> list[float]:
    return [float(v) for v in np.asarray(values, dtype=np.float64).ravel()]


def _jsonable(value: Any) -> Any:
    """A period parameter as a JSON value (text for what JSON cannot hold)."""
    if isinstance(value, (str, bool)) or value is None:
        return value
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else str(value)
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    return str(value)


def _zone_name(tz) -> str:
    """An IANA name (``Asia/Shanghai``), ``UTC`` or a fixed offset ``UTC+08:00``."""
    key = getattr(tz, "key", None) or getattr(tz, "zone", None)
    return str(key) if key else str(tz)


def _common_meta(label: str, light) -> dict:
    return {"label": label, "level": str(light.level),
            "heights_cm": _floats(light.heights_cm), "rect": _floats(light.rect),
            "rays": int(light.rays),
            "seconds": {str(k): float(v) for k, v in light.seconds.items()
                        if isinstance(v, (int, float)) and math.isfinite(v)},
            "warnings": [str(w) for w in light.warnings], "periodic": bool(light.periodic)}


def _map_arrays(light, prefix: str = "") -> dict[str, np.ndarray]:
    xe, ye = light.map_edges
    return {f"{prefix}maps": np.asarray(light.maps, np.float64),
            f"{prefix}map_x_edges": np.asarray(xe, np.float64),
            f"{prefix}map_y_edges": np.asarray(ye, np.float64),
            f"{prefix}map_rays": np.asarray(light.map_rays, np.int64)}


def _sky_parts(light, prefix: str = "") -> tuple[dict, dict[str, np.ndarray]]:
    """Metadata and arrays of a SkyLight (arrays named with ``prefix``)."""
    sky = light.sky
    meta = _common_meta("", light)
    del meta["label"]
    meta.update({"sky": {"kind": str(sky.kind), "split": str(sky.split)},
                 "transmission": _floats(light.transmission),
                 "density": float(light.density),
                 "intercepted_fraction": float(light.intercepted_fraction)})
    arrays = {f"{prefix}sky_{name}": np.asarray(getattr(sky, name), np.float64)
              for name in _SKY_ARRAYS}
    arrays.update({f"{prefix}per_direction": np.asarray(light.per_direction, np.float64),
                   f"{prefix}per_direction_intercepted":
                       np.asarray(light.per_direction_intercepted, np.float64),
                   f"{prefix}triangle_share": np.asarray(light.triangle_share, np.float64)})
    arrays.update(_map_arrays(light, prefix))
    return meta, arrays


def sky_record(label: str, light, settings: dict | None = None) -> Record:
    """A sky result (``SkyLight`` traced on the canopy labelled ``label``); ``settings``: the
    app's sky settings of the run (JSON), kept for reopening."""
    meta, arrays = _sky_parts(light)
    meta = {"label": label, **meta}
    if settings is not None:
        meta["settings"] = _jsonable(settings)
    return Record(SKY_KIND, meta, arrays)


def day_record(label: str, light, settings: dict | None = None) -> Record:
    """A day result (``PeriodLight`` traced on the canopy labelled ``label``); ``settings``
    as :func:`sky_record`."""
    from maizeviz.light.sources.perez import SPLIT_ARRAYS

    p = light.period
    meta = _common_meta(label, light)
    meta["period"] = {"times": [t.isoformat() for t in p.times],
                      "tz": _zone_name(p.times.tz if p.times.tz is not None else p.start.tz),
                      "start": p.start.isoformat(), "end": p.end.isoformat(),
                      "source": str(p.source), "parameters": _jsonable(dict(p.parameters)),
                      "par_umol_per_j": float(p.par_umol_per_j),
                      "notes": [str(n) for n in p.notes]}
    arrays = {f"period_{name}": np.asarray(getattr(p, name), np.float64)
              for name in (*_PERIOD_ARRAYS, *_PERIOD_OPTIONAL) if getattr(p, name) is not None}
    arrays.update({"step_transmission": np.asarray(light.step_transmission, np.float64),
                   "step_intercepted_fraction":
                       np.asarray(light.step_intercepted_fraction, np.float64),
                   "triangle_direct_mol": np.asarray(light.triangle_direct_mol, np.float64),
                   "triangle_diffuse_mol": np.asarray(light.triangle_diffuse_mol, np.float64)})
    arrays.update(_map_arrays(light))
    if light.diffuse is not None:                   # each step's diffuse light split by Perez
        meta["diffuse_model"] = str(light.diffuse.model)
        arrays.update({f"{_PEREZ}{name}": np.asarray(getattr(light.diffuse, name), np.float64)
                       for name in SPLIT_ARRAYS})
    if light.sky is not None:
        sky_meta, sky_arrays = _sky_parts(light.sky, _DIFFUSE)
        meta["sky"] = sky_meta
        arrays.update(sky_arrays)
    else:
        meta["sky"] = None
    if settings is not None:
        meta["settings"] = _jsonable(settings)
    return Record(DAY_KIND, meta, arrays)


def sun_record(label: str, result) -> Record:
    """A sun result (a ``LightResult`` traced on the canopy labelled ``label``)."""
    meta = {"label": label, "level": result.level,
            "sun": {"zenith_deg": float(result.sun.zenith_deg),
                    "azimuth_deg": float(result.sun.azimuth_deg), "when": result.sun.when},
            "heights_cm": _floats(result.heights_cm),
            "transmission": _floats(result.transmission),
            "rays": int(result.rays), "rect": _floats(result.rect),
            "ray_area_cm2": float(result.ray_area_cm2), "density": float(result.density),
            "direction": _floats(result.direction),
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
    if getattr(result, "triangle_sunlit_cm2", None) is not None:
        arrays["triangle_sunlit_cm2"] = np.asarray(result.triangle_sunlit_cm2, np.float64)
    return Record(SUN_KIND, meta, arrays)


def absorbed_record(label: str, light, settings: dict | None = None) -> Record:
    """Light absorbed with scattering (an ``AbsorbedLight`` traced on the canopy labelled
    ``label``); ``settings``: the optics spec as JSON (kept for reopening)."""
    o = light.optics
    meta = {"label": label, "level": light.level, "band": light.band,
            "optics": {"reflectance": float(o.reflectance),
                       "transmittance": float(o.transmittance),
                       "ground_reflectance": float(o.ground_reflectance),
                       "ranks": [[int(r), float(a), float(b)] for r, a, b in o.ranks]},
            "irradiance_w_m2": float(light.irradiance_w_m2),
            # absorbed_stalks only where stalks absorbed: a leaves-only result is written as
            # before they took light
            "balance": {k: float(getattr(light.balance, k)) for k in _BALANCE
                        if k != "absorbed_stalks" or light.balance.absorbed_stalks},
            "rect": _floats(light.rect), "rays": int(light.rays),
            "directions": int(light.directions), "depth": int(light.depth),
            "threshold": float(light.threshold), "seed": int(light.seed),
            "events": int(light.events), "periodic": bool(light.periodic),
            "seconds": {k: float(v) for k, v in light.seconds.items()}}
    if settings is not None:
        meta["settings"] = _jsonable(settings)
    arrays = {"triangle_absorbed_w": np.asarray(light.triangle_absorbed_w, np.float64),
              "triangle_sunlit_cm2": np.asarray(light.triangle_sunlit_cm2, np.float64)}
    # what photosynthesis and standard errors need (maizeviz 0.2): the direct-beam part, the
    # sun, and each batch's shares as (3, nnz) rows of (batch, triangle, value)
    if light.triangle_direct_w is not None:
        arrays["triangle_direct_w"] = np.asarray(light.triangle_direct_w, np.float64)
    if light.sun_direction is not None:
        meta["sun_direction"] = [float(c) for c in light.sun_direction]
    if light.batches is not None:
        for name in ("absorbed", "direct", "sunlit_cm2"):
            m = getattr(light.batches, name).tocoo()
            arrays[f"batches_{name}"] = np.vstack([m.row, m.col, m.data]).astype(np.float64)
    return Record(ABSORBED_KIND, meta, arrays)


def _batches_from(rec: Record, where: str, what: str, n_tri: int):
    """The per-batch shares of an absorbed-light record (None when it has none)."""
    from scipy.sparse import csr_array

    from maizeviz.light.results.uncertainty import BATCHES, Batches

    if "batches_absorbed" not in rec.arrays:
        return None
    parts = []
    for name in ("absorbed", "direct", "sunlit_cm2"):
        a = _array(rec, f"batches_{name}", where, what, (3, None))
        rows, cols = a[0], a[1]
        if np.any(rows != np.round(rows)) or np.any(cols != np.round(cols)) or \
                np.any((rows < 0) | (rows >= BATCHES)) or np.any((cols < 0) | (cols >= n_tri)):
            raise ProjectError(f"{where}: {what}: array 'batches_{name}' names batches or "
                               "triangles that do not exist; the project is damaged")
        parts.append(csr_array((a[2], (rows.astype(np.int64), cols.astype(np.int64))),
                               shape=(BATCHES, n_tri)))
    return Batches(*parts)


def run_record(label: str, result, settings: dict | None = None,
               stands: dict | None = None) -> Record:
    """The record of any light result: a sun's ``LightResult``, a ``SkyLight``, a
    ``PeriodLight`` or an ``AbsorbedLight``; ``settings``: the settings of a sky, day or
    absorbed run as JSON (kept for reopening); ``stands``: the identity of the stands it was
    traced on (:func:`maizeviz.project.stands.stands_identity`)."""
    from maizeviz.light.results.absorbed import AbsorbedLight
    from maizeviz.light.results.diffuse import PeriodLight, SkyLight

    if isinstance(result, AbsorbedLight):
        rec = absorbed_record(label, result, settings)
    elif isinstance(result, SkyLight):
        rec = sky_record(label, result, settings)
    elif isinstance(result, PeriodLight):
        rec = day_record(label, result, settings)
    else:
        rec = sun_record(label, result)
    if stands is not None:
        rec.meta["stands"] = dict(stands)
    return rec


# ------------------------------------------------------------------------------ reading
def _array(rec: Record, name: str, where: str, what: str, shape: tuple, *,
           counts: bool = False, nan: bool = False, lo: float | None = None,
           hi: float | None = None) -> np.ndarray:
    """Array ``name`` of the record, checked: present, numeric, of ``shape`` (None: any
    size), finite (NaN allowed with ``nan``), within [lo, hi]; a float64 (int64 for
    ``counts``) copy."""
    a = rec.arrays.get(name)
    if a is None:
        raise ProjectError(f"{where}: {what} has no array '{name}'; the project is damaged")
    if a.dtype.kind not in ("iu" if counts else "iuf"):
        raise ProjectError(f"{where}: {what}: array '{name}' holds {a.dtype}, not "
                           f"{'whole numbers' if counts else 'numbers'}; the project is damaged")
    if a.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, a.shape)):
        want = " x ".join("any" if s is None else str(s) for s in shape) or "a single value"
        raise ProjectError(f"{where}: {what}: array '{name}' is {' x '.join(map(str, a.shape))}"
                           f", expected {want}; the project is damaged")
    out = np.array(a, dtype=np.int64 if counts else np.float64)
    finite = np.isfinite(out)
    if not nan and not finite.all() or nan and np.isinf(out).any():
        raise ProjectError(f"{where}: {what}: array '{name}' holds "
                           f"{'infinite' if nan else 'NaN or infinite'} values; the project is "
                           "damaged")
    vals = out[finite]
    if (lo is not None and np.any(vals < lo)) or (hi is not None and np.any(vals > hi)):
        rng = f"[{lo:g}, {hi:g}]" if lo is not None and hi is not None else \
            (f">= {lo:g}" if lo is not None else f"<= {hi:g}")
        raise ProjectError(f"{where}: {what}: array '{name}' has values outside {rng}; the "
                           "project is damaged")
    return out


def _number(m: dict, key: str, where: str, what: str, lo: float | None = None,
            hi: float | None = None, default: Any = ...) -> float:
    value = get(m, key, (int, float), where=f"{where}: {what}") if default is ... else \
        get(m, key, (int, float), default, f"{where}: {what}")
    value = float(value)
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        raise ProjectError(f"{where}: {what}: '{key}' is {value:g}, out of range; the project "
                           "is damaged")
    return value


def _common(m: dict, where: str, what: str) -> dict:
    """Heights, rectangle, rays, seconds, warnings, level and periodic flag, checked."""
    at = f"{where}: {what}"
    heights = get_numbers(m, "heights_cm", where=at)
    rect = get_numbers(m, "rect", where=at)
    rays = get(m, "rays", int, where=at)
    if not heights:
        raise ProjectError(f"{at} has no heights; the project is damaged")
    if len(rect) != 4 or not (rect[2] > rect[0] and rect[3] > rect[1]):
        raise ProjectError(f"{at}: 'rect' must be 4 numbers x0, y0, x1, y1 with x1 > x0 and "
                           "y1 > y0; the project is damaged")
    if rays < 1:
        raise ProjectError(f"{at}: 'rays' must be at least 1, got {rays}")
    seconds = get(m, "seconds", dict, {}, at)
    return {"heights_cm": np.array(heights, np.float64), "rect": tuple(rect), "rays": rays,
            "level": str(get(m, "level", str, "", at)),
            "warnings": tuple(str(get({"w": w}, "w", str, where=f"{at}: warnings"))
                              for w in get(m, "warnings", list, [], at)),
            "seconds": {str(k): float(v) for k, v in seconds.items()
                        if isinstance(v, (int, float)) and not isinstance(v, bool)
                        and math.isfinite(v)},
            "periodic": bool(get(m, "periodic", bool, False, at))}


def _maps(rec: Record, prefix: str, n_heights: int, where: str, what: str) -> dict:
    xe = _array(rec, f"{prefix}map_x_edges", where, what, (None,))
    ye = _array(rec, f"{prefix}map_y_edges", where, what, (None,))
    if len(xe) < 2 or len(ye) < 2 or np.any(np.diff(xe) <= 0) or np.any(np.diff(ye) <= 0):
        raise ProjectError(f"{where}: {what}: the heatmap's bin edges are not increasing; the "
                           "project is damaged")
    a, b = len(xe) - 1, len(ye) - 1
    maps = _array(rec, f"{prefix}maps", where, what, (n_heights, a, b), nan=True, lo=0, hi=_ONE)
    rays = _array(rec, f"{prefix}map_rays", where, what, (a, b), counts=True, lo=0)
    return {"maps": maps, "map_edges": (xe, ye), "map_rays": rays}


def _sky_light(rec: Record, m: dict, prefix: str, where: str, what: str):
    """A SkyLight from its metadata ``m`` and the record's arrays named with ``prefix``."""
    from maizeviz.light.results.diffuse import SkyLight
    from maizeviz.light.sources.sky import Sky

    at = f"{where}: {what}"
    c = _common(m, where, what)
    n_h = len(c["heights_cm"])
    transmission = np.array(get_numbers(m, "transmission", where=at), np.float64)
    if len(transmission) != n_h or np.any(transmission < 0) or np.any(transmission > _ONE):
        raise ProjectError(f"{at}: 'transmission' must be {n_h} numbers in [0, 1], one per "
                           "height; the project is damaged")
    sky_meta = get(m, "sky", dict, where=at)
    kind = get(sky_meta, "kind", str, where=f"{at}: sky")
    split = get(sky_meta, "split", str, where=f"{at}: sky")
    parts = {name: _array(rec, f"{prefix}sky_{name}", where, what, (None,))
             for name in _SKY_ARRAYS}
    try:
        sky = Sky(kind, split, **parts)
    except MaizevizError as exc:
        raise ProjectError(f"{at}: the stored sky cannot be used ({exc})") from None
    n = sky.n
    per_direction = _array(rec, f"{prefix}per_direction", where, what, (n, n_h), lo=0, hi=_ONE)
    per_int = _array(rec, f"{prefix}per_direction_intercepted", where, what, (n,), lo=0, hi=_ONE)
    share = _array(rec, f"{prefix}triangle_share", where, what, (None,), lo=0)
    return SkyLight(sky=sky, transmission=transmission, per_direction=per_direction,
                    intercepted_fraction=_number(m, "intercepted_fraction", where, what, 0, _ONE),
                    per_direction_intercepted=per_int, triangle_share=share,
                    density=_number(m, "density", where, what, lo=1e-300),
                    **_maps(rec, prefix, n_h, where, what), **c)


def sky_from_record(rec: Record, where: str) -> tuple[str, Any, dict | None]:
    """(label, SkyLight, stored settings or None) from a ``light_sky`` record; refused with
    ProjectError if malformed."""
    m = rec.meta
    light = _sky_light(rec, m, "", where, "a sky result")
    return (str(get(m, "label", str, light.level, where)), light,
            get(m, "settings", dict, None, where))


def _zone(name: str, where: str):
    try:
        return iana_zone(name)
    except MaizevizError:
        pass
    fixed = _FIXED_ZONE.fullmatch(name)
    if fixed:
        sign = -1 if fixed.group(1) == "-" else 1
        offset = _dt.timedelta(hours=int(fixed.group(2)), minutes=int(fixed.group(3)))
        if offset < _dt.timedelta(hours=24):
            return _dt.timezone(sign * offset)
    raise ProjectError(f"{where}: a day result's time zone '{name[:40]}' is not one this "
                       "computer knows (an IANA name such as Asia/Shanghai, or UTC+08:00)")


def _time(text: Any, where: str, what: str):
    """An ISO 8601 time with its UTC offset, as a UTC pandas Timestamp."""
    import pandas as pd

    if not isinstance(text, str) or not _OFFSET.search(text.strip()):
        shown = json.dumps(text)[:40] if isinstance(text, (str, int, float, bool)) or \
            text is None else "something else"
        raise ProjectError(f"{where}: {what} must be an ISO 8601 time with its UTC offset "
                           f"(2005-08-01T12:00:00+08:00), got {shown}")
    t: pd.Timestamp | None
    try:
        t = pd.Timestamp(text.strip())
        t = None if t is pd.NaT or t.tz is None else t.as_unit("ns")   # years 1678-2261
    except (ValueError, TypeError, OverflowError):
        t = None
    if t is None:
        raise ProjectError(f"{where}: {what} '{text[:40]}' is not a valid ISO 8601 time with "
                           "its UTC offset (years 1678 to 2261)")
    return t.tz_convert("UTC")


def _period(rec: Record, m: dict, where: str):
    import pandas as pd

    from maizeviz.light.sources.irradiance import Period

    at = f"{where}: a day result's period"
    p = get(m, "period", dict, where=f"{where}: a day result")
    texts = get(p, "times", list, where=at)
    zone = _zone(get(p, "tz", str, where=at), where)
    utc = [_time(t, at, f"time step {i + 1}") for i, t in enumerate(texts)]
    times = pd.DatetimeIndex(utc, dtype="datetime64[ns, UTC]") if utc else \
        pd.DatetimeIndex([], dtype="datetime64[ns, UTC]")
    if len(times) > 1 and not np.all(np.diff(times.asi8) > 0):
        raise ProjectError(f"{at}: its time steps are not in increasing order; the project is "
                           "damaged")
    start = _time(get(p, "start", str, where=at), at, "'start'").tz_convert(zone)
    end = _time(get(p, "end", str, where=at), at, "'end'").tz_convert(zone)
    if end <= start:
        raise ProjectError(f"{at}: it ends before it starts; the project is damaged")
    n = len(times)
    arrays = {name: _array(rec, f"period_{name}", where, "a day result's period", (n,))
              for name in _PERIOD_ARRAYS}
    arrays.update({name: _array(rec, f"period_{name}", where, "a day result's period", (n,),
                                nan=nan, lo=None if nan else 0.0)
                   for name, nan in _PERIOD_OPTIONAL.items() if f"period_{name}" in rec.arrays})
    notes = tuple(str(get({"n": v}, "n", str, where=f"{at}: notes"))
                  for v in get(p, "notes", list, [], at))
    try:
        return Period(times=times.tz_convert(zone), start=start, end=end,
                      source=str(get(p, "source", str, where=at)),
                      parameters=dict(get(p, "parameters", dict, {}, at)),
                      par_umol_per_j=_number(p, "par_umol_per_j", where,
                                             "a day result's period"),
                      notes=notes, **arrays)
    except MaizevizError as exc:
        raise ProjectError(f"{at} cannot be used ({exc})") from None


def day_from_record(rec: Record, where: str) -> tuple[str, Any, dict | None]:
    """(label, PeriodLight, stored settings or None) from a ``light_day`` record; refused with
    ProjectError if malformed."""
    from maizeviz.light.results.diffuse import PeriodLight
    from maizeviz.light.sources.perez import SPLIT_ARRAYS, DiffuseSplit

    m = rec.meta
    what = "a day result"
    c = _common(m, where, what)
    n_h = len(c["heights_cm"])
    period = _period(rec, m, where)
    n = period.n_steps
    step_t = _array(rec, "step_transmission", where, what, (n, n_h), lo=0, hi=_ONE)
    step_f = _array(rec, "step_intercepted_fraction", where, what, (n,), lo=0, hi=_ONE)
    direct = _array(rec, "triangle_direct_mol", where, what, (None,), lo=0)
    diffuse = _array(rec, "triangle_diffuse_mol", where, what, (len(direct),), lo=0)
    sky = None
    if m.get("sky") is not None:
        sky_meta = get(m, "sky", dict, where=f"{where}: {what}")
        sky = _sky_light(rec, sky_meta, _DIFFUSE, where, "a day result's sky")
        if not (np.array_equal(sky.heights_cm, c["heights_cm"]) and sky.rect == c["rect"]
                and sky.rays == c["rays"] and len(sky.triangle_share) == len(direct)):
            raise ProjectError(f"{where}: a day result's sky does not match its heights, "
                               "rectangle, rays or triangles; the project is damaged")
    elif n:
        raise ProjectError(f"{where}: a day result with time steps has no sky light; the "
                           "project is damaged")
    split = None
    model = get(m, "diffuse_model", str, None, f"{where}: {what}")
    if model is not None:
        parts = {name: _array(rec, f"{_PEREZ}{name}", where, what, (n,),
                              nan=name == "clearness") for name in SPLIT_ARRAYS}
        try:
            split = DiffuseSplit(model, **parts)
        except MaizevizError as exc:
            raise ProjectError(f"{where}: {what}: its diffuse split cannot be used ({exc}); "
                               "the project is damaged") from None
    light = PeriodLight(period=period, sky=sky, step_transmission=step_t,
                        step_intercepted_fraction=step_f, triangle_direct_mol=direct,
                        triangle_diffuse_mol=diffuse, diffuse=split,
                        **_maps(rec, "", n_h, where, what), **c)
    return (str(get(m, "label", str, light.level, where)), light,
            get(m, "settings", dict, None, where))


def sun_from_record(rec: Record, where: str) -> tuple[str, Any]:
    """(label, LightResult) from a ``light`` record; refused with ProjectError if malformed."""
    from maizeviz.light.results.direct import LightResult
    from maizeviz.light.sources.sun import Sun

    m = rec.meta
    what = "a sun result"
    at = f"{where}: {what}"
    sun = get(m, "sun", dict, where=at)
    heights = get_numbers(m, "heights_cm", where=at)
    transmission = get_numbers(m, "transmission", where=at)
    rect = get_numbers(m, "rect", where=at)
    direction = get_numbers(m, "direction", where=at)
    rays = get(m, "rays", int, where=at)
    if len(heights) != len(transmission) or len(rect) != 4 or len(direction) != 3 or rays < 0:
        raise ProjectError(f"{at} has inconsistent sizes; the project is damaged")
    stored_z = rec.arrays.get("first_z")     # -inf where a ray hits nothing
    if stored_z is None or stored_z.dtype.kind != "f" or stored_z.shape != (rays,) or \
            rays > MAX_RAYS:
        raise ProjectError(f"{at}: its rays are missing or do not match; the project is "
                           "damaged")
    first_z = np.asarray(stored_z)           # read only now that its size is known right
    if np.isnan(first_z).any() or (first_z == np.inf).any():
        raise ProjectError(f"{at}: its rays are missing or do not match; the project is "
                           "damaged")
    hits: dict[str, Any] = {}
    for name in ("first_hits", "second_hits"):
        hits[name] = None if name not in rec.arrays else \
            _array(rec, name, where, what, (None,), counts=True, lo=0)
    if (hits["first_hits"] is None) != (hits["second_hits"] is None) or (
            hits["first_hits"] is not None
            and len(hits["first_hits"]) != len(hits["second_hits"])):
        raise ProjectError(f"{at}: its first and second hits per triangle do not match "
                           "(one missing, or of other lengths); the project is damaged")
    if "triangle_sunlit_cm2" in rec.arrays:        # the sampled sunlit area (older: none)
        if hits["first_hits"] is None:
            raise ProjectError(f"{at}: it has a sampled sunlit area but no hits per "
                               "triangle; the project is damaged")
        hits["triangle_sunlit_cm2"] = _array(rec, "triangle_sunlit_cm2", where, what,
                                             (len(hits["first_hits"]),), lo=0)
    planes: dict[str, Any] = {}
    if "sensor_lit" in rec.arrays:
        lit = rec.arrays["sensor_lit"]
        if lit.dtype != np.uint8 or lit.shape != (len(heights), -(-rays // 8)):
            raise ProjectError(f"{at}: its sensor planes do not match its heights and rays; "
                               "the project is damaged")
        planes = {"sensor_lit": np.array(lit),
                  "sensor_offset_cm": _array(rec, "sensor_offset_cm", where, what,
                                             (len(heights), 2)),
                  "periodic": bool(get(m, "periodic", bool, False, at))}
    try:
        result = LightResult(
            sun=Sun(_number(sun, "zenith_deg", where, what), _number(sun, "azimuth_deg", where,
                                                                      what),
                    str(get(sun, "when", str, "", at))),
            heights_cm=np.array(heights), transmission=np.array(transmission), rays=rays,
            rect=(rect[0], rect[1], rect[2], rect[3]),
            ray_area_cm2=_number(m, "ray_area_cm2", where, what),
            first_z=first_z.astype(np.float32), direction=np.array(direction),
            seconds={str(k): float(v) for k, v in get(m, "seconds", dict, {}, at).items()
                     if isinstance(v, (int, float)) and not isinstance(v, bool)
                     and math.isfinite(v)},
            warnings=tuple(str(w) for w in get(m, "warnings", list, [], at)),
            level=str(get(m, "level", str, "", at)),
            density=_number(m, "density", where, what), **hits, **planes)
    except (ValueError, MaizevizError) as exc:     # e.g. a sun below the horizon
        raise ProjectError(f"{at} cannot be used ({exc})") from None
    return str(get(m, "label", str, result.level, at)), result


def absorbed_from_record(rec: Record, where: str) -> tuple[str, Any, dict | None]:
    """(label, AbsorbedLight, stored settings) from a ``light_absorbed`` record; refused
    with ProjectError if malformed."""
    from maizeviz.light.results.absorbed import AbsorbedLight, Balance
    from maizeviz.light.trace.optics import Optics

    m = rec.meta
    what = "an absorbed-light result"
    at = f"{where}: {what}"
    band = get(m, "band", str, where=at)
    optics = get(m, "optics", dict, where=at)
    balance = get(m, "balance", dict, where=at)
    rect = get_numbers(m, "rect", where=at)
    if len(rect) != 4:
        raise ProjectError(f"{at} has inconsistent sizes; the project is damaged")
    n = rec.arrays.get("triangle_absorbed_w")
    n_tri = int(n.shape[0]) if n is not None and n.ndim == 1 else -1
    absorbed = _array(rec, "triangle_absorbed_w", where, what, (n_tri,), lo=0)
    sunlit = _array(rec, "triangle_sunlit_cm2", where, what, (n_tri,), lo=0)
    settings = get(m, "settings", dict, None, at)
    direct = _array(rec, "triangle_direct_w", where, what, (n_tri,), lo=0) \
        if "triangle_direct_w" in rec.arrays else None
    batches = _batches_from(rec, where, what, n_tri)
    sun_dir = get_numbers(m, "sun_direction", where=at) if "sun_direction" in m else None
    if sun_dir is not None and len(sun_dir) != 3:
        raise ProjectError(f"{at} has inconsistent sizes; the project is damaged")
    try:
        light = AbsorbedLight(
            band, Optics(_number(optics, "reflectance", where, what, 0, 1),
                         _number(optics, "transmittance", where, what, 0, 1),
                         _number(optics, "ground_reflectance", where, what, 0, 1), band,
                         _ranks(optics, at)),
            _number(m, "irradiance_w_m2", where, what, 0),
            # absorbed_stalks: 0 in projects saved before stalks took light
            Balance(*(_number(balance, k, where, what,
                              default=0.0 if k == "absorbed_stalks" else ...)
                      for k in _BALANCE)),
            absorbed, sunlit, (rect[0], rect[1], rect[2], rect[3]),
            get(m, "rays", int, where=at), get(m, "directions", int, where=at),
            get(m, "depth", int, where=at), _number(m, "threshold", where, what, 0, 1),
            get(m, "seed", int, where=at), get(m, "events", int, where=at),
            bool(get(m, "periodic", bool, False, at)), str(get(m, "level", str, "", at)),
            {str(k): float(v) for k, v in get(m, "seconds", dict, {}, at).items()
             if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)},
            triangle_direct_w=direct, batches=batches,
            sun_direction=None if sun_dir is None else (sun_dir[0], sun_dir[1], sun_dir[2]))
    except (ValueError, TypeError, MaizevizError) as exc:
        raise ProjectError(f"{at} cannot be used ({exc})") from None
    return str(get(m, "label", str, light.level, at)), light, settings


def _ranks(optics: dict, at: str) -> tuple:
    """Leaf optics per rank of a record: ((rank, reflectance, transmittance), ...)."""
    rows = get(optics, "ranks", list, [], at)
    if len(rows) > 10_000 or not all(isinstance(r, list) and len(r) == 3 for r in rows):
        raise ProjectError(f"{at}: its optics per leaf rank are malformed; the project is "
                           "damaged")
    return tuple((r[0], r[1], r[2]) for r in rows)


def run_from_record(rec: Record, where: str) -> tuple[str, Any, str, dict | None] | None:
    """(label, result, light kind ``"sun"``/``"sky"``/``"day"``, stored settings or None) of
    a record, or None for a kind this maizeviz does not know.

    Raises
    ------
    ProjectError
        A malformed record (one line naming what is wrong).
    """
    stored: dict | None = None
    if rec.kind == SUN_KIND:
        label, result = sun_from_record(rec, where)
    elif rec.kind == SKY_KIND:
        label, result, stored = sky_from_record(rec, where)
    elif rec.kind == DAY_KIND:
        label, result, stored = day_from_record(rec, where)
    elif rec.kind == ABSORBED_KIND:
        label, result, stored = absorbed_from_record(rec, where)
    else:
        return None
    stands = rec.meta.get("stands")
    if isinstance(stands, dict):             # the result says which stands it belongs to
        result = replace(result, stands=dict(stands))
    return label, result, KINDS[rec.kind], stored


#: Arrays of a record that hold one value per canopy triangle (stalks included).
PER_TRIANGLE = ("first_hits", "second_hits", "triangle_share", "triangle_direct_mol",
                "triangle_diffuse_mol", "triangle_absorbed_w", "triangle_sunlit_cm2",
                "triangle_direct_w")


def per_triangle(rec: Record) -> int:
    """The most triangles any per-triangle array of ``rec`` declares (0 without one), from
    the arrays' headers: nothing is read."""
    return max((int(a.shape[0]) if a.ndim else 0 for name, a in rec.arrays.items()
                if name.endswith(PER_TRIANGLE)), default=0)
