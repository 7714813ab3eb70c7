"""A sweep file: axes of canopies, mesh levels and suns, checked before anything runs.

The file is TOML (standard library ``tomllib``). Every list is an axis and the scenarios are the
product of the axes, minus the ``exclude`` entries. A single value is a one-value axis.
Defaults are those of ``maizeviz canopy`` and ``maizeviz light``::

    [canopy]
    points = ["block3x3.csv", "genotypes/*.csv"]  # required; globs; relative to this file
    tile = ["3x3"]                 # AxB copies of the digitized block (default "1x1")
    row_spacing = [60]             # cm between rows (default 60)
    plant_spacing = [30]           # cm between plants of a row (default 30)
    block = "3x3"                  # rows x plants of the digitized block (default: inferred)
    layout = ["field.json"]        # layout files: arrangements besides (or instead of) tilings
    level = ["K4", "standard", "36", "8"]   # required; as the app's slider names them
    preserve_area = true           # below the standard mesh, keep the smooth area (default)
    cover_resolution = 0.5         # cm, ground-cover pixel (not an axis)

    [light]
    sun = [{zenith = 30, azimuth = 180},                # required; angles in degrees, or
           {date = "2005-08-01", time = "12:00", lat = 39.9, lon = 116.4, tz = "Asia/Shanghai"},
           {date = "2005-08-01", solar_noon = true, lat = 39.9, lon = 116.4, altitude = 50}]
                                   # a place (deg N, deg E, m) and a local time (tz: UTC)
    density = [4, 16]              # rays per cm2 (default 4)
    heights = [0, 50, 100, 150, 200, 225]   # cm; not an axis: every scenario reports all
    periodic = true                # rays leaving the plot re-enter it (default false)
    rect = [0, 0, 180, 90]         # sample rectangle x0, y0, x1, y1 in cm (default: centre tile)
    optics = ["black",             # leaf optics: "black" (interception only, the default) or
              {band = "par"},      # a table: absorbed light with scattering, each key optional
              {band = "nir", reflectance = 0.45, transmittance = 0.40, ground_reflectance = 0.25, depth = 20},
              {band = "par", direct_w_m2 = 520, diffuse_w_m2 = 60, seed = 1, ranks = [[1, 0.12, 0.06]]}]
                                   # ranks: [rank, rho, tau] per leaf rank. NIR leaves scatter
                                   # 85 %: depth 20 leaves 0.2 % of it unresolved on the bundled
                                   # canopy, depth 3 left 28 %
    photosynthesis = ["none",      # gross CO2 assimilation of scenarios with PAR optics:
                      {model = "c4", temperature = 30, co2_ppm = 400},   # "none", or a leaf
                      {model = "wofost", amax = 70, eff = 0.45}]         # model and its keys

    [[exclude]]                    # partial scenarios to drop (or, before [canopy]:
    level = "K4"                   # exclude = [{level = "K4", density = 16}])
    density = 16

An inline table (``{...}``) stays on one line (TOML 1.0). The schema, every key's type, unit,
range and default, is declared in :mod:`maizeviz.sweep.schema`.

Each scenario has a stable key: a hash of everything that determines its numbers (the points
and layout files by content, not by name; every parameter; maizeviz's major.minor version), so
results on disk can be matched to scenarios whatever the files are called.
"""

from __future__ import annotations

import fnmatch
import functools
import hashlib
import itertools
import json
import math
import os
import tomllib
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import maizeviz
from maizeviz.io.inputs import read_input, refuse_zero_tail
from maizeviz.light.specs import OpticsSpec
from maizeviz.sweep import compute
from maizeviz.sweep.errors import SweepSpecError

if TYPE_CHECKING:                  # the schema needs pydantic (the sweep extra): read when used
    from maizeviz.sweep.schema import Canopy, Exclude

#: Largest sweep file (bytes): a hand-written or generated file is far smaller.
MAX_SPEC_BYTES = 4 * 2**20
#: More scenarios than this are refused unless confirmed (``yes=True``, ``--yes``).
MAX_SCENARIOS = 10_000
#: More combinations than this are refused outright: split the sweep.
HARD_MAX_SCENARIOS = 1_000_000

def version_tag() -> str:
    """maizeviz major.minor: results of other patch releases are reused, not of others."""
    return ".".join(maizeviz.__version__.split(".")[:2])


def _digest(obj) -> str:
    text = json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def arrangement_label(layout: str | None, tile: str | None, row_spacing: float | None,
                      plant_spacing: float | None) -> str:
    """An arrangement in words, as listings and the summary show it: the layout file's name,
    or ``"3x3 at 60 x 30 cm"`` for a tiling (``tile`` as ``"AxB"``)."""
    if layout or tile is None:
        return layout or "?"
    return f"{tile} at {row_spacing:g} x {plant_spacing:g} cm"


def sun_label(zenith_deg: float, azimuth_deg: float, when: str | None) -> str:
    """A sun in words: ``"z 30.00 az 180.00"``, with its time when it came from one."""
    angles = f"z {zenith_deg:.2f} az {azimuth_deg:.2f}"
    return f"{angles} ({when})" if when else angles


@dataclass(frozen=True)
class PointsFile:
    """A points file: ``name`` as shown (relative to the sweep file), absolute ``path``."""

    name: str
    path: str
    sha256: str


@dataclass(frozen=True)
class Arrangement:
    """Where the plants stand: a tiling of the digitized block, or a layout file.

    ``tile`` (A, B); spacings in cm; ``block`` (rows, plants per row) or None (inferred); or
    ``layout`` (as shown), ``layout_path`` (absolute) and its content hash.
    """

    tile: tuple | None = None
    row_spacing: float | None = None
    plant_spacing: float | None = None
    block: tuple | None = None
    layout: str | None = None
    layout_path: str | None = None
    layout_sha256: str | None = None

    @property
    def label(self) -> str:
        return arrangement_label(self.layout, f"{self.tile[0]}x{self.tile[1]}" if self.tile
                                 else None, self.row_spacing, self.plant_spacing)

    def canonical(self) -> dict:
        if self.layout or self.tile is None:
            return {"layout_sha256": self.layout_sha256}
        return {"tile": list(self.tile), "row_spacing": self.row_spacing,
                "plant_spacing": self.plant_spacing,
                "block": list(self.block) if self.block else None}


@dataclass(frozen=True)
class SunSpec:
    """A sun: angles in degrees (zenith from vertical, azimuth clockwise from north), ``when``
    (ISO time when it came from a place and date, else None) and the table as given."""

    zenith_deg: float
    azimuth_deg: float
    when: str | None
    given: tuple

    @property
    def label(self) -> str:
        return sun_label(self.zenith_deg, self.azimuth_deg, self.when)


@dataclass(frozen=True)
class Scenario:
    """One light computation of a sweep; ``key`` identifies its inputs, ``group_key`` its
    canopy (scenarios of a group share leaves, canopy, measures and Embree scene)."""

    index: int
    key: str
    group_key: str
    points: PointsFile
    arrangement: Arrangement
    level: str
    preserve_area: bool
    sun: SunSpec
    density: float
    periodic: bool
    heights_cm: tuple
    rect_cm: tuple | None
    cover_resolution: float
    optics: OpticsSpec | None = None
    photosynthesis: tuple | None = None

    def axes(self) -> dict:
        """The axis values as result columns."""
        a = self.arrangement
        return {"points": self.points.name, "points_sha256": self.points.sha256,
                "layout": a.layout, "tile": f"{a.tile[0]}x{a.tile[1]}" if a.tile else None,
                "row_spacing": a.row_spacing, "plant_spacing": a.plant_spacing,
                "block": f"{a.block[0]}x{a.block[1]}" if a.block else None,
                "level": self.level, "preserve_area": self.preserve_area,
                "sun_zenith_deg": self.sun.zenith_deg, "sun_azimuth_deg": self.sun.azimuth_deg,
                "sun_when": self.sun.when, "density": self.density, "periodic": self.periodic,
                **optics_columns(self.optics),
                "photosynthesis": photosynthesis_label(self.photosynthesis)}


def photosynthesis_label(ph: tuple | None) -> str:
    """A scenario's leaf model in words ("none", or "c4 temperature 30 co2_ppm 400")."""
    if ph is None:
        return "none"
    from maizeviz.photosynthesis.split import leaf_model

    d = dict(ph)
    name = str(d.pop("model"))
    temp = d.pop("temperature")
    defaults = leaf_model(name).as_dict()
    return " ".join([name, f"{temp:g} C"] + [f"{k} {v:g}" if isinstance(v, (int, float))
                                              else f"{k} {v}" for k, v in sorted(d.items())
                                              if defaults.get(k) != v])


def optics_columns(optics: OpticsSpec | None) -> dict:
    """The optics of a scenario as result columns (None for black leaves)."""
    if optics is None:
        return {"optics_band": None, "leaf_reflectance": None, "leaf_transmittance": None,
                "ground_reflectance": None, "scatter_depth": None, "optics": "black"}
    o = optics.optics()
    return {"optics_band": o.band, "leaf_reflectance": o.reflectance,
            "leaf_transmittance": o.transmittance, "ground_reflectance": o.ground_reflectance,
            "scatter_depth": optics.depth, "optics": optics_label(optics)}


def optics_label(optics: OpticsSpec | None) -> str:
    """Leaf optics in words, every setting that changes the numbers: "black", or band, leaf
    rho and tau, soil rho, then what differs from the defaults (irradiance, depth, seed,
    ranks)."""
    if optics is None:
        return "black"
    from maizeviz.light.trace.scatter import DEFAULT_DEPTH

    o = optics.optics()
    text = (f"{o.band} rho {o.reflectance:g} tau {o.transmittance:g} soil "
            f"{o.ground_reflectance:g}")
    if optics.direct_w_m2 is not None:
        text += f" direct {optics.direct_w_m2:g} W/m2"
    if optics.diffuse_w_m2:
        text += f" diffuse {optics.diffuse_w_m2:g} W/m2"
    if optics.depth != DEFAULT_DEPTH:
        text += f" depth {optics.depth}"
    if optics.seed:
        text += f" seed {optics.seed}"
    if o.ranks:
        text += " ranks " + ";".join(f"{r}:{a:g}/{b:g}" for r, a, b in o.ranks)
    return text


@functools.lru_cache(maxsize=256)
def _optics_inputs(optics: OpticsSpec) -> dict:
    """An optics axis value's fields (once per value: a sweep lists it in many scenarios)."""
    return asdict(optics)


def _group_inputs(points, arr, level, preserve, cover) -> dict:
    """What determines a group's canopy (its key's inputs)."""
    return {"points_sha256": points.sha256, **arr.canonical(), "level": level,
            "preserve_area": preserve, "cover_resolution": cover, "maizeviz": version_tag()}


def _scenario_inputs(group, sun, density, periodic, heights, rect, optics=None,
                     photosynthesis=None) -> dict:
    """What determines a scenario's numbers (its key's inputs): its group's, and the rest."""
    full = dict(group, sun_zenith_deg=sun.zenith_deg, sun_azimuth_deg=sun.azimuth_deg,
                sun_when=sun.when, density=density, periodic=periodic, heights_cm=list(heights),
                rect_cm=list(rect) if rect else None)
    if optics is not None:              # black leaves keep the keys they always had
        full["optics"] = _optics_inputs(optics)
    if photosynthesis is not None:      # so do scenarios without photosynthesis
        full["photosynthesis"] = dict(photosynthesis)
    return full


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: the scenarios in a stable order (scenarios of a group together).

    Attributes
    ----------
    source : str, the sweep file as given
    document : dict, the file's content with globs resolved (JSON-ready, for sweep.json)
    scenarios : tuple of Scenario
    excluded : int, combinations dropped by ``exclude``
    fingerprint : str, hash of the scenario keys: two specs with the same one compute the same
    """

    source: str
    document: dict
    scenarios: tuple
    excluded: int
    fingerprint: str

    def groups(self) -> list[list[Scenario]]:
        """Scenarios by group (points content, arrangement, level, area rule), in order."""
        out: dict[str, list] = {}
        for s in self.scenarios:
            out.setdefault(s.group_key, []).append(s)
        return list(out.values())


# ------------------------------------------------------------------------------- listing
def _fail(source: str, where: str, msg: str) -> NoReturn:
    raise SweepSpecError(f"{source}: {where}: {msg}")


def _shown(path: str, base: Path) -> str:
    """A path as listings show it: relative to the sweep file's folder."""
    try:
        return os.path.relpath(path, base)
    except ValueError:  # pragma: no cover - another drive on Windows
        return path


def _sha(path: str, source: str, base: Path, where: str) -> str:
    try:
        return compute.file_sha256(path)
    except OSError as exc:
        _fail(source, where, f"{_shown(path, base)}: cannot be read ({exc.strerror or exc})")


def read_toml(path) -> tuple[dict, str]:
    """The parsed sweep file and its text; SweepSpecError for a file that is missing, not a
    regular file (a FIFO is refused at once, not waited on), over :data:`MAX_SPEC_BYTES`, or
    not TOML."""
    raw = refuse_zero_tail(read_input(path, "sweep file", MAX_SPEC_BYTES, SweepSpecError), path,
                           "sweep file", SweepSpecError)
    try:
        # a byte order mark (Windows editors write one) is read past, as in points files
        text = raw.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError:
        raise SweepSpecError(f"{path}: not a TOML text file (not UTF-8)") from None
    try:
        return tomllib.loads(text), text
    except tomllib.TOMLDecodeError as exc:
        raise SweepSpecError(f"{path}: not valid TOML: {' '.join(str(exc).split())}") from None
    except RecursionError:                # tomllib recurses once per nested array or table
        raise SweepSpecError(f"{path}: not a sweep file: arrays or tables nested too deeply") \
            from None


def load_spec(path, yes: bool = False, max_scenarios: int = MAX_SCENARIOS) -> SweepSpec:
    """Read and check a sweep file and list its scenarios.

    Every key is checked before anything runs; points and layout files are hashed; suns given
    by place and time are resolved through pvlib.

    Raises
    ------
    SweepSpecError
        One line naming the file and the key (``canopy.level[2]``) or path that is wrong;
        also for more than ``max_scenarios`` scenarios unless ``yes``.
    """
    doc, _ = read_toml(path)
    try:
        from maizeviz.sweep.schema import validate
    except ImportError as exc:
        raise SweepSpecError(f"reading a sweep file needs pydantic ({exc}): pip install "
                             "'maizeviz[sweep]'") from None
    source = str(path)
    base = Path(path).resolve().parent
    sweep = validate(doc, source, base)
    canopy, light = sweep.canopy, sweep.light
    points = _points_axis(canopy, source, base)
    arrangements = _arrangements(canopy, source, base)
    matchers = [_matcher(e) for e in sweep.exclude]
    levels, preserve, cover = canopy.level, canopy.preserve_area, canopy.cover_resolution
    suns = [SunSpec(*s) for s in light.sun]
    densities, periodic = light.density, light.periodic
    optics, photosynthesis = light.optics, light.photosynthesis
    heights, rect = light.heights, light.rect

    axes: list[list[Any]] = [points, arrangements, levels, preserve, densities, periodic, suns,
                             optics, photosynthesis]
    _check_combinations(source, math.prod(len(a) for a in axes), max_scenarios,
                        yes or bool(matchers))
    scenarios, excluded = _scenarios(source, axes, matchers, heights, rect, cover)
    if not scenarios and not excluded:   # every leaf model, and no PAR optics to feed one
        _fail(source, "light.photosynthesis", "a leaf model needs PAR optics (optics = "
              "[{band = \"par\"}]) and none is given: add them, or \"none\"")
    if not scenarios:
        raise SweepSpecError(f"{source}: exclude drops every scenario: nothing to run")
    if len(scenarios) > max_scenarios and not yes:
        raise SweepSpecError(f"{source}: {len(scenarios):,} scenarios is more than "
                             f"{max_scenarios:,}: confirm with --yes, or narrow the axes")
    document = json.loads(json.dumps(doc, default=str))
    document["canopy"]["points"] = [{"name": p.name, "sha256": p.sha256} for p in points]
    fingerprint = _digest(sorted(s.key for s in scenarios))[:24]
    return SweepSpec(source, document, tuple(scenarios), excluded, fingerprint)


def _points_axis(canopy: Canopy, source: str, base: Path) -> list[PointsFile]:
    """The points files (globs expanded), each once, hashed; two of the same content
    refused."""
    points: list[PointsFile] = []
    by_sha: dict[str, str] = {}
    for i, group in enumerate(canopy.points):
        for p in group:
            if any(q.path == p for q in points):
                continue                                  # two patterns naming one file
            sha = _sha(p, source, base, f"canopy.points[{i}]")
            if sha in by_sha:
                _fail(source, f"canopy.points[{i}]", f"{_shown(p, base)} has the same content "
                      f"as {by_sha[sha]}: keep one of them")
            by_sha[sha] = _shown(p, base)
            points.append(PointsFile(_shown(p, base), p, sha))
    return points


def _arrangements(canopy: Canopy, source: str, base: Path) -> list[Arrangement]:
    """The tilings (tile x row spacing x plant spacing, with a block) and layout files."""
    given = canopy.model_fields_set
    arrangements = []
    if given & {"tile", "row_spacing", "plant_spacing", "block"} or "layout" not in given:
        arrangements += [Arrangement(t, r, p, canopy.block) for t in canopy.tile
                         for r in canopy.row_spacing for p in canopy.plant_spacing]
    for i, group in enumerate(canopy.layout):
        for p in group:
            arrangements.append(Arrangement(layout=_shown(p, base), layout_path=p,
                                            layout_sha256=_sha(p, source, base,
                                                               f"canopy.layout[{i}]")))
    return arrangements


def _check_combinations(source: str, total: int, max_scenarios: int, allowed: bool) -> None:
    """Refuse, before listing them, more combinations than a sweep file may hold, and more
    than ``max_scenarios`` unless ``allowed`` (--yes, or excludes that may drop some)."""
    if total > HARD_MAX_SCENARIOS:
        raise SweepSpecError(f"{source}: the axes make {total:,} combinations, beyond the "
                             f"{HARD_MAX_SCENARIOS:,} one sweep file may hold: split the sweep")
    if total > max_scenarios and not allowed:                  # refused before listing
        raise SweepSpecError(f"{source}: {total:,} scenarios is more than {max_scenarios:,}: "
                             "confirm with --yes, or narrow the axes")


def _scenarios(source: str, axes: list[list[Any]], matchers: list, heights, rect,
               cover: float) -> tuple[list[Scenario], int]:
    """Every combination of the axes the excludes keep, as scenarios, and how many were
    excluded; an exclude that matches nothing is refused."""
    scenarios: list[Scenario] = []
    used, excluded = [False] * len(matchers), 0
    par = {opt: opt is not None and opt.optics().band == "par" for opt in axes[7]}
    groups: dict[tuple, tuple[dict, str]] = {}      # inputs and key, by canopy
    for pf, arr, lv, pa, dens, per, sun, opt, ph in itertools.product(*axes):
        if ph is not None and not par[opt]:
            continue                    # photosynthesis is of PAR absorbed: not of this optics
        values = {"points": pf, "arrangement": arr, "level": lv, "preserve_area": pa,
                  "density": dens, "periodic": per, "sun": sun, "optics": opt,
                  "photosynthesis": ph}
        hit = [i for i, m in enumerate(matchers) if m(values)]
        if hit:
            for i in hit:
                used[i] = True
            excluded += 1
            continue
        if (pf, arr, lv, pa) not in groups:
            group = _group_inputs(pf, arr, lv, pa, cover)
            groups[pf, arr, lv, pa] = group, _digest(group)[:24]
        group, group_key = groups[pf, arr, lv, pa]
        full = _scenario_inputs(group, sun, dens, per, heights, rect, opt, ph)
        scenarios.append(Scenario(len(scenarios), _digest(full)[:24], group_key, pf, arr, lv, pa,
                                  sun, dens, per, heights, rect, cover, opt, ph))
    for i, u in enumerate(used):
        if not u:
            _fail(source, f"exclude[{i}]", "matches no scenario (a typo in a value?)")
    return scenarios, excluded


def _matcher(entry: Exclude) -> Callable[[dict[str, Any]], bool]:
    """A predicate over a scenario's axis values for one ``exclude`` entry (a sun: every key
    given must agree)."""
    wants = [(k, v.given() if k == "sun" else v) for k, v in entry.given().items()]
    return lambda vals: all(_matches(vals, key, want) for key, want in wants)


def _matches(vals: dict[str, Any], key: str, want: Any) -> bool:
    arr = vals["arrangement"]
    if key in ("points", "layout"):
        name = vals["points"].name if key == "points" else arr.layout
        return name is not None and (fnmatch.fnmatch(name, want)
                                     or fnmatch.fnmatch(Path(name).name, want))
    if key in ("tile", "row_spacing", "plant_spacing"):
        return bool(getattr(arr, key) == want)
    if key == "sun":
        given = dict(vals["sun"].given)
        return all(given.get(k) == x for k, x in want.items())
    return bool(vals[key] == want)
