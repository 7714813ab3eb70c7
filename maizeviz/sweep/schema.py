"""The sweep file's schema, declared once: its sections, keys, types, units, ranges, defaults,
which keys are axes, the sun's two forms, the optics table and the leaf models.

The declarations are pydantic models (:class:`SweepFile` and the tables under it); one generic
reader, :func:`validate`, checks a parsed file against them and turns pydantic's first error
into one line naming the file and the key's path (``sweep.toml: light.sun[2].zenith: must be
from 0 to 90 degrees, got 95``). Every validated value is canonical (numbers as float, mesh
levels as the app names them, suns as angles, paths absolute), so that
:mod:`maizeviz.sweep.spec` lists the scenarios and keys them from the model alone.

An axis (:data:`Axis`) is a list whose values are each a scenario's; a single value is a
one-value axis, and a value given twice is refused. The checks the canopy, the sun and the
leaf models make themselves (tile and spacing limits, a sun below the horizon, a leaf model's
parameters) are called from here, so that a file is refused at load, not on every worker.

References
----------
pydantic v2, "Validators" and "Strict mode": https://docs.pydantic.dev/latest/concepts/validators/
"""

from __future__ import annotations

import glob
import json
import os
from datetime import date, datetime
from datetime import time as dtime
from pathlib import Path
from typing import Annotated, Any, ClassVar, NamedTuple, TypeVar

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    Strict,
    ValidationError,
    ValidationInfo,
    model_validator,
)
from pydantic_core import ErrorDetails, PydanticCustomError

from maizeviz.errors import MaizevizError
from maizeviz.light.scene.request import MAX_HEIGHTS
from maizeviz.light.specs import OpticsSpec
from maizeviz.sweep import compute
from maizeviz.sweep.errors import SweepSpecError

#: Heights (cm) every scenario reports when ``light.heights`` is not given.
DEFAULT_HEIGHTS = (0.0, 50.0, 100.0, 150.0, 200.0, 225.0)
#: Most scatterings a sweep follows.
MAX_DEPTH = 50
#: Largest irradiance of a band, W/m2 (as the command line's --irradiance and --diffuse).
MAX_IRRADIANCE = 5000.0
#: Largest scattering seed.
MAX_SEED = 2**31 - 1

T = TypeVar("T")


def _shown(v: Any) -> str:
    """A value as a message quotes it (TOML-ish, at most 60 characters)."""
    if isinstance(v, int) and not isinstance(v, bool) and abs(v) > 2**64:
        return "an integer too large for one"
    text = json.dumps(v, default=str)
    return text if len(text) <= 60 else text[:57] + "..."


def _fail(message: str, at: str | int | None = None) -> PydanticCustomError:
    """A refusal of the value being checked (of its key or item ``at`` when given)."""
    return PydanticCustomError("sweep", message, {"at": at} if at is not None else None)


# ------------------------------------------------------------------------------ value types
def _as_list(v: Any) -> Any:
    return v if isinstance(v, list) else [v]


def _token(v: Any) -> str:
    return json.dumps(v, sort_keys=True, default=str)


def _distinct(values: list) -> list:
    """An axis names each value once (after conversion: "K4" and "K=4" are one level)."""
    seen: dict[str, int] = {}
    for i, v in enumerate(values):
        j = seen.setdefault(_token(v), i)
        if j != i:
            raise PydanticCustomError("repeat", "repeats item {first}", {"at": i, "first": j})
    return values


#: An axis: a list of values (a single value is a one-value axis), not empty, none twice.
Axis = Annotated[list[T], BeforeValidator(_as_list), Field(min_length=1),
                 AfterValidator(_distinct)]


def _within(lo: float, hi: float, unit: str = "", whole: bool = False):
    """A range check [lo, hi], its message naming the range and unit."""
    what = "a whole number from" if whole else "from"
    span = f"{lo} to {hi}" if whole else f"{lo:g} to {hi:g}"

    def check(v):
        if not lo <= v <= hi:
            raise _fail(f"must be {what} {span}{' ' + unit if unit else ''}, got {v:g}")
        return v
    return AfterValidator(check)


#: A finite number (an integer is read as a float; true and false are not numbers).
Number = Annotated[float, Strict(), Field(allow_inf_nan=False)]
Positive = Annotated[Number, Field(gt=0)]
NonNegative = Annotated[Number, Field(ge=0)]
Fraction = Annotated[Number, _within(0, 1)]
Irradiance = Annotated[Number, _within(0, MAX_IRRADIANCE, "W/m2")]
Bool = Annotated[bool, Strict()]


def _iso(v: Any) -> Any:
    """TOML date and time literals as the text they stand for."""
    return v.isoformat() if isinstance(v, (date, datetime, dtime)) else v


def _text(v: Any) -> str:
    if not isinstance(v, str) or not v.strip():
        raise _fail(f"must be a non-empty string, got {_shown(v)}")
    return v


Text = Annotated[str, BeforeValidator(_text)]
TimeText = Annotated[str, BeforeValidator(_text), BeforeValidator(_iso)]


def _shape(quantity: str):
    """A tile count or block shape "AxB", checked as the canopy checks it."""
    def convert(v: Any) -> tuple[int, int]:
        if not isinstance(v, str):
            raise _fail(f"must be a string such as \"3x3\", got {_shown(v)}")
        try:
            shape = compute.parse_tile(v, quantity)
        except MaizevizError:
            raise _fail(f"must look like 3x3 (whole numbers >= 1), got '{v}'") from None
        try:
            return compute.check_shape(shape, quantity)
        except MaizevizError as exc:
            raise _fail(str(exc)) from None
    return BeforeValidator(convert)


def _spacing(name: str):
    """A row or plant spacing in cm, checked as the canopy checks it."""
    def convert(v):
        try:
            return compute.check_spacing(v, name)
        except MaizevizError as exc:
            raise _fail(str(exc)) from None
    return AfterValidator(convert)


def _level(v: Any) -> str:
    if isinstance(v, bool) or not isinstance(v, (str, int)):
        raise _fail(f"must be a level name such as \"K4\", \"standard\" or \"36\", got "
                    f"{_shown(v)}")
    try:
        return compute.level_label(v)
    except (MaizevizError, ValueError) as exc:        # the core has raised both
        raise _fail(str(exc)) from None


def _files(v: Any, info: ValidationInfo) -> list[str]:
    """Absolute paths of the files a path or glob names (relative to the sweep file)."""
    pattern = _text(v)
    base = Path(info.context["base"]) if info.context else Path.cwd()
    full = Path(os.path.expanduser(pattern))
    if not full.is_absolute():
        full = base / full
    if any(c in pattern for c in "*?["):
        found = sorted(p for p in glob.glob(str(full), recursive=True) if os.path.isfile(p))
        if not found:
            raise _fail(f"'{pattern}' matches no file (in {full.parent})")
        return [str(Path(p).resolve()) for p in found]
    if full.is_dir():
        raise _fail(f"{pattern}: is a folder, not a file")
    if not full.is_file():
        raise _fail(f"{pattern}: no such file (looked for {full})")
    return [str(full.resolve())]


Tile = Annotated[tuple[int, int], _shape("tile")]
Block = Annotated[tuple[int, int], _shape("block")]
RowSpacing = Annotated[Positive, _spacing("row spacing")]      # cm
PlantSpacing = Annotated[Positive, _spacing("plant spacing")]  # cm
Level = Annotated[str, BeforeValidator(_level)]
#: The files a path or glob names, absolute.
Files = Annotated[list[str], BeforeValidator(_files)]


def _heights(values: tuple[float, ...]) -> tuple[float, ...]:
    for i, h in enumerate(values):
        if h in values[:i]:
            raise _fail(f"height {h + 0.0:g} cm is given twice", at=i)
    return values


#: Heights above the ground (cm) every scenario reports: not an axis.
Heights = Annotated[tuple[NonNegative, ...], Field(min_length=1, max_length=MAX_HEIGHTS),
                    AfterValidator(_heights)]


def _rect_form(v: Any) -> Any:
    if not isinstance(v, list) or len(v) != 4:
        raise _fail("must be [x0, y0, x1, y1] in cm")
    return tuple(v)


def _rect_order(r: tuple[float, float, float, float]) -> tuple[float, ...]:
    if r[2] <= r[0] or r[3] <= r[1]:
        raise _fail(f"must have x1 > x0 and y1 > y0, got {list(r)}")
    return r


#: The sample rectangle x0, y0, x1, y1 in cm.
Rect = Annotated[tuple[Number, Number, Number, Number], BeforeValidator(_rect_form),
                 AfterValidator(_rect_order)]


# ----------------------------------------------------------------------------------- tables
class Table(BaseModel):
    """A TOML table: its keys are the model's fields; any other key is refused naming the
    keys it may hold. ``example`` says what a table of this kind looks like."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    example: ClassVar[str] = "a table"

    @model_validator(mode="before")
    @classmethod
    def _known_keys(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            raise _fail(f"must be {cls.example}")
        for k in data if cls.model_config.get("extra") == "forbid" else ():
            if k not in cls.model_fields:
                raise PydanticCustomError("unknown_key", "unknown key",
                                          {"key": k, "known": list(cls.model_fields)})
        return data

    def given(self) -> dict[str, Any]:
        """The keys the file gave, with their checked values."""
        return {k: getattr(self, k) for k in self.model_fields_set}


class SunKeys(Table):
    """A sun's keys: angles in degrees, or a place (degrees north and east, m above the sea)
    and a local time (``date``, ``time`` or ``solar_noon``; ``tz`` an IANA zone, default
    UTC). In ``[[exclude]]`` any of them picks the suns that share it."""

    example: ClassVar[str] = ("a table such as {zenith = 30, azimuth = 180} or {date = "
                              "\"2005-08-01\", time = \"12:00\", lat = 39.9, lon = 116.4, tz = "
                              "\"Asia/Shanghai\"}")
    ANGLES: ClassVar[tuple[str, ...]] = ("zenith", "azimuth")

    zenith: Annotated[Number, _within(0, 90, "degrees")] | None = Field(
        None, description="deg from the vertical")
    azimuth: Number | None = Field(None, description="deg clockwise from north")
    date: TimeText | None = Field(None, description="local date, 2005-08-01")
    time: TimeText | None = Field(None, description="local clock time, 12:00")
    solar_noon: Bool | None = Field(None, description="the sun at its highest that day")
    lat: Number | None = Field(None, description="deg north")
    lon: Number | None = Field(None, description="deg east")
    tz: Text | None = Field(None, description="IANA time zone (default UTC)")
    altitude: Number | None = Field(None, description="m above sea level (default 0)")


class SunTable(SunKeys):
    """A sun of the ``light.sun`` axis: in one of its two forms, complete."""

    @model_validator(mode="after")
    def _one_form(self) -> SunTable:
        """Either both angles, or a date, a place and a time (or solar noon)."""
        given = self.model_fields_set
        angles = given & set(self.ANGLES)
        if angles and given - angles:
            raise _fail("give either zenith and azimuth or a place and time, not both")
        for k in self.ANGLES if angles else ("date", "lat", "lon"):
            if k not in given:
                raise _fail("is missing" if angles else "is missing (a sun from a place needs "
                            "date, lat, lon and time or solar_noon)", at=k)
        if not angles and self.time is None and not self.solar_noon:
            raise _fail("is missing (or set solar_noon = true)", at="time")
        return self


def _ranks(v: Any) -> tuple:
    if not isinstance(v, list) or not all(isinstance(r, list) and len(r) == 3 for r in v):
        raise _fail("must be a list of [rank, reflectance, transmittance], such as "
                    "[[1, 0.12, 0.06]]")
    return tuple(tuple(r) for r in v)        # as given: integers stay so in scenario keys


class OpticsTable(Table):
    """Leaf optics with scattering (:class:`maizeviz.light.specs.OpticsSpec`); every key
    optional, the band's maize defaults otherwise."""

    example: ClassVar[str] = ('"black" or a table such as {band = "par", reflectance = 0.1, '
                              'transmittance = 0.05, ground_reflectance = 0.1}')

    band: Annotated[str, BeforeValidator(_text), AfterValidator(str.lower)] = Field(
        "par", description='waveband, "par" or "nir"')
    reflectance: Fraction | None = Field(None, description="leaf, fraction (band's default)")
    transmittance: Fraction | None = Field(None, description="leaf, fraction (band's default)")
    ground_reflectance: Fraction | None = Field(None, description="soil, fraction")
    direct_w_m2: Irradiance | None = Field(None, description="W/m2 on the horizontal (default "
                                                             "the band's share of 1000)")
    diffuse_w_m2: Irradiance = Field(0.0, description="W/m2 from an overcast sky")
    depth: Annotated[int, Strict(), _within(0, MAX_DEPTH, whole=True)] | None = Field(
        None, description="scatterings followed per ray")
    seed: Annotated[int, Strict(), _within(0, MAX_SEED, whole=True)] = Field(
        0, description="of the Monte Carlo scattering")
    ranks: Annotated[tuple, BeforeValidator(_ranks)] = Field(
        (), description="[rank, reflectance, transmittance] per leaf rank, numbers as given")


class LeafModelTable(Table):
    """A leaf photosynthesis model (:func:`maizeviz.photosynthesis.split.leaf_model`) and the
    air temperature in C; any other key is one of the model's parameters (a number, or
    ``temperature_response``'s name), checked by the model itself."""

    model_config = ConfigDict(extra="allow", frozen=True)
    example: ClassVar[str] = '"none" or a table such as {model = "c4", temperature = 30}'
    __pydantic_extra__: dict[str, Number]

    model: Text = Field(description='"c4" or "wofost"')
    temperature: Annotated[Number, _within(-50, 70, "C")] = Field(25.0, description="air, C")
    temperature_response: Text | None = Field(None, description='C4: "collatz" or "clm45"')


def _named_off(*names: str):
    """Optional values: ``false`` or one of ``names`` (any case) stands for None."""
    def convert(v):
        return None if v is False or (isinstance(v, str) and v.lower() in names) else v
    return BeforeValidator(convert)


def _optics_spec(t: OpticsTable | None) -> OpticsSpec | None:
    if t is None:
        return None
    spec = OpticsSpec(**t.given())
    try:
        spec.optics()
    except MaizevizError as exc:
        raise _fail(str(exc)) from None
    return spec


def _leaf_model(t: LeafModelTable | None) -> tuple | None:
    if t is None:
        return None
    from maizeviz.photosynthesis.split import leaf_model

    params = {k: v for k, v in t.given().items() if k not in ("model", "temperature")}
    try:
        model = leaf_model(t.model, **params)
    except MaizevizError as exc:
        raise _fail(str(exc)) from None
    return tuple(sorted({**model.as_dict(), "temperature": t.temperature}.items()))


class ResolvedSun(NamedTuple):
    """A sun of the axis: angles in degrees, the local time it was computed for (None when
    given as angles), and its keys as given (sorted (key, value) pairs)."""

    zenith_deg: float
    azimuth_deg: float
    when: str | None
    given: tuple


def _resolve_sun(t: SunTable) -> ResolvedSun:
    given = t.given()
    try:
        z, a, when = compute.resolve_sun(given)
    except MaizevizError as exc:
        raise _fail(str(exc)) from None
    return ResolvedSun(z, a, when or None, tuple(sorted(given.items())))


#: A sun of the axis, resolved to angles.
Sun = Annotated[SunTable, AfterValidator(_resolve_sun)]
#: Leaf optics: "black" (interception, None) or an :class:`OpticsSpec`.
Optics = Annotated[OpticsTable | None, _named_off("black", "none"),
                   AfterValidator(_optics_spec)]
#: A leaf model: "none" (None) or sorted (key, value) pairs of its parameters and temperature.
LeafModel = Annotated[LeafModelTable | None, _named_off("none"), AfterValidator(_leaf_model)]


class Canopy(Table):
    """``[canopy]``: the points files, arrangements (tilings or layout files) and levels."""

    example: ClassVar[str] = "a table ([canopy])"

    points: Axis[Files] = Field(description="points files; globs, relative to the file")
    tile: Axis[Tile] = Field([(1, 1)], description="AxB copies of the digitized block")
    row_spacing: Axis[RowSpacing] = Field([60.0], description="cm between rows")
    plant_spacing: Axis[PlantSpacing] = Field([30.0], description="cm between plants of a row")
    block: Block | None = Field(None, description="rows x plants of the block (default: "
                                                  "inferred); not an axis")
    layout: Axis[Files] = Field([], description="layout files, besides or instead of tilings")
    level: Axis[Level] = Field(description="mesh levels, as the app's slider names them")
    preserve_area: Axis[Bool] = Field([True], description="below the standard mesh, keep the "
                                                          "smooth leaf area")
    cover_resolution: Positive = Field(0.5, description="cm, the ground-cover pixel; not an "
                                                        "axis")


class Light(Table):
    """``[light]``: suns, ray densities, heights, periodic field, sample rectangle, optics,
    leaf models."""

    example: ClassVar[str] = "a table ([light])"

    sun: Axis[Sun] = Field(description="suns: angles, or a place and a time")
    density: Axis[Positive] = Field([4.0], description="rays per cm2")
    heights: Heights = Field(DEFAULT_HEIGHTS, description="cm above the ground; not an axis: "
                                                          "every scenario reports all")
    periodic: Axis[Bool] = Field([False], description="rays leaving the plot re-enter it")
    rect: Rect | None = Field(None, description="sample rectangle x0, y0, x1, y1 in cm "
                                                "(default: the centre tile); not an axis")
    optics: Axis[Optics] = Field([None], description='leaf optics: "black" (interception) or '
                                                     'a table')
    photosynthesis: Axis[LeafModel] = Field([None], description='"none" or a leaf model, of '
                                                                'PAR scenarios')


class Exclude(Table):
    """One ``[[exclude]]`` entry: values of the axes; the scenarios holding all of them are
    dropped. ``points`` and ``layout`` are names or globs; ``sun`` any of a sun's keys."""

    example: ClassVar[str] = 'a table such as {level = "K4", density = 16}'

    points: Text | None = None
    tile: Tile | None = None
    row_spacing: RowSpacing | None = None
    plant_spacing: PlantSpacing | None = None
    layout: Text | None = None
    level: Level | None = None
    preserve_area: Bool | None = None
    sun: SunKeys | None = None
    density: Positive | None = None
    periodic: Bool | None = None
    optics: Optics = None
    photosynthesis: LeafModel = None

    @model_validator(mode="after")
    def _not_empty(self) -> Exclude:
        if not self.model_fields_set:
            raise _fail("is empty: name at least one axis value")
        if self.sun is not None and not self.sun.model_fields_set:
            raise _fail("must be a table of sun keys, such as {zenith = 30}", at="sun")
        return self


class SweepFile(Table):
    """A sweep file: ``exclude`` (before ``[canopy]``, or as ``[[exclude]]`` tables), then
    ``[canopy]`` and ``[light]``."""

    canopy: Canopy
    light: Light
    exclude: list[Exclude] = []


# ---------------------------------------------------------------------------------- reading
#: pydantic's own errors in this file's words ({got}: the value as given).
MESSAGES = {
    "missing": "is missing",
    "float_type": "must be a number, got {got}",
    "finite_number": "must be a number, got {got}",
    "int_type": "must be a whole number, got {got}",
    "bool_type": "must be true or false, got {got}",
    "string_type": "must be a string, got {got}",
    "list_type": "must be a list, got {got}",
    "tuple_type": "must be a list, got {got}",
    "greater_than": "must be > {gt:g}, got {got}",
    "greater_than_equal": "must be >= {ge:g}, got {got}",
    "too_long": "holds more than {max_length:,} values",
}


def _path(loc: list, doc: Any) -> str:
    """``light.sun[2].zenith`` from pydantic's location, walking the document: an index into
    a single value (a one-value axis) is left out."""
    out, node = "", doc
    for part in loc:
        if isinstance(part, int):
            if isinstance(node, list):
                out += f"[{part}]"
                node = node[part] if part < len(node) else None
        else:
            out += f".{part}" if out else str(part)
            node = node.get(part) if isinstance(node, dict) else None
    return out


def _line(source: str, err: ErrorDetails, doc: dict) -> str:
    """One pydantic error as the file's one line."""
    kind, ctx = err["type"], dict(err.get("ctx") or {})
    loc = list(err["loc"])
    if ctx.get("at") is not None:
        loc.append(ctx["at"])
    path = _path(loc, doc)
    if kind == "unknown_key":
        where = path
        name = f"{where}.{ctx['key']}" if where else ctx["key"]
        if ctx["key"] == "exclude" and where in ("canopy", "light"):
            return (f"{source}: '{name}': exclude belongs at the top of the file, before "
                    "[canopy], or in [[exclude]] tables")
        return (f"{source}: unknown key '{name}' (known{' in ' + where if where else ''}: "
                f"{', '.join(ctx['known'])})")
    if kind == "repeat":
        message = f"repeats {_path(list(err['loc']), doc)}[{ctx['first']}]"
    elif kind == "too_short":
        message = "is empty: give at least one value"
    elif kind == "missing" and len(loc) == 1:
        return f"{source}: the [{path}] table is missing"
    elif kind in MESSAGES:
        message = MESSAGES[kind].format(got=_shown(err.get("input")), **ctx)
    else:                                          # this schema's own refusals
        message = err["msg"]
    return f"{source}: {path or 'the file'}: {message}"


def validate(doc: dict, source: str, base: Path) -> SweepFile:
    """The parsed sweep file ``doc`` checked against the schema.

    Parameters
    ----------
    doc : dict
        The file's TOML, as :func:`tomllib.loads` gives it.
    source : str
        The file as the messages name it.
    base : Path
        The folder that relative paths and globs are relative to.

    Returns
    -------
    SweepFile
        Every key checked and converted (numbers as float, suns resolved, paths absolute).

    Raises
    ------
    SweepSpecError
        One line: ``source: key.path[i]: what is wrong``.
    """
    try:
        return SweepFile.model_validate(doc, context={"base": str(base)})
    except ValidationError as exc:
        first = exc.errors(include_url=False)[0]
        # one line, whatever the file's keys and values hold (TOML keys may be "a\nb")
        raise SweepSpecError(" ".join(_line(source, first, doc).split())) from None
