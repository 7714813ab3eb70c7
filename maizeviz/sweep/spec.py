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
           {date = "2005-08-01", solar_noon = true, lat = 39.9, lon = 116.4, tz = "Asia/Shanghai"}]
    density = [4]                  # rays per cm2 (default 4)
    heights = [0, 50, 100, 150, 200, 225]   # cm; not an axis: every scenario reports all
    periodic = true                # rays leaving the plot re-enter it (default false)
    rect = [0, 0, 180, 90]         # sample rectangle x0, y0, x1, y1 in cm (default: centre tile)
    optics = ["black",             # leaf optics: "black" (interception only, the default) or
              {band = "par"},      # a table: absorbed light with scattering, each key optional:
              {band = "nir", reflectance = 0.45, transmittance = 0.40, ground_reflectance = 0.25,
               direct_w_m2 = 520, diffuse_w_m2 = 0, depth = 20, seed = 0,
               ranks = [[1, 0.5, 0.35], [2, 0.48, 0.38]]}]   # [rank, rho, tau] per leaf rank
                                   # (NIR leaves scatter 85 %: depth 20 leaves 0.2 % of it
                                   # unresolved on the bundled canopy, depth 3 left 28 %)
    photosynthesis = ["none",      # gross CO2 assimilation of scenarios with PAR optics:
                      {model = "c4", temperature = 30, co2_ppm = 400},   # "none", or a leaf
                      {model = "wofost", amax = 70, eff = 0.45}]         # model and its keys

    [[exclude]]                    # partial scenarios to drop (or, before [canopy]:
    level = "K4"                   # exclude = [{level = "K4", density = 16}])
    density = 16

Each scenario has a stable key: a hash of everything that determines its numbers (the points
and layout files by content, not by name; every parameter; maizeviz's major.minor version), so
results on disk can be matched to scenarios whatever the files are called.
"""

from __future__ import annotations

import fnmatch
import glob
import hashlib
import itertools
import json
import math
import os
import tomllib
from collections.abc import Callable
from dataclasses import asdict, dataclass
from datetime import date, datetime
from datetime import time as dtime
from pathlib import Path
from typing import Any, NoReturn

import maizeviz
from maizeviz.errors import MaizevizError
from maizeviz.io.inputs import read_input, refuse_zero_tail
from maizeviz.light.scene.request import MAX_HEIGHTS
from maizeviz.light.specs import OpticsSpec
from maizeviz.sweep import compute
from maizeviz.sweep.errors import SweepSpecError

#: Largest sweep file (bytes): a hand-written or generated file is far smaller.
MAX_SPEC_BYTES = 4 * 2**20
#: More scenarios than this are refused unless confirmed (``yes=True``, ``--yes``).
MAX_SCENARIOS = 10_000
#: More combinations than this are refused outright: split the sweep.
HARD_MAX_SCENARIOS = 1_000_000

DEFAULT_HEIGHTS = (0.0, 50.0, 100.0, 150.0, 200.0, 225.0)

CANOPY_KEYS = ("points", "tile", "row_spacing", "plant_spacing", "block", "layout", "level",
               "preserve_area", "cover_resolution")
LIGHT_KEYS = ("sun", "density", "heights", "periodic", "rect", "optics", "photosynthesis")
TOP_KEYS = ("canopy", "light", "exclude")
AXES = ("points", "tile", "row_spacing", "plant_spacing", "layout", "level", "preserve_area",
        "sun", "density", "periodic", "optics", "photosynthesis")
#: Keys of an optics table (:class:`maizeviz.light.specs.OpticsSpec`); "black" (or false) is
#: the black leaves of interception.
OPTICS_KEYS = ("band", "reflectance", "transmittance", "ground_reflectance", "direct_w_m2",
               "diffuse_w_m2", "depth", "seed", "ranks")
#: Most scatterings a sweep follows.
MAX_DEPTH = 50
#: Largest irradiance of a band, W/m2 (as the command line's --irradiance and --diffuse).
MAX_IRRADIANCE = 5000.0
SUN_ANGLE_KEYS = ("zenith", "azimuth")
SUN_PLACE_KEYS = ("date", "time", "solar_noon", "lat", "lon", "tz", "altitude")


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


def _scenario_inputs(points, arr, level, preserve, sun, density, periodic, heights, rect,
                     cover, optics=None, photosynthesis=None) -> tuple[dict, dict]:
    group = {"points_sha256": points.sha256, **arr.canonical(), "level": level,
             "preserve_area": preserve, "cover_resolution": cover, "maizeviz": version_tag()}
    full = dict(group, sun_zenith_deg=sun.zenith_deg, sun_azimuth_deg=sun.azimuth_deg,
                sun_when=sun.when, density=density, periodic=periodic, heights_cm=list(heights),
                rect_cm=list(rect) if rect else None)
    if optics is not None:              # black leaves keep the keys they always had
        full["optics"] = asdict(optics)
    if photosynthesis is not None:      # so do scenarios without photosynthesis
        full["photosynthesis"] = dict(photosynthesis)
    return group, full


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


# ------------------------------------------------------------------------------- checking
class _Checker:
    """Converts and checks values, naming ``source: key`` in every message."""

    def __init__(self, source: str, base: Path):
        self.source = source
        self.base = base

    def fail(self, where: str, msg: str) -> NoReturn:
        raise SweepSpecError(f"{self.source}: {where}: {msg}")

    def known(self, table: dict, known: tuple, where: str):
        for k in table:
            if k == "exclude" and where in ("canopy", "light"):
                raise SweepSpecError(f"{self.source}: '{where}.exclude': exclude belongs at the "
                                     "top of the file, before [canopy], or in [[exclude]] tables")
            if k not in known:
                name = f"{where}.{k}" if where else k
                raise SweepSpecError(f"{self.source}: unknown key '{name}' (known"
                                     f"{' in ' + where if where else ''}: {', '.join(known)})")

    def axis(self, section: dict, key: str, where: str, convert, default=None) -> list:
        name = f"{where}.{key}"
        if key not in section:
            if default is None:
                self.fail(name, "is missing")
            return list(default)
        raw = section[key]
        values = raw if isinstance(raw, list) else [raw]
        if not values:
            self.fail(name, "is empty: give at least one value")
        out: list[Any] = []
        seen: dict[str, int] = {}
        for i, v in enumerate(values):
            item = f"{name}[{i}]" if isinstance(raw, list) else name
            c = convert(v, item)
            token = json.dumps(c, sort_keys=True, default=str)
            if token in seen:
                self.fail(item, f"repeats {name}[{seen[token]}]")
            seen[token] = i
            out.append(c)
        return out

    # converters: (value, where) -> canonical value
    def number(self, v, where, positive=True, minimum=None):
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(where, f"must be a number, got {json.dumps(v, default=str)}")
        try:
            finite = math.isfinite(v)
        except OverflowError:                              # an integer such as 10**400
            self.fail(where, "must be a number, got an integer too large for one")
        if not finite:
            self.fail(where, f"must be a number, got {json.dumps(v, default=str)}")
        if positive and v <= 0:
            self.fail(where, f"must be > 0, got {v}")
        if minimum is not None and v < minimum:
            self.fail(where, f"must be >= {minimum:g}, got {v}")
        return float(v)

    def boolean(self, v, where):
        if not isinstance(v, bool):
            self.fail(where, f"must be true or false, got {json.dumps(v, default=str)}")
        return v

    def shape(self, v, where):
        """A tile count or, for ``canopy.block``, a block shape, checked as the canopy does."""
        if not isinstance(v, str):
            self.fail(where, f"must be a string such as \"3x3\", got {json.dumps(v, default=str)}")
        quantity = "block" if where.endswith("block") else "tile"
        try:
            shape = compute.parse_tile(v, quantity)
        except MaizevizError:
            self.fail(where, f"must look like 3x3 (whole numbers >= 1), got '{v}'")
        try:
            return compute.check_shape(shape, quantity)
        except MaizevizError as exc:
            self.fail(where, str(exc))

    def spacing(self, v, where):
        """A row or plant spacing in cm, checked as the canopy does."""
        value = self.number(v, where)
        try:
            return compute.check_spacing(
                value, "plant spacing" if "plant_spacing" in where else "row spacing")
        except MaizevizError as exc:
            self.fail(where, str(exc))

    def level(self, v, where):
        if isinstance(v, bool) or not isinstance(v, (str, int)):
            self.fail(where, f"must be a level name such as \"K4\", \"standard\" or \"36\", "
                             f"got {json.dumps(v, default=str)}")
        try:
            return compute.level_label(v)
        except (MaizevizError, ValueError) as exc:         # the core has raised both
            self.fail(where, str(exc))

    def text(self, v, where):
        if not isinstance(v, str) or not v.strip():
            self.fail(where, f"must be a non-empty string, got {json.dumps(v, default=str)}")
        return v

    def sun_table(self, v, where) -> dict:
        if not isinstance(v, dict):
            self.fail(where, "must be a table such as {zenith = 30, azimuth = 180} or {date = "
                             "\"2005-08-01\", time = \"12:00\", lat = 39.9, lon = 116.4, tz = "
                             "\"Asia/Shanghai\"}")
        self.known(v, SUN_ANGLE_KEYS + SUN_PLACE_KEYS, where)
        t = {}
        for k, x in v.items():
            if isinstance(x, (date, datetime, dtime)):
                x = x.isoformat()                       # TOML date and time literals
            t[k] = x
        angles = [k for k in t if k in SUN_ANGLE_KEYS]
        place = [k for k in t if k in SUN_PLACE_KEYS]
        if angles and place:
            self.fail(where, "give either zenith and azimuth or a place and time, not both")
        if angles:
            for k in SUN_ANGLE_KEYS:
                if k not in t:
                    self.fail(f"{where}.{k}", "is missing")
                t[k] = self.number(t[k], f"{where}.{k}", positive=False)
        else:
            self._sun_place(t, where)
        return t

    def _sun_place(self, t: dict, where: str) -> None:
        """A sun given by a place and time: date, lat and lon, and a time or solar noon,
        each checked (in place)."""
        for k in ("date", "lat", "lon"):
            if k not in t:
                self.fail(f"{where}.{k}", "is missing (a sun from a place needs date, lat, "
                                          "lon and time or solar_noon)")
        for k in ("date", "time", "tz"):
            if k in t:
                t[k] = self.text(t[k], f"{where}.{k}")
        for k in ("lat", "lon", "altitude"):
            if k in t:
                t[k] = self.number(t[k], f"{where}.{k}", positive=False)
        if "solar_noon" in t:
            t["solar_noon"] = self.boolean(t["solar_noon"], f"{where}.solar_noon")
        if "time" not in t and not t.get("solar_noon"):
            self.fail(f"{where}.time", "is missing (or set solar_noon = true)")

    def optics(self, v, where) -> OpticsSpec | None:
        """Leaf optics: "black" or false (interception), or a table of OPTICS_KEYS."""
        if v is False or (isinstance(v, str) and v.lower() in ("black", "none")):
            return None
        if not isinstance(v, dict):
            self.fail(where, 'must be "black" or a table such as {band = "par", reflectance = '
                             '0.1, transmittance = 0.05, ground_reflectance = 0.1}')
        self.known(v, OPTICS_KEYS, where)
        t: dict[str, Any] = {}
        if "band" in v:
            t["band"] = self.text(v["band"], f"{where}.band").lower()
        for k in ("reflectance", "transmittance", "ground_reflectance", "direct_w_m2",
                  "diffuse_w_m2"):
            if k in v:
                t[k] = self.number(v[k], f"{where}.{k}", positive=False, minimum=0)
                if k.endswith("_w_m2") and t[k] > MAX_IRRADIANCE:
                    self.fail(f"{where}.{k}", f"must be from 0 to {MAX_IRRADIANCE:g} W/m2, got "
                                              f"{t[k]:g}")
        for k in ("depth", "seed"):
            if k in v:
                x = v[k]
                if isinstance(x, bool) or not isinstance(x, int) or not 0 <= x <= (
                        MAX_DEPTH if k == "depth" else 2**31 - 1):
                    self.fail(f"{where}.{k}", f"must be a whole number from 0 to "
                                              f"{MAX_DEPTH if k == 'depth' else 2**31 - 1}, "
                                              f"got {x!r}")
                t[k] = x
        if "ranks" in v:
            rows = v["ranks"]
            if not isinstance(rows, list) or not all(
                    isinstance(r, list) and len(r) == 3 for r in rows):
                self.fail(f"{where}.ranks", "must be a list of [rank, reflectance, "
                                            "transmittance], such as [[1, 0.12, 0.06]]")
            t["ranks"] = tuple(tuple(r) for r in rows)
        spec = OpticsSpec(**t)
        try:
            spec.optics()
        except MaizevizError as exc:
            self.fail(where, str(exc))
        return spec

    def photosynthesis(self, v, where) -> tuple | None:
        """A leaf model: "none" or false, or a table {model = "c4" or "wofost", temperature
        = C, and the model's parameters}; as sorted (key, value) pairs."""
        if v is False or (isinstance(v, str) and v.lower() == "none"):
            return None
        if not isinstance(v, dict) or not isinstance(v.get("model"), str):
            self.fail(where, 'must be "none" or a table such as {model = "c4", temperature '
                             '= 30}')
        from maizeviz.photosynthesis.split import leaf_model

        params = {k: x for k, x in v.items() if k not in ("model", "temperature")}
        for k, x in params.items():
            # the C4 model's temperature response is a name (collatz, clm45)
            if k != "temperature_response":
                params[k] = self.number(x, f"{where}.{k}", positive=False)
        temp = self.number(v.get("temperature", 25.0), f"{where}.temperature",
                           positive=False)
        if not -50 <= temp <= 70:
            self.fail(f"{where}.temperature", f"must be from -50 to 70 C, got {temp:g}")
        try:
            model = leaf_model(str(v["model"]), **params)
        except MaizevizError as exc:
            self.fail(where, str(exc))
        return tuple(sorted({**model.as_dict(), "temperature": temp}.items()))

    def sun(self, v, where) -> SunSpec:
        t = self.sun_table(v, where)
        try:
            z, a, when = compute.resolve_sun(t)
        except MaizevizError as exc:
            self.fail(where, str(exc))
        return SunSpec(z, a, when or None, tuple(sorted(t.items())))

    def files(self, v, where) -> list[str]:
        """Absolute paths of the files a path or glob names (relative to the sweep file)."""
        pattern = self.text(v, where)
        full = Path(os.path.expanduser(pattern))
        if not full.is_absolute():
            full = self.base / full
        if any(c in pattern for c in "*?["):
            found = sorted(p for p in glob.glob(str(full), recursive=True) if os.path.isfile(p))
            if not found:
                self.fail(where, f"'{pattern}' matches no file (in {full.parent})")
            return [str(Path(p).resolve()) for p in found]
        if full.is_dir():
            self.fail(where, f"{pattern}: is a folder, not a file")
        if not full.is_file():
            self.fail(where, f"{pattern}: no such file (looked for {full})")
        return [str(full.resolve())]

    def shown(self, path: str) -> str:
        try:
            return os.path.relpath(path, self.base)
        except ValueError:  # pragma: no cover - another drive on Windows
            return path

    def sha(self, path: str, where: str) -> str:
        try:
            return compute.file_sha256(path)
        except OSError as exc:
            self.fail(where, f"{self.shown(path)}: cannot be read ({exc.strerror or exc})")


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
    source = str(path)
    ck = _Checker(source, Path(path).resolve().parent)
    canopy, light = _sections(ck, doc, source)

    # --- canopy axes
    points = _points_axis(ck, canopy)
    arrangements = _arrangements(ck, canopy)
    levels = ck.axis(canopy, "level", "canopy", ck.level)
    preserve = ck.axis(canopy, "preserve_area", "canopy", ck.boolean, [True])
    cover = 0.5
    if "cover_resolution" in canopy:
        cover = ck.number(canopy["cover_resolution"], "canopy.cover_resolution")

    # --- light axes
    suns = ck.axis(light, "sun", "light", ck.sun)
    densities = ck.axis(light, "density", "light", ck.number, [4.0])
    periodic = ck.axis(light, "periodic", "light", ck.boolean, [False])
    optics = ck.axis(light, "optics", "light", ck.optics, [None])
    photosynthesis = ck.axis(light, "photosynthesis", "light", ck.photosynthesis, [None])
    heights = _heights(ck, light)
    rect = _rect(ck, light)

    # --- exclude
    excludes = doc.get("exclude", [])
    if not isinstance(excludes, list) or not all(isinstance(e, dict) for e in excludes):
        ck.fail("exclude", "must be a list of tables such as [{level = \"K4\", density = 16}]")
    matchers = [_matcher(ck, e, f"exclude[{i}]") for i, e in enumerate(excludes)]

    axes: list[list[Any]] = [points, arrangements, levels, preserve, densities, periodic, suns,
                             optics, photosynthesis]
    _check_combinations(source, math.prod(len(a) for a in axes), max_scenarios,
                        yes or bool(matchers))
    scenarios, excluded = _scenarios(ck, axes, matchers, heights, rect, cover)
    if not scenarios:
        raise SweepSpecError(f"{source}: exclude drops every scenario: nothing to run")
    if len(scenarios) > max_scenarios and not yes:
        raise SweepSpecError(f"{source}: {len(scenarios):,} scenarios is more than "
                             f"{max_scenarios:,}: confirm with --yes, or narrow the axes")
    document = json.loads(json.dumps(doc, default=str))
    document["canopy"]["points"] = [{"name": p.name, "sha256": p.sha256} for p in points]
    fingerprint = _digest(sorted(s.key for s in scenarios))[:24]
    return SweepSpec(source, document, tuple(scenarios), excluded, fingerprint)


def _sections(ck: _Checker, doc: dict, source: str) -> tuple[dict, dict]:
    """The file's [canopy] and [light] tables, each checked for unknown keys."""
    ck.known(doc, TOP_KEYS, "")
    for sec in ("canopy", "light"):
        if sec not in doc:
            raise SweepSpecError(f"{source}: the [{sec}] table is missing")
        if not isinstance(doc[sec], dict):
            raise SweepSpecError(f"{source}: '{sec}' must be a table ([{sec}])")
    canopy, light = doc["canopy"], doc["light"]
    ck.known(canopy, CANOPY_KEYS, "canopy")
    ck.known(light, LIGHT_KEYS, "light")
    return canopy, light


def _points_axis(ck: _Checker, canopy: dict) -> list[PointsFile]:
    """The points files (globs expanded), each once, hashed; two of the same content
    refused."""
    points: list[PointsFile] = []
    by_sha: dict[str, str] = {}
    for i, group in enumerate(ck.axis(canopy, "points", "canopy", ck.files)):
        for p in group:
            if any(q.path == p for q in points):
                continue                                  # two patterns naming one file
            sha = ck.sha(p, f"canopy.points[{i}]")
            if sha in by_sha:
                ck.fail(f"canopy.points[{i}]", f"{ck.shown(p)} has the same content as "
                        f"{by_sha[sha]}: keep one of them")
            by_sha[sha] = ck.shown(p)
            points.append(PointsFile(ck.shown(p), p, sha))
    return points


def _arrangements(ck: _Checker, canopy: dict) -> list[Arrangement]:
    """The tilings (tile x row spacing x plant spacing, with a block) and layout files."""
    tiling_given = any(k in canopy for k in ("tile", "row_spacing", "plant_spacing", "block"))
    arrangements = []
    if tiling_given or "layout" not in canopy:
        tiles = ck.axis(canopy, "tile", "canopy", ck.shape, [(1, 1)])
        rows = ck.axis(canopy, "row_spacing", "canopy", ck.spacing, [60.0])
        plants = ck.axis(canopy, "plant_spacing", "canopy", ck.spacing, [30.0])
        block = None
        if "block" in canopy:
            block = ck.shape(canopy["block"], "canopy.block")
        arrangements += [Arrangement(t, r, p, block) for t in tiles for r in rows for p in plants]
    if "layout" in canopy:
        for i, group in enumerate(ck.axis(canopy, "layout", "canopy", ck.files)):
            for p in group:
                arrangements.append(Arrangement(layout=ck.shown(p), layout_path=p,
                                                layout_sha256=ck.sha(p, f"canopy.layout[{i}]")))
    return arrangements


def _heights(ck: _Checker, light: dict) -> tuple[float, ...]:
    """``light.heights``: a list of at most MAX_HEIGHTS heights >= 0 cm, none twice."""
    if "heights" not in light:
        return DEFAULT_HEIGHTS
    raw = light["heights"]
    if not isinstance(raw, list):
        ck.fail("light.heights", "must be a list of heights in cm, such as [0, 50, 100]")
    if not raw:
        ck.fail("light.heights", "is empty: give at least one height")
    if len(raw) > MAX_HEIGHTS:
        ck.fail("light.heights", f"holds {len(raw):,} heights; at most {MAX_HEIGHTS:,}")
    heights = tuple(ck.number(h, f"light.heights[{i}]", positive=False, minimum=0)
                    for i, h in enumerate(raw))
    for i, h in enumerate(heights):
        if h in heights[:i]:
            ck.fail(f"light.heights[{i}]", f"height {h + 0.0:g} cm is given twice")
    return heights


def _rect(ck: _Checker, light: dict) -> tuple[float, ...] | None:
    """``light.rect``: [x0, y0, x1, y1] cm with x1 > x0 and y1 > y0, or None."""
    if "rect" not in light:
        return None
    raw = light["rect"]
    if not isinstance(raw, list) or len(raw) != 4:
        ck.fail("light.rect", "must be [x0, y0, x1, y1] in cm")
    rect = tuple(ck.number(v, f"light.rect[{i}]", positive=False) for i, v in enumerate(raw))
    if rect[2] <= rect[0] or rect[3] <= rect[1]:
        ck.fail("light.rect", f"must have x1 > x0 and y1 > y0, got {list(rect)}")
    return rect


def _check_combinations(source: str, total: int, max_scenarios: int, allowed: bool) -> None:
    """Refuse, before listing them, more combinations than a sweep file may hold, and more
    than ``max_scenarios`` unless ``allowed`` (--yes, or excludes that may drop some)."""
    if total > HARD_MAX_SCENARIOS:
        raise SweepSpecError(f"{source}: the axes make {total:,} combinations, beyond the "
                             f"{HARD_MAX_SCENARIOS:,} one sweep file may hold: split the sweep")
    if total > max_scenarios and not allowed:                  # refused before listing
        raise SweepSpecError(f"{source}: {total:,} scenarios is more than {max_scenarios:,}: "
                             "confirm with --yes, or narrow the axes")


def _scenarios(ck: _Checker, axes: list[list[Any]], matchers: list, heights, rect,
               cover: float) -> tuple[list[Scenario], int]:
    """Every combination of the axes the excludes keep, as scenarios, and how many were
    excluded; an exclude that matches nothing is refused."""
    scenarios: list[Scenario] = []
    used, excluded = [False] * len(matchers), 0
    for pf, arr, lv, pa, dens, per, sun, opt, ph in itertools.product(*axes):
        if ph is not None and (opt is None or opt.optics().band != "par"):
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
        group, full = _scenario_inputs(pf, arr, lv, pa, sun, dens, per, heights, rect, cover,
                                       opt, ph)
        scenarios.append(Scenario(len(scenarios), _digest(full)[:24], _digest(group)[:24], pf, arr,
                                  lv, pa, sun, dens, per, heights, rect, cover, opt, ph))
    for i, u in enumerate(used):
        if not u:
            ck.fail(f"exclude[{i}]", "matches no scenario (a typo in a value?)")
    return scenarios, excluded


def _matcher(ck: _Checker, entry: dict, where: str) -> Callable[[dict[str, Any]], bool]:
    """A predicate over a scenario's axis values for one ``exclude`` entry."""
    ck.known(entry, AXES, where)
    if not entry:
        ck.fail(where, "is empty: name at least one axis value")
    wants: list[tuple[str, Any]] = []
    for key, v in entry.items():
        w = f"{where}.{key}"
        want: Any
        if key in ("points", "layout"):
            want = ck.text(v, w)                           # a name or a glob
        elif key == "tile":
            want = ck.shape(v, w)
        elif key in ("row_spacing", "plant_spacing"):
            want = ck.spacing(v, w)
        elif key == "density":
            want = ck.number(v, w)
        elif key == "level":
            want = ck.level(v, w)
        elif key in ("preserve_area", "periodic"):
            want = ck.boolean(v, w)
        elif key == "optics":
            want = ck.optics(v, w)
        elif key == "photosynthesis":
            want = ck.photosynthesis(v, w)
        else:                                              # sun: every key given must agree
            if not isinstance(v, dict) or not v:
                ck.fail(w, "must be a table of sun keys, such as {zenith = 30}")
            ck.known(v, SUN_ANGLE_KEYS + SUN_PLACE_KEYS, w)
            want = {k: (x.isoformat() if isinstance(x, (date, datetime, dtime)) else
                        ck.number(x, f"{w}.{k}", positive=False)
                        if isinstance(x, int) and not isinstance(x, bool) else x)
                    for k, x in v.items()}
        wants.append((key, want))
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
