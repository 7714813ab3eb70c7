"""The sweep's only door into the maizeviz core: the canopy of one group and all its suns.

A *group* is every scenario sharing one canopy: the same points file (by content), tiling or
layout file, mesh level and area rule. Its work is done once and reused by all its suns:

- leaves are read and fitted once per points file per process (cached by the file's sha256, so
  a Dask worker fits each file once however many tasks it runs);
- the canopy is built and measured once per group;
- one :class:`~maizeviz.light.engine.LightEngine` per group keeps its Embree scenes: the plain
  one serves the ground cover and every open-field sun of the group, the periodic one every
  periodic sun.

Every import of the computing core (leaf, mesh, canopy, light) is in this file, so that moving
core modules is a one-file change (the rest of the sweep uses only ``maizeviz.errors`` and
``maizeviz.io``). The numbers equal ``maizeviz canopy --json`` and ``maizeviz light --json``
for the same inputs: the same functions with the same arguments, except that tracing runs on
one thread (a Dask worker is one process per core) and without the hit classes, neither of
which changes transmission.

Scenarios are duck-typed (see :class:`maizeviz.sweep.spec.Scenario`); of the sweep this
module imports only its errors.
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any

from maizeviz.canopy.build import Canopy, build_canopy
from maizeviz.canopy.layout import check_block, check_tile, layout_for, parse_shape
from maizeviz.canopy.layout import check_spacing as _core_check_spacing
from maizeviz.canopy.measures import measure_canopy
from maizeviz.cost import Cost, cover_cost, layout_cost, light_cost
from maizeviz.errors import MaizevizError
from maizeviz.io.hashing import sha256_stream
from maizeviz.leaf.fit import read_leaves
from maizeviz.light.engine import LightEngine
from maizeviz.light.scene.request import Sampling
from maizeviz.light.sources.sun import Sun, sun_at
from maizeviz.mesh.levels import parse_level
from maizeviz.sweep.errors import WorkerInputError

#: Points files whose fitted leaves a process keeps (a block of 9 plants is a few MB).
LEAVES_CACHE_SIZE = 8
#: Canopies (with their Embree scene) a process keeps: a 9 x 9 canopy at K = 4 is 2.7 M
#: triangles, about 300 MB with its scene, so only the latest two.
CANOPY_CACHE_SIZE = 2


# ------------------------------------------------------------------------- values of a spec
def level_label(text) -> str:
    """Canonical name of a mesh level: ``"K4"`` -> ``"K=4"``, ``"std"`` -> ``"standard"``,
    ``36`` -> ``"36 triangles"``. Raises MaizevizError naming the text."""
    return parse_level(str(text)).label


def level_order(label: str) -> tuple[int, int]:
    """Sort key, finest first: interpolated levels by K descending, then budgets descending."""
    lv = parse_level(label.replace(" triangles", ""))
    if lv.interp is not None:
        return (0, -lv.interp)
    return (1, -(lv.triangles or 0))


def parse_tile(text, quantity: str = "tile") -> tuple[int, int]:
    """``"3x3"`` -> (3, 3); MaizevizError otherwise."""
    return parse_shape(str(text), quantity)


def check_shape(shape: tuple[int, int], quantity: str = "tile") -> tuple[int, int]:
    """A parsed tile count or block shape (``quantity``: "tile" or "block") checked as the
    canopy checks it (at most ``MAX_PLANTS`` plants); MaizevizError otherwise."""
    return check_block(shape) if quantity == "block" else check_tile(shape)


def check_spacing(value, name: str = "row spacing") -> float:
    """A row or plant spacing (cm) checked as the canopy checks it; MaizevizError otherwise."""
    return _core_check_spacing(value, name)


def resolve_sun(table: dict) -> tuple[float, float, str]:
    """Sun angles of a sweep's sun table: (zenith deg, azimuth deg, when).

    ``{zenith, azimuth}`` as given; ``{date, time | solar_noon, lat, lon, tz, altitude}``
    through pvlib exactly as ``maizeviz light --date ...`` does. Raises MaizevizError.
    """
    if "zenith" in table:
        sun = Sun(float(table["zenith"]), float(table["azimuth"]))
    else:
        sun = sun_at(table["date"], table.get("time"), float(table["lat"]), float(table["lon"]),
                     table.get("tz", "UTC"), bool(table.get("solar_noon", False)),
                     float(table.get("altitude", 0.0)))
    return float(sun.zenith_deg), float(sun.azimuth_deg), sun.when


# ---------------------------------------------------------------------------- worker caches
class _LRU:
    """A small thread-safe least-recently-used map (a worker may run several threads)."""

    def __init__(self, size: int):
        self.size = size
        self.items: OrderedDict = OrderedDict()
        self.lock = threading.Lock()

    def get(self, key):
        with self.lock:
            value = self.items.get(key)
            if value is not None:
                self.items.move_to_end(key)
            return value

    def put(self, key, value):
        with self.lock:
            self.items[key] = value
            self.items.move_to_end(key)
            while len(self.items) > self.size:
                self.items.popitem(last=False)

    def clear(self):
        with self.lock:
            self.items.clear()


_LEAVES = _LRU(LEAVES_CACHE_SIZE)
_CANOPIES = _LRU(CANOPY_CACHE_SIZE)


def clear_caches() -> None:
    """Forget fitted leaves and canopies of this process (benchmarks start cold with it)."""
    _LEAVES.clear()
    _CANOPIES.clear()


def file_sha256(path) -> str:
    """sha256 (hex) of a file's bytes; OSError when it cannot be read."""
    with open(path, "rb") as fh:
        return sha256_stream(fh)


def _leaves(path: str, sha256: str):
    """Fitted leaves of a points file, once per content per process: (found, seconds)."""
    found = _LEAVES.get(sha256)
    if found is not None:
        return found, 0.0
    t0 = time.perf_counter()
    try:
        now = file_sha256(path)
    except OSError as exc:            # the driver read it: this machine cannot
        raise WorkerInputError(f"{path}: cannot be read here ({exc.strerror or exc}); every "
                               "worker needs the points files at the same path") from None
    if now != sha256:
        raise MaizevizError(f"{path}: the file changed since the sweep started (its content "
                            "hash differs); run the sweep again")
    found = read_leaves(path)         # the CLI's reader, defaults: skip bad leaves, degree 3
    if not found.leaves:
        first = f" ({found.skipped[0]})" if found.skipped else ""
        raise MaizevizError(f"{path}: no leaf could be reconstructed{first}; the canopy is empty")
    _LEAVES.put(sha256, found)
    return found, time.perf_counter() - t0


# ------------------------------------------------------------------------------ one group
@dataclass
class _GroupState:
    """A built canopy with its measures and scene; ``seconds`` not yet charged to a row."""

    canopy: Canopy
    measures: dict[str, Any]
    engine: LightEngine
    leaves_skipped: int
    warnings: list[str]
    seconds: dict[str, float] = field(default_factory=dict)


def _layout(s, leaves):
    """The CLI's ``layout_for``: the layout file, or the digitized block tiled."""
    a = s.arrangement
    if a.layout_path:
        try:
            now = file_sha256(a.layout_path)
        except OSError as exc:
            raise WorkerInputError(f"{a.layout_path}: cannot be read here "
                                   f"({exc.strerror or exc}); every worker needs the layout "
                                   "files at the same path") from None
        if now != a.layout_sha256:
            raise MaizevizError(f"{a.layout_path}: the file changed since the sweep started "
                                "(its content hash differs); run the sweep again")
        return layout_for(leaves, layout_file=a.layout_path)
    return layout_for(leaves, tuple(a.tile), a.row_spacing, a.plant_spacing,
                      tuple(a.block) if a.block else None)


def _group_state(s) -> _GroupState:
    """Leaves -> layout -> canopy -> measures (-> scene) for the group of scenario ``s``."""
    state = _CANOPIES.get(s.group_key)
    if state is not None:
        return _GroupState(state.canopy, state.measures, state.engine, state.leaves_skipped,
                           state.warnings)                   # nothing left to charge
    found, fit_s = _leaves(s.points.path, s.points.sha256)
    t0 = time.perf_counter()
    layout = _layout(s, found.leaves)
    t1 = time.perf_counter()
    canopy = build_canopy(found.leaves, layout, parse_level(s.level), s.preserve_area)
    t2 = time.perf_counter()
    engine = LightEngine(canopy)
    scene = engine.scene(periodic=False)               # plain: the ground cover uses it too
    t3 = time.perf_counter()
    m = measure_canopy(canopy, s.cover_resolution, False, scene=scene)
    t4 = time.perf_counter()
    warnings = list(found.problems) + [f"skipped: {e}" for e in found.skipped]
    # the inferred block is a note the CLI prints for every tiling, not a warning
    warnings += [w for w in layout.warnings if not w.startswith("block inferred")]
    state = _GroupState(canopy, m.as_dict(), engine, len(found.skipped), warnings,
                        {"fit": fit_s, "layout": t1 - t0, "build": t2 - t1, "scene": t3 - t2,
                         "measure": t4 - t3})
    _CANOPIES.put(s.group_key, state)
    return state


def _charge(state: _GroupState) -> dict:
    """The group's stage seconds for the first row that needed them, zeros afterwards, so
    that seconds summed over rows are the time spent."""
    spent = dict.fromkeys(("fit", "layout", "build", "scene", "measure"), 0.0)
    spent.update(state.seconds)
    state.seconds = {}
    return spent


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def _error(s, exc: BaseException) -> dict:
    status = "failed" if isinstance(exc, WorkerInputError) else "error"
    return {"key": s.key, "status": status, "error": _one_line(exc)}


def _light(state: _GroupState, s) -> dict:
    sun = Sun(s.sun.zenith_deg, s.sun.azimuth_deg, s.sun.when or "")
    sampling = Sampling(tuple(s.heights_cm), s.density, s.rect_cm, s.periodic, threads=1)
    seconds = _charge(state)
    t0 = time.perf_counter()
    res = state.engine.sun(sun, classes=False, sampling=sampling)
    seconds["scene"] += res.seconds["build"]           # a periodic scene built for this row
    seconds["trace"] = time.perf_counter() - t0 - res.seconds["build"]
    absorbed: dict = {}
    if s.optics is not None:                           # leaves with optics: absorbed light
        t0 = time.perf_counter()
        light = s.optics.absorbed(state.engine, sun, sampling)
        seconds["scatter"] = time.perf_counter() - t0
        b = light.balance
        absorbed = {"incident_w_m2": b.incident, "absorbed_leaves_w_m2": b.absorbed_leaves,
                    "absorbed_ground_w_m2": b.absorbed_ground,
                    "reflected_top_w_m2": b.reflected_top, "balance_closure": b.closure,
                    "absorbed_leaves_se_w_m2": light.absorbed_leaves_error,
                    "unresolved_w_m2": b.unresolved}
        from maizeviz.light.results.absorbed import UNRESOLVED_WARN, unresolved_warning

        if b.incident and b.unresolved > UNRESOLVED_WARN * b.incident:
            state_warnings = [unresolved_warning(b.unresolved / b.incident, light.depth)]
        else:
            state_warnings = []
        if s.photosynthesis is not None:
            from maizeviz.light.results.assimilation import assimilate
            from maizeviz.photosynthesis.split import model_from_dict

            ph = dict(s.photosynthesis)
            temp = float(ph.pop("temperature"))
            a = assimilate(state.engine.canopy, light, model_from_dict(ph), temp)
            absorbed.update(canopy_gross_umol_m2_s=a.canopy_gross_umol_m2_s,
                            canopy_gross_umol_m2_s_se=a.canopy_gross_error_umol_m2_s,
                            canopy_gross_kg_co2_ha_h=a.canopy_gross_kg_co2_ha_h)
        absorbed["warnings_scatter"] = state_warnings
    m = state.measures
    return {**absorbed,"key": s.key, "status": "ok", "error": None, "triangles": m["triangles"],
            "plants": m["plants"], "leaves": m["leaves"],
            "leaves_skipped": state.leaves_skipped, "leaf_area_m2": m["leaf_area_m2"],
            "projected_area_m2": m["projected_area_m2"],
            "ground_cover_m2": m["ground_cover_m2"], "ground_area_m2": m["ground_area_m2"],
            "lai": m["lai"], "rays": int(res.rays),
            "heights_cm": [float(h) for h in res.heights_cm],
            "transmission": [float(t) for t in res.transmission],
            "warnings": list(state.warnings) + list(res.warnings)
            + absorbed.pop("warnings_scatter", []), "seconds": seconds}


def compute_scenarios(scenarios) -> list[dict]:
    """Results of scenarios that share one group, in the order given.

    Returns one dict per scenario: ``key``, ``status`` ("ok"; "error": bad input; "failed":
    an input file this process cannot read, worth retrying elsewhere), ``error`` (one line
    or None) and, when ok, the canopy measures (``triangles``, ``leaf_area_m2``, ``lai``, ...,
    areas in m2), ``rays``, ``heights_cm`` (H,) and ``transmission`` (H,) in [0, 1],
    ``warnings`` (list of str) and ``seconds`` per stage (fit, layout, build, scene, measure,
    trace; the group stages are charged to the first scenario that needed them).

    Bad input (an unreadable points file, a level the leaves cannot take, a sample rectangle
    outside the plot, ...) gives "error" results; anything else is a bug and is raised.
    """
    if not scenarios:
        return []
    keys = {s.group_key for s in scenarios}
    if len(keys) != 1:
        raise ValueError(f"compute_scenarios takes one group, got {len(keys)}")
    try:
        state = _group_state(scenarios[0])
    except MaizevizError as exc:                    # LeafError, PointsFileError, LayoutError
        return [_error(s, exc) for s in scenarios]
    out = []
    for s in scenarios:
        try:
            out.append(_light(state, s))
        except MaizevizError as exc:
            out.append(_error(s, exc))
    return out


# ------------------------------------------------------------------------------- estimates
def group_costs(scenarios) -> list[Cost]:
    """What one group costs (``maizeviz.cost``, the same estimate as the command line's):
    its canopy, its ground-cover rays and each scenario's tracing, without building anything
    (the leaves are fitted, and cached, to know their grid shapes)."""
    s = scenarios[0]
    found, _ = _leaves(s.points.path, s.points.sha256)
    layout = _layout(s, found.leaves)
    rect = s.rect_cm or layout.centre_bounds
    return [layout_cost(found.leaves, layout, parse_level(s.level)),
            cover_cost(layout, s.cover_resolution),
            *(light_cost(rect, sc.density, len(sc.heights_cm)) for sc in scenarios)]


def describe_core() -> dict:
    """What the core offers the sweep (recorded in sweep.json)."""
    return {"scene_reuse": {"measure_canopy": True, "trace_light": True}}

