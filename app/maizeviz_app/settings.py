"""The study's settings as evented objects, without Qt: what the canopy is built at, how light
is traced, where the digitizer is connected.

Each group is a dataclass made evented by psygnal (as napari's ``Dims`` or ``Camera``): setting
a field emits ``settings.events.<field>(new, old)`` when the value changes, and
``settings.events`` relays every field's change. The model owns them
(:attr:`maizeviz_app.model.StudyModel.settings`); widgets bind to them both ways
(:mod:`maizeviz_app.bind`), undo records their changes (:mod:`maizeviz_app.undo`), a project
saves them (:meth:`StudySettings.light_doc`), and a script or a test sets them with no window::

    model.settings.sun.zenith_deg = 30.0
    model.settings.sampling.heights = "0, 100"
    model.compute_light()

Values are kept as typed (heights as text, the day as a date string); they become the core's
requests when a computation starts (:meth:`StudySettings.sun_request` and its siblings), which
refuse a value that cannot be used with an :class:`InputProblem` naming the field.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any, ClassVar

from psygnal import SignalGroup, evented

from maizeviz.errors import MaizevizError
from maizeviz.io.points import shown
from maizeviz.numbers import number

DEFAULT_PLACE = "2005-08-01 12:00 39.9 116.4 Asia/Shanghai"
DEFAULT_HEIGHTS = "0, 50, 100, 150, 200, 225"
#: µmol of PAR photons per joule of shortwave (maizeviz.light.sources.irradiance's default,
#: 0.48 x 4.57, kept here as a number: the window makes its settings before the core is
#: imported; a test holds it equal to the core's).
DEFAULT_PAR_FACTOR = 0.48 * 4.57
#: Most scatterings followed per ray (maizeviz.light.trace.scatter.DEFAULT_DEPTH, likewise).
DEFAULT_DEPTH = 20
#: Band defaults of the leaf and soil optics (maizeviz.light.trace.optics.DEFAULT_OPTICS) and the
#: band's direct irradiance (its share of 1000 W/m2 of shortwave), filled in lazily.
_BAND_DEFAULTS: dict[str, tuple[float, float, float, float]] = {}
#: The lights the app computes.
MODES = ("sun", "sky", "day")


class InputProblem(MaizevizError):
    """A light setting that cannot be used; ``quantity`` names the field. A MaizevizError:
    the user's to correct, told in one line, never an internal error."""

    def __init__(self, message: str, quantity: str):
        super().__init__(message, quantity=quantity)


def parse_heights(text: str) -> tuple[float, ...]:
    """``"0, 50, 100"`` -> (0.0, 50.0, 100.0) cm; a word that is not a number is named.

    Items are separated by commas (or semicolons) and may end in "cm". An empty item (``0,,50``,
    a trailing comma) is refused as ``maizeviz light --heights`` refuses it, with the same
    words: a height left out by a slip should not pass unseen.
    """
    items = text.replace(";", ",").split(",")
    if not "".join(items).strip():
        raise InputProblem("give at least one height in cm, e.g. 0, 50, 100", "heights")
    out = []
    for k, item in enumerate(items, 1):
        part = item.strip()
        if not part:
            raise InputProblem(f"heights: item {k} of {len(items)} is empty in '{shown(text)}'; "
                               "write numbers separated by single commas", "heights")
        try:
            h = number(part.removesuffix("cm").strip())
        except ValueError:
            raise InputProblem(f"heights: '{shown(part)}' is not a number of centimetres; write "
                               "them separated by commas, e.g. 0, 50, 100", "heights") from None
        if not math.isfinite(h) or h < 0:
            raise InputProblem(f"heights must be finite numbers of 0 cm or more, got "
                               f"{shown(part)}", "heights")
        out.append(h)
    return tuple(out)


def band_defaults(band: str) -> tuple[float, float, float, float]:
    """Leaf reflectance, leaf transmittance, soil reflectance and direct W/m2 of a band."""
    if band not in _BAND_DEFAULTS:
        from maizeviz.light.trace.optics import DEFAULT_OPTICS, SHORTWAVE_SHARE

        d = DEFAULT_OPTICS[band]
        _BAND_DEFAULTS[band] = (d.reflectance, d.transmittance, d.ground_reflectance,
                                round(1000.0 * SHORTWAVE_SHARE[band], 1))
    return _BAND_DEFAULTS[band]


def _range(low: float, high: float, unit: str = "") -> dict:
    return {"range": (low, high), "unit": unit}


# ---------------------------------------------------------------------------- the groups
@evented
@dataclass
class CanopySettings:
    """How the canopy is built: the slider's stop (``level``: ``"K4"`` ... ``"4"``), area
    preservation, and the tiling a points file is opened with (tiles along each side)."""

    if TYPE_CHECKING:                           # made by @evented
        events: ClassVar[SignalGroup]

    level: str = "36"
    preserve_area: bool = True
    tile: int = 3


@evented
@dataclass
class LightSettings:
    """Which light a computation traces: ``mode`` sun, sky or day; ``stalks``: the stalks
    intercept and scatter light as the leaves do (``LightEngine(with_stalks=True)``, the
    command line's default), or, off, the leaves alone take it (the paper's canopy,
    ``maizeviz light --leaves-only``)."""

    if TYPE_CHECKING:                           # made by @evented
        events: ClassVar[SignalGroup]

    mode: str = "sun"
    stalks: bool = True


@evented
@dataclass
class SunSettings:
    """The sun's angles (degrees; azimuth clockwise from north) and the place and time the
    angles can be computed from (``place``: ``YYYY-MM-DD HH:MM lat lon tz``)."""

    if TYPE_CHECKING:                           # made by @evented
        events: ClassVar[SignalGroup]

    zenith_deg: float = field(default=22.34, metadata=_range(0.0, 89.9, "°"))
    azimuth_deg: float = field(default=166.95, metadata=_range(0.0, 360.0, "°"))
    place: str = DEFAULT_PLACE


@evented
@dataclass
class SamplingSettings:
    """Shared by every light: sensor plane heights (text, cm, comma separated), rays per cm2,
    and whether the field is periodic (rays wrap at the plot edges)."""

    if TYPE_CHECKING:                           # made by @evented
        events: ClassVar[SignalGroup]

    heights: str = DEFAULT_HEIGHTS
    density: float = field(default=2.0, metadata=_range(0.01, 100.0, "rays/cm²"))
    periodic: bool = True


@evented
@dataclass
class SkySettings:
    """The diffuse sky: ``kind`` soc or uoc; ``split`` auto (16, 46 or 145 directions: a
    turtle or Tregenza's) or equal (an equal-area split of ``directions``)."""

    if TYPE_CHECKING:                           # made by @evented
        events: ClassVar[SignalGroup]

    kind: str = "soc"
    split: str = "auto"
    directions: int = field(default=46, metadata=_range(0, 1000, "directions"))


@evented
@dataclass
class DaySettings:
    """A day at a place: clear sky (Linke turbidity) or a weather file; clock times ``start``
    and ``end`` (``HH:MM``, empty: the whole day); ``diffuse`` sky or perez."""

    if TYPE_CHECKING:                           # made by @evented
        events: ClassVar[SignalGroup]

    date: str = "2005-08-01"
    latitude: float = field(default=39.9, metadata=_range(-90.0, 90.0, "° N"))
    longitude: float = field(default=116.4, metadata=_range(-180.0, 180.0, "° E"))
    tz: str = "Asia/Shanghai"
    step_min: float = field(default=30.0, metadata=_range(0.0, 1440.0, "min"))
    start: str = ""
    end: str = ""
    source: str = "clear"
    linke_turbidity: float = field(default=3.0, metadata=_range(1.0, 10.0))
    weather: str = ""
    par_factor: float = field(default=DEFAULT_PAR_FACTOR, metadata=_range(0.0001, 10.0,
                                                                           "µmol/J"))
    diffuse: str = "sky"


@evented
@dataclass
class OpticsSettings:
    """Leaf optics of a sun (``enabled``: absorbed light with scattering; off: black leaves).
    Choosing a ``band`` sets the leaf and soil optics and the direct irradiance to the band's
    defaults (the fields after it; see :meth:`StudySettings.__init__`)."""

    if TYPE_CHECKING:                           # made by @evented
        events: ClassVar[SignalGroup]

    enabled: bool = False
    band: str = "par"
    reflectance: float = field(default=0.10, metadata=_range(0.0, 1.0))
    transmittance: float = field(default=0.05, metadata=_range(0.0, 1.0))
    ground_reflectance: float = field(default=0.10, metadata=_range(0.0, 1.0))
    direct_w_m2: float = field(default=480.0, metadata=_range(0.0, 2000.0, "W/m²"))
    diffuse_w_m2: float = field(default=0.0, metadata=_range(0.0, 2000.0, "W/m²"))
    depth: int = field(default=DEFAULT_DEPTH, metadata=_range(0, 50))


#: Leaf photosynthesis models the light panel offers ("none": absorbed light only).
PHOTOSYNTHESIS = ("none", "c4", "wofost")
#: The main parameters of each leaf model (the fields of :class:`PhotosynthesisSettings` that
#: are its, by the core's names: maizeviz.photosynthesis.c4.C4Leaf, .wofost.WofostLeaf).
MODEL_PARAMS = {"c4": ("vmax", "alpha", "co2_ppm"), "wofost": ("amax", "eff")}


@evented
@dataclass
class PhotosynthesisSettings:
    """Leaf photosynthesis of a sun's absorbed PAR (leaf optics on, band PAR): ``model``
    none, c4 (Collatz et al. 1992, maize) or wofost (its negative exponential); the leaves'
    ``temperature_c``; the C4 model's Rubisco capacity ``vmax`` at 25 C, quantum yield
    ``alpha``, ambient ``co2_ppm`` and temperature response ``c4_temperature`` (collatz, the
    paper's; clm45, CLM 4.5's); WOFOST's ``amax`` and ``eff``. The defaults are the core's (a
    test holds them equal)."""

    if TYPE_CHECKING:                           # made by @evented
        events: ClassVar[SignalGroup]

    model: str = "none"
    temperature_c: float = field(default=25.0, metadata=_range(-50.0, 70.0, "°C"))
    vmax: float = field(default=39.0, metadata=_range(0.0, 500.0, "µmol/m²/s"))
    alpha: float = field(default=0.04, metadata=_range(0.0, 0.125, "mol/mol"))
    co2_ppm: float = field(default=400.0, metadata=_range(0.0, 5000.0, "ppm"))
    amax: float = field(default=70.0, metadata=_range(0.0, 500.0, "kg CO₂/ha/h"))
    eff: float = field(default=0.45, metadata=_range(0.0, 5.0, "kg CO₂/ha/h per W/m²"))
    c4_temperature: str = "collatz"


@evented
@dataclass
class DigitizerSettings:
    """Where the FASTRAK is connected: the serial port's device and its baud rate."""

    if TYPE_CHECKING:                           # made by @evented
        events: ClassVar[SignalGroup]

    port: str = "/dev/ttyUSB0"
    baud: int = field(default=115200, metadata=_range(1200, 115200, "baud"))


#: Light settings in a project file: key -> (group, field). The keys are those of maizeviz
#: 0.2 onwards (maizeviz_app.saved_state.LIGHT_SETTINGS checks their types), so old projects open.
LIGHT_DOC = {
    "mode": ("light", "mode"), "stalks": ("light", "stalks"),
    "zenith_deg": ("sun", "zenith_deg"), "azimuth_deg": ("sun", "azimuth_deg"),
    "place": ("sun", "place"),
    "heights": ("sampling", "heights"), "density": ("sampling", "density"),
    "periodic": ("sampling", "periodic"),
    "sky_kind": ("sky", "kind"), "sky_split": ("sky", "split"),
    "sky_directions": ("sky", "directions"),
    "day_date": ("day", "date"), "latitude": ("day", "latitude"),
    "longitude": ("day", "longitude"), "tz": ("day", "tz"), "step_min": ("day", "step_min"),
    "from": ("day", "start"), "to": ("day", "end"), "source": ("day", "source"),
    "linke_turbidity": ("day", "linke_turbidity"), "weather": ("day", "weather"),
    "par_factor": ("day", "par_factor"), "day_diffuse": ("day", "diffuse"),
    "optics": ("optics", "enabled"), "band": ("optics", "band"),
    "reflectance": ("optics", "reflectance"), "transmittance": ("optics", "transmittance"),
    "ground_reflectance": ("optics", "ground_reflectance"),
    "direct_w_m2": ("optics", "direct_w_m2"), "diffuse_w_m2": ("optics", "diffuse_w_m2"),
    "depth": ("optics", "depth"),
    "photosynthesis": ("photosynthesis", "model"),
    "leaf_temperature_c": ("photosynthesis", "temperature_c"),
    "c4_vmax": ("photosynthesis", "vmax"), "c4_alpha": ("photosynthesis", "alpha"),
    "co2_ppm": ("photosynthesis", "co2_ppm"), "wofost_amax": ("photosynthesis", "amax"),
    "wofost_eff": ("photosynthesis", "eff"),
    "c4_temperature": ("photosynthesis", "c4_temperature"),
}
#: Choices a text setting may take: (group, field) -> allowed values.
CHOICES = {("light", "mode"): MODES, ("sky", "kind"): ("soc", "uoc"),
           ("sky", "split"): ("auto", "equal"), ("day", "source"): ("clear", "weather"),
           ("day", "diffuse"): ("sky", "perez"), ("optics", "band"): ("par", "nir"),
           ("photosynthesis", "model"): PHOTOSYNTHESIS,
           ("photosynthesis", "c4_temperature"): ("collatz", "clm45")}


def field_names(group: Any) -> list[str]:
    """The fields of a settings group, in declaration order."""
    return [f.name for f in fields(group)]


def field_range(group: Any, name: str) -> tuple[float, float] | None:
    """The (low, high) a numeric field may take (what its widget offers), or None."""
    for f in fields(group):
        if f.name == name:
            return f.metadata.get("range")
    raise AttributeError(name)


class StudySettings:
    """Every settings group of a study, by name (:attr:`groups`): ``canopy``, ``light``,
    ``sun``, ``sampling``, ``sky``, ``day``, ``optics``, ``photosynthesis``, ``digitizer``.

    The one rule between fields lives here: choosing a band sets the optics to the band's
    defaults (as the command line's defaults follow ``--band``)."""

    def __init__(self) -> None:
        self.canopy = CanopySettings()
        self.light = LightSettings()
        self.sun = SunSettings()
        self.sampling = SamplingSettings()
        self.sky = SkySettings()
        self.day = DaySettings()
        self.optics = OpticsSettings()
        self.photosynthesis = PhotosynthesisSettings()
        self.digitizer = DigitizerSettings()
        #: A context several fields set by :meth:`set` change inside (the study's
        #: ``history.step``: one undo step; by default nothing).
        self.together: Callable[[], AbstractContextManager] = nullcontext
        # the PAR defaults are the dataclass's (a test holds them equal to the core's)
        self.optics.events.band.connect(self._band_defaults)

    @property
    def groups(self) -> dict[str, Any]:
        return {"canopy": self.canopy, "light": self.light, "sun": self.sun,
                "sampling": self.sampling, "sky": self.sky, "day": self.day,
                "optics": self.optics, "photosynthesis": self.photosynthesis,
                "digitizer": self.digitizer}

    def _band_defaults(self, band: str, *_old) -> None:
        o = self.optics
        o.reflectance, o.transmittance, o.ground_reflectance, o.direct_w_m2 = \
            band_defaults(band)

    # ------------------------------------------------------------------ values
    def snapshot(self, name: str) -> dict[str, Any]:
        """A group's values by field."""
        group = self.groups[name]
        return {f: getattr(group, f) for f in field_names(group)}

    def set(self, name: str, values: dict[str, Any]) -> None:
        """Set fields of group ``name`` in declaration order (a band before the optics it
        sets), each checked (:meth:`check`), as one change: inside :attr:`together` (the
        study's undo history makes them one step)."""
        group = self.groups[name]
        checked = {f: self.check(name, f, values[f]) for f in field_names(group) if f in values}
        with self.together():
            for f, value in checked.items():
                setattr(group, f, value)

    def check(self, name: str, key: str, value: Any) -> Any:
        """``value`` for field ``key`` of group ``name``, of the field's type and within its
        range or choices; InputProblem naming the field otherwise."""
        group = self.groups[name]
        default = getattr(type(group)(), key)
        what = f"{name} setting '{key}'"
        if isinstance(default, bool):
            if not isinstance(value, bool):
                raise InputProblem(f"{what} must be true or false, got {value!r}", key)
            return value
        if isinstance(default, (int, float)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                    not math.isfinite(value):
                raise InputProblem(f"{what} must be a number, got {value!r}", key)
            if isinstance(default, int) and value != int(value):
                raise InputProblem(f"{what} must be a whole number, got {value!r}", key)
            low_high = field_range(group, key)
            if low_high is not None and not low_high[0] <= value <= low_high[1]:
                raise InputProblem(f"{what} is {value:g}; it must be from {low_high[0]:g} to "
                                   f"{low_high[1]:g}", key)
            return type(default)(value)
        if not isinstance(value, str):
            raise InputProblem(f"{what} must be text, got {value!r}", key)
        allowed = CHOICES.get((name, key))
        if allowed is not None and value not in allowed:
            raise InputProblem(f"{what} is '{value}', not one of {', '.join(allowed)}", key)
        return value

    def light_doc(self) -> dict[str, Any]:
        """The light settings as a project stores them."""
        return {key: getattr(self.groups[g], f) for key, (g, f) in LIGHT_DOC.items()}

    def apply_light_doc(self, doc: dict[str, Any]) -> None:
        """Light settings read from a project (keys it lacks keep their values); the optics'
        band first, so its values are the project's, not the band's defaults."""
        by_group: dict[str, dict[str, Any]] = {}
        for key, (g, f) in LIGHT_DOC.items():
            if key in doc:
                by_group.setdefault(g, {})[f] = doc[key]
        if "stalks" not in doc:
            # saved before the app had a leaves-only switch: its stalks took light
            by_group.setdefault("light", {})["stalks"] = True
        if doc.get("photosynthesis") == "c4" and "c4_temperature" not in doc:
            # saved before the C4 temperature response was a choice: CLM 4.5's, what it computed
            by_group["photosynthesis"]["c4_temperature"] = "clm45"
        if by_group.get("sky", {}).get("split") == "auto" and \
                by_group["sky"].get("directions", 46) not in (16, 46, 145):
            by_group["sky"]["split"] = "equal"
        for g in ("optics", "photosynthesis", "sun", "sampling", "sky", "day", "light"):
            if g in by_group:
                self.set(g, by_group[g])

    def canopy_doc(self) -> dict[str, Any]:
        """The canopy settings as a project stores them (``tile`` is the layout's)."""
        c = self.canopy
        return {"tile": c.tile, "level": c.level, "preserve_area": c.preserve_area}

    # ------------------------------------------------------------------ requests
    def sampling_spec(self):
        """Heights, density and field (:class:`maizeviz.light.scene.request.Sampling`, 2 tracing
        threads)."""
        from maizeviz.light.scene.request import Sampling

        s = self.sampling
        return Sampling(parse_heights(s.heights), s.density, None, s.periodic, 2)

    def sampling_key(self, heights) -> tuple:
        """What every result of a comparison shares: heights, density, periodic field and
        whether the stalks take light."""
        return (tuple(float(h) for h in heights), self.sampling.density,
                self.sampling.periodic, self.light.stalks)

    def sun_request(self):
        """The sun's light request (hit classes on: the canopy is coloured)."""
        from maizeviz.light.scene.request import LightRequest
        from maizeviz.light.sources.sun import Sun

        return LightRequest(Sun(self.sun.zenith_deg, self.sun.azimuth_deg),
                            self.sampling_spec(), classes=True)

    def sky_spec(self):
        """The sky chosen (:class:`maizeviz.light.specs.SkySpec`)."""
        from maizeviz.light.specs import SkySpec

        s = self.sky
        return SkySpec(s.kind, int(s.directions), "equal" if s.split == "equal" else "auto")

    def day_spec(self):
        """The day chosen (:class:`maizeviz.light.specs.DaySpec`); an empty weather file is
        refused here, the rest (clock times included) by the core when the period is made."""
        from maizeviz.light.specs import DaySpec

        d = self.day
        weather = None
        if d.source == "weather":
            weather = d.weather.strip()
            if not weather:
                raise InputProblem("choose a weather file (CSV with a time column and ghi in "
                                   "W/m²), or use the clear sky", "weather")
        return DaySpec(d.date, d.latitude, d.longitude, d.tz.strip(), d.step_min,
                       d.start.strip() or None, d.end.strip() or None, d.linke_turbidity,
                       d.par_factor, weather, d.diffuse)

    def optics_spec(self):
        """Absorbed light as chosen (:class:`maizeviz.light.specs.OpticsSpec`), with the leaf
        model when one is chosen; None when leaf optics are off. Leaf scattering above 1, or
        photosynthesis from NIR, refused naming the field."""
        from maizeviz.light.specs import OpticsSpec

        o = self.optics
        if not o.enabled:
            return None
        model, temperature, params = self.photosynthesis_choice()
        spec = OpticsSpec(o.band, o.reflectance, o.transmittance, o.ground_reflectance,
                          o.direct_w_m2, o.diffuse_w_m2, o.depth, photosynthesis=model,
                          temperature_c=temperature, photosynthesis_params=params,
                          c4_temperature=self.photosynthesis.c4_temperature)
        spec.optics()                                   # checked now, named by the core
        spec.leaf_model()
        return spec

    def photosynthesis_choice(self) -> tuple[str, float, tuple]:
        """The leaf model as :class:`maizeviz.light.specs.OpticsSpec` takes it: its name (""
        for none), the leaf temperature (C) and the main parameters that differ from the
        model's defaults, as ``((name, value), ...)`` in :data:`MODEL_PARAMS` order."""
        p = self.photosynthesis
        if p.model == "none":
            return "", 25.0, ()
        default = PhotosynthesisSettings()
        params = tuple((k, float(getattr(p, k))) for k in MODEL_PARAMS[p.model]
                       if getattr(p, k) != getattr(default, k))
        return p.model, float(p.temperature_c), params
