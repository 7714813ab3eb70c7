"""``maizeviz light``: sunlight and skylight through the canopy with Embree (Table 3 and beyond).

Three things can be asked, alone or together: a single sun (angles, or a place and a clock
time), a diffuse sky (``--sky``), and a day or a period (``--day``, ``--from/--to``,
``--weather``), whose diffuse part uses the sky traced once for the whole period.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from maizeviz.canopy.export import export_canopy
from maizeviz.canopy.field import canopy_of
from maizeviz.canopy.from_mesh import MESH_LEVEL
from maizeviz.canopy.scene import Canopy
from maizeviz.cli.common import (
    NUMBER_ARG,
    WHOLE_ARG,
    Progress,
    add_canopy_options,
    add_level_options,
    canopy_setup,
    check_canopy_costs,
    check_export,
    check_input_options,
    floats,
    fmt_table,
    input_name,
    is_mesh,
    leaves_summary,
    level_path,
    levels_from,
    mesh_setup,
    say,
    say_estimate,
)
from maizeviz.cli.stalk_light import stalk_line, stalk_record, with_stalk_columns
from maizeviz.cost import check, light_costs, mesh_cost
from maizeviz.errors import LeafError, MaizevizError, check_range
from maizeviz.io.atomic import file_tag, make_folder, write_rows
from maizeviz.io.outputs import OutputFolder, check_run_paths
from maizeviz.leaf.fit import Leaf
from maizeviz.light.engine import LightEngine
from maizeviz.light.report.beer_lambert import BeerLambert, beer_lambert, beer_lambert_sky, clumping
from maizeviz.light.report.heatmap import map_stems, save_figure, write_heatmaps
from maizeviz.light.report.mesh_export import light_cells
from maizeviz.light.report.tables import write_steps
from maizeviz.light.results.absorbed import AbsorbedLight
from maizeviz.light.results.assimilation import assimilate
from maizeviz.light.results.diffuse import PeriodLight, SkyLight
from maizeviz.light.results.direct import LightResult
from maizeviz.light.results.per_leaf import merge_rows, plant_light
from maizeviz.light.scene.request import Sampling
from maizeviz.light.sources.irradiance import (
    DEFAULT_LINKE_TURBIDITY,
    DEFAULT_PAR_UMOL_PER_J,
    PAR_UMOL_PER_J_PAR,
    Period,
    WeatherFileError,
    clear_sky_period,
    read_weather,
    weather_period,
)
from maizeviz.light.sources.perez import PEREZ_MODELS, split_summary
from maizeviz.light.sources.sky import SKY_KINDS, Sky, make_sky
from maizeviz.light.sources.sun import Sun, sun_at
from maizeviz.light.trace.optics import BANDS, optics_for, read_optics_table
from maizeviz.light.trace.precision import check_precision, trace_until
from maizeviz.light.trace.scatter import DEFAULT_DEPTH
from maizeviz.mesh.levels import CANOPY_LEVELS
from maizeviz.photosynthesis.c4 import TEMPERATURE_RESPONSES
from maizeviz.photosynthesis.split import MODELS, LeafModel, leaf_model

#: The subcommand.
NAME = "light"
#: ``--sky`` of a period whose diffuse light is split by Perez's model, step by step.
PEREZ = "perez"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        NAME, help="sunlight and skylight through the canopy with Embree (Table 3)",
        description="Trace parallel rays through a canopy for a sun, a diffuse sky or a whole "
                    "day: transmission on sensor planes at several heights over a sample "
                    "rectangle, light intercepted per leaf and per plant, per mesh level with "
                    "timings.")
    add_canopy_options(p)
    add_level_options(p, CANOPY_LEVELS)
    sun = p.add_argument_group("sun (explicit angles, or place + date + time through pvlib)")
    sun.add_argument("--sun-zenith", type=NUMBER_ARG, metavar="DEG", help="zenith angle, degrees")
    sun.add_argument("--sun-azimuth", type=NUMBER_ARG, metavar="DEG",
                     help="azimuth, degrees clockwise from north (field y = north by default)")
    sun.add_argument("--date", help="YYYY-MM-DD")
    sun.add_argument("--time", help="local clock time HH:MM (or HH:MM+08:00 with its offset)")
    sun.add_argument("--solar-noon", action="store_true", help="the true solar noon of --date")
    sun.add_argument("--lat", type=NUMBER_ARG, help="latitude, degrees north")
    sun.add_argument("--lon", type=NUMBER_ARG, help="longitude, degrees east")
    sun.add_argument("--tz", default=None,
                     help="time zone, e.g. Asia/Shanghai (default UTC, or the offset of --time)")
    sky = p.add_argument_group("diffuse sky")
    sky.add_argument("--sky", choices=[*sorted(SKY_KINDS), PEREZ],
                     help="soc: standard overcast (radiance (1 + 2 cos zenith)/3), uoc: uniform "
                          "overcast; a period uses soc unless told; perez (a period only): "
                          "each time step's diffuse light split by Perez's anisotropic model "
                          "(pvlib), its circumsolar part traced with the sun, the rest over a "
                          "uniform sky")
    sky.add_argument("--sky-directions", type=WHOLE_ARG, default=None, metavar="N",
                     help="directions of the sky: 6, 16, 46 (den Dulk's turtle), 145 (Tregenza) "
                          "or any N >= 1 (equal solid angles); default 46")
    per = p.add_argument_group("a day or a period (sun every --step, sky once)")
    per.add_argument("--day", action="store_true", help="the whole of --date, 00:00 to 24:00")
    per.add_argument("--from", dest="from_", metavar="HH:MM",
                     help="start of the period on --date (local clock time)")
    per.add_argument("--to", metavar="HH:MM", help="end of the period on --date")
    per.add_argument("--step", type=NUMBER_ARG, default=None, metavar="MIN",
                     help="time step, minutes (default 30)")
    per.add_argument("--weather", metavar="FILE",
                     help="irradiance from a weather file instead of the clear sky: maizeviz's "
                          "CSV (time with zone, ghi W/m2, optional dni, dhi, par umol/m2/s, "
                          "temp_air), an EPW, TMY3 or NSRDB PSM3/PSM4 file; the file sets the "
                          "period (and, EPW/TMY3/PSM, the time zone and the place)")
    per.add_argument("--linke-turbidity", type=NUMBER_ARG, default=None, metavar="T",
                     help=f"Linke turbidity of the clear sky (default {DEFAULT_LINKE_TURBIDITY:g})")
    per.add_argument("--altitude", type=NUMBER_ARG, default=0.0, metavar="M",
                     help="site altitude, m (clear sky and sun positions; default 0)")
    per.add_argument("--par-factor", type=NUMBER_ARG, default=None, metavar="UMOL_PER_J",
                     help=f"umol of PAR per J of shortwave (default 0.48 x 4.57 = "
                          f"{DEFAULT_PAR_UMOL_PER_J:.4g})")
    per.add_argument("--steps", metavar="CSV", help="write one line per time step")
    per.add_argument("--plots", metavar="DIR",
                     help="write PNGs of the period: PAR through the day, transmission profile")
    p.add_argument("--heights", default="0,50,100,150,200,225", metavar="CM,...",
                   help="heights of the sensor planes, cm (default 0,50,100,150,200,225)")
    p.add_argument("--density", type=NUMBER_ARG, default=4.0,
                   help="rays (and sensors) per cm2 of the sample rectangle (default 4)")
    p.add_argument("--rect", metavar="X0,Y0,X1,Y1",
                   help="sample rectangle, cm (default: the central tile)")
    p.add_argument("--periodic", action="store_true",
                   help="rays leaving the plot sideways re-enter on the other side (infinite field)")
    p.add_argument("--threads", type=WHOLE_ARG, default=os.cpu_count() or 1,
                   help="tracing threads (default: all cores)")
    p.add_argument("--leaves-only", action="store_true",
                   help="stalks take no light (the paper's canopy); by default they intercept "
                        "and scatter light like any organ, their share reported apart")
    p.add_argument("--with-stalks", action="store_true",
                   help="stalks take light (the default; kept for older scripts)")
    p.add_argument("--check", action="store_true",
                   help="print Beer-Lambert exp(-G L(h)/cos theta) from the mesh beside each value")
    p.add_argument("--json", action="store_true", help="print JSON instead of tables")
    p.add_argument("--verbose", action="store_true",
                   help="print the sky's directions and weights on stderr")
    p.add_argument("--heatmaps", metavar="DIR", help="write a transmission map PNG + CSV per height")
    p.add_argument("--heatmap-bin", type=NUMBER_ARG, default=5.0, metavar="CM",
                   help="heatmap bin size, cm (default 5)")
    p.add_argument("--leaf-light", metavar="CSV",
                   help="write the light intercepted by every lit leaf")
    p.add_argument("--plant-light", metavar="CSV", help="the same summed per plant")
    p.add_argument("--export", metavar="PATH",
                   help="write the canopy mesh of one level with each triangle's light (its "
                        "leaf's, as --leaf-light): .vtu .vtp .vtk .ply .obj .stl")
    ab = p.add_argument_group(
        "absorbed light with scattering (any of these turns it on; needs a sun)")
    ab.add_argument("--band", choices=BANDS, default=None,
                    help="waveband: par (default) or nir, with its default optics")
    ab.add_argument("--reflectance", type=NUMBER_ARG, default=None, metavar="R",
                    help="leaf reflectance in the band (PAR default 0.10, NIR 0.45)")
    ab.add_argument("--transmittance", type=NUMBER_ARG, default=None, metavar="T",
                    help="leaf transmittance in the band (PAR default 0.05, NIR 0.40)")
    ab.add_argument("--ground-reflectance", type=NUMBER_ARG, default=None, metavar="G",
                    help="soil reflectance in the band (PAR default 0.10, NIR 0.25)")
    ab.add_argument("--optics-table", metavar="CSV",
                    help="leaf optics per leaf rank: a CSV with rank,reflectance,transmittance "
                         "(and optionally band); ranks it does not name take --reflectance and "
                         "--transmittance (or the band's defaults)")
    ab.add_argument("--irradiance", type=NUMBER_ARG, default=None, metavar="W_M2",
                    help="the band's direct irradiance on a horizontal plane, W/m2 (default "
                         "its share of 1000 W/m2: PAR 480, NIR 520)")
    ab.add_argument("--diffuse", type=NUMBER_ARG, default=0.0, metavar="W_M2",
                    help="the band's diffuse irradiance on a horizontal plane, W/m2, spread "
                         "over --sky (default soc) (default 0)")
    ab.add_argument("--depth", type=WHOLE_ARG, default=None, metavar="N",
                    help=f"most scatterings followed per ray (default {DEFAULT_DEPTH})")
    ab.add_argument("--seed", type=WHOLE_ARG, default=None, help="random seed (default 0)")
    ab.add_argument("--precision", type=NUMBER_ARG, default=None, metavar="REL_SE",
                    help="trace denser until the relative Monte Carlo standard error of the "
                         "leaves' absorbed light (of the canopy's assimilation with "
                         "--photosynthesis) is at most this (0.005: 0.5 %%), and so is its bias "
                         "from the density (estimated from halves of the same rays)")
    ph = p.add_argument_group(
        "photosynthesis from the absorbed PAR (turns absorbed light on; the sun, or a period)")
    ph.add_argument("--photosynthesis", choices=MODELS, default=None,
                    help="leaf model: c4 (Collatz et al. 1992, maize) or wofost (negative "
                         "exponential)")
    ph.add_argument("--c4-temperature", choices=tuple(TEMPERATURE_RESPONSES), default=None,
                    help="c4: how Vmax falls in heat and cold: collatz (the paper's own, "
                         "Vmax 44.7 at 35 C; default) or clm45 (CLM 4.5's, 62.6 at 35 C; "
                         "what maizeviz 0.2 computed)")
    ph.add_argument("--amax", type=NUMBER_ARG, default=None, metavar="KG_HA_H",
                    help="wofost: gross assimilation at light saturation, kg CO2/ha leaf/h "
                         "(default 70)")
    ph.add_argument("--eff", type=NUMBER_ARG, default=None, metavar="KG_HA_H_PER_W_M2",
                    help="wofost: initial light use efficiency, kg CO2/ha/h per J/m2/s of "
                         "absorbed PAR (default 0.45)")
    ph.add_argument("--vmax", type=NUMBER_ARG, default=None, metavar="UMOL_M2_S",
                    help="c4: Rubisco capacity at 25 C, umol/m2/s (default 39)")
    ph.add_argument("--alpha", type=NUMBER_ARG, default=None, metavar="MOL_MOL",
                    help="c4: quantum yield, mol CO2 per mol of PAR photons the leaf "
                         "absorbs (default 0.04; a model that applies it to incident "
                         "photons, as BioCro does, is alpha / absorptance here)")
    ph.add_argument("--co2", type=NUMBER_ARG, default=None, metavar="PPM",
                    help="c4: ambient CO2, umol/mol (default 400; intercellular 0.4 of it)")
    ph.add_argument("--temperature", type=NUMBER_ARG, default=None, metavar="C",
                    help="air (leaf) temperature, C (default 25; a weather file's own air "
                         "temperature when it has one)")
    p.set_defaults(run=run)


def _absorbed_asked(args: argparse.Namespace) -> bool:
    return any(v is not None for v in (args.band, args.reflectance, args.transmittance,
                                        args.ground_reflectance, args.irradiance,
                                        args.optics_table, args.depth, args.seed,
                                        args.photosynthesis, args.precision)) or \
        bool(args.diffuse)


def _leaf_model_from(args: argparse.Namespace) -> LeafModel | None:
    """The leaf model ``--photosynthesis`` names, with its flags; refuses another model's
    flags and photosynthesis from NIR."""
    own = {"c4": ("vmax", "alpha", "co2", "c4_temperature"), "wofost": ("amax", "eff")}
    given = [k for k in ("vmax", "alpha", "co2", "c4_temperature", "amax", "eff",
                         "temperature")
             if getattr(args, k) is not None]
    if args.photosynthesis is None:
        if given:
            raise MaizevizError(f"--{given[0].replace('_', '-')} is a parameter of leaf "
                                "photosynthesis: add "
                                "--photosynthesis c4 or wofost", quantity="photosynthesis")
        return None
    other = [k for k in given if k != "temperature" and k not in own[args.photosynthesis]]
    if other:
        raise MaizevizError(f"--{other[0].replace('_', '-')} is not a parameter of the "
                            f"{args.photosynthesis} "
                            "model", quantity="photosynthesis")
    if args.band == "nir":
        raise MaizevizError("photosynthesis works from absorbed PAR: give no --band nir",
                            quantity="band")
    if args.temperature is not None:
        check_range(args.temperature, "the air temperature (C)", -50, 70, "temperature")
    return leaf_model(args.photosynthesis, vmax=args.vmax, alpha=args.alpha,
                      co2_ppm=args.co2, temperature_response=args.c4_temperature,
                      amax=args.amax, eff=args.eff)


# ------------------------------------------------------------------------------ what is asked
def _period_asked(args: argparse.Namespace) -> bool:
    return bool(args.day or args.from_ or args.to or args.weather)


def _check_options(args: argparse.Namespace) -> None:
    """Refuse options that contradict each other, one line each."""
    explicit = args.sun_zenith is not None or args.sun_azimuth is not None
    if args.sky == PEREZ and not _period_asked(args):
        raise MaizevizError("--sky perez splits the diffuse light of each time step by the "
                            "sun's place and the sky's clearness: it needs a period (--day, "
                            "--from/--to or --weather with --date, --lat and --lon)")
    if _period_asked(args):
        what = "--weather" if args.weather else ("--day" if args.day else "--from/--to")
        if explicit:
            raise MaizevizError(f"{what} follows the sun through the period: give no "
                                "--sun-zenith/--sun-azimuth")
        if args.time or args.solar_noon:
            raise MaizevizError(f"{what} follows the sun through the period: give no --time or "
                                "--solar-noon")
        if args.day and (args.from_ or args.to):
            raise MaizevizError("give either --day or --from/--to, not both")
        if args.weather:
            if args.day or args.from_ or args.to or args.step is not None:
                raise MaizevizError("the weather file sets the period and its steps: give no "
                                    "--day, --from, --to or --step with --weather")
            if args.linke_turbidity is not None:
                raise MaizevizError("--linke-turbidity is for the clear sky, not for --weather")
            if (args.lat is None) != (args.lon is None):
                raise MaizevizError("give both --lat and --lon (or neither, with a weather file "
                                    "whose header gives the place: EPW, TMY3, PSM)")
        else:
            if args.date is None or args.lat is None or args.lon is None:
                raise MaizevizError(f"{what} needs --date, --lat and --lon (and --tz)")
        return
    for flag, value in (("--step", args.step), ("--linke-turbidity", args.linke_turbidity),
                        ("--par-factor", args.par_factor), ("--steps", args.steps),
                        ("--plots", args.plots)):
        if value is not None:
            raise MaizevizError(f"{flag} is for a period: add --day (or --from/--to, or "
                                "--weather) with --date, --lat and --lon")
    if args.sky_directions is not None and args.sky is None:
        raise MaizevizError("--sky-directions needs --sky (soc or uoc) or a period")


def sun_from(args: argparse.Namespace) -> Sun | None:
    """The single sun of the command line: explicit angles, or a place and time through pvlib;
    None when only a sky or a period is asked for."""
    explicit = args.sun_zenith is not None or args.sun_azimuth is not None
    place = any(v is not None for v in (args.date, args.time, args.lat, args.lon)) or args.solar_noon
    if _period_asked(args):
        return None
    if explicit and place:
        raise MaizevizError("give either --sun-zenith/--sun-azimuth or a place and time, not both")
    if explicit:
        if args.sun_zenith is None or args.sun_azimuth is None:
            raise MaizevizError("give both --sun-zenith and --sun-azimuth")
        return Sun(args.sun_zenith, args.sun_azimuth)
    if not place:
        if args.sky is not None:
            return None
        raise MaizevizError("where is the sun? give --sun-zenith and --sun-azimuth, or --date, "
                            "--time (or --solar-noon), --lat, --lon and --tz; or --sky soc for "
                            "an overcast sky, or --day for a whole day")
    if args.date is None or args.lat is None or args.lon is None:
        raise MaizevizError("a sun from a place needs --date, --lat and --lon (and --time or "
                            "--solar-noon, --tz)")
    if not args.time and not args.solar_noon:
        raise MaizevizError("give --time HH:MM or --solar-noon for one sun, or --day (or "
                            "--from/--to) for a period")
    return sun_at(args.date, args.time, args.lat, args.lon, args.tz, args.solar_noon,
                  args.altitude)


def period_from(args: argparse.Namespace) -> Period | None:
    """The period of the command line (clear sky or weather file), or None."""
    if not _period_asked(args):
        return None
    par = DEFAULT_PAR_UMOL_PER_J if args.par_factor is None else args.par_factor
    if args.weather:
        weather = read_weather(args.weather, tz=args.tz)
        lat, lon = args.lat, args.lon
        if lat is None:
            lat, lon = weather.place.get("latitude"), weather.place.get("longitude")
            if lat is None or lon is None:
                problem = weather.place.get("problem")
                raise MaizevizError(f"{os.path.basename(args.weather)}: {problem}, not a "
                                    "place: give --lat and --lon" if problem else
                                    "a weather CSV file needs the place: give --lat and --lon",
                                    quantity="weather")
            say(f"place: latitude {lat:g}, longitude {lon:g} (the header of "
                f"{os.path.basename(args.weather)})")
        period = weather_period(weather, lat, lon, args.altitude, par)
        if args.photosynthesis:
            check_air_temperature(weather, period)
        return period
    linke = DEFAULT_LINKE_TURBIDITY if args.linke_turbidity is None else args.linke_turbidity
    return clear_sky_period(args.date, args.lat, args.lon, args.tz or "UTC",
                            30.0 if args.step is None else args.step, args.from_, args.to,
                            args.altitude, linke, par)


#: Air temperatures the leaf models take [deg C] (those of ``assimilate``).
LEAF_TEMPERATURE_C = (-50.0, 70.0)


def check_air_temperature(weather, period: Period) -> None:
    """Refuse a weather file's air temperature outside the leaf models' range on a step
    the photosynthesis uses, naming the file and its line (it was blamed on
    ``--temperature``)."""
    temp = weather.temp_air
    if temp is None or period.temp_air is None:
        return
    lo, hi = LEAF_TEMPERATURE_C
    used = np.isin(weather.times.asi8, period.times.asi8)
    with np.errstate(invalid="ignore"):
        bad = np.flatnonzero(used & np.isfinite(temp) & ((temp < lo) | (temp > hi)))
    if len(bad):
        k = int(bad[0])
        raise WeatherFileError(f"{weather.path}, line {int(weather.line[k])} "
                               f"({weather.times[k].isoformat()}), column temp_air: "
                               f"{temp[k]:g} C, outside the {lo:g}..{hi:g} C a leaf model "
                               "takes; correct the cell or trace the light without "
                               "--photosynthesis")


def temperature_note(args: argparse.Namespace, period: Period | None) -> str:
    """Which air temperature is used when ``--temperature`` is given with a weather file
    that has its own: the file's, a measurement of the period traced, and ``--temperature``
    where the file has none (a note, so that a modeller is not surprised)."""
    if args.temperature is None or period is None or period.temp_air is None:
        return ""
    own = np.isfinite(period.temp_air)
    if not own.any():
        return ""
    name = os.path.basename(str(period.parameters.get("weather_file", "the weather file")))
    rest = int((~own).sum())
    fill = f"; --temperature {args.temperature:g} C for the {rest} without one" if rest \
        else f": --temperature {args.temperature:g} C is not used"
    return (f"air temperature: {name}'s own on {int(own.sum())} of {len(own)} steps "
            f"({np.nanmin(period.temp_air):.1f} to {np.nanmax(period.temp_air):.1f} C){fill}")


def sky_from(args: argparse.Namespace, period: Period | None) -> Sky | None:
    """The diffuse sky: --sky, or the standard overcast sky for a period."""
    if args.sky is None and period is None:
        return None
    n = 46 if args.sky_directions is None else args.sky_directions
    return make_sky("uoc" if args.sky == PEREZ else (args.sky or "soc"), n)


# ------------------------------------------------------------------------------ run
@dataclass
class _Job:
    """What one ``maizeviz light`` run traces on every level: its options read and checked
    once, and the warnings already said (each is said once for all levels)."""

    args: argparse.Namespace
    sun: Sun | None
    heights: tuple[float, ...]
    rect: tuple[float, ...] | None
    period: Period | None
    sky: Sky | None
    optics: Any
    leaf_model: LeafModel | None
    temp_c: float
    want_rows: bool
    n_levels: int
    said: set[str] = field(default_factory=set)


@dataclass
class _Level:
    """One level's canopy, engine and outputs as its handlers fill them."""

    canopy: Canopy
    label: str
    engine: LightEngine
    rec: dict[str, Any]
    warnings: list[str] = field(default_factory=list)
    tables: list[list[dict]] = field(default_factory=list)
    plant_extra: dict[int, dict[str, float]] = field(default_factory=dict)
    res: LightResult | None = None
    sky_res: SkyLight | None = None
    per_res: PeriodLight | None = None
    ab: AbsorbedLight | None = None
    abd: Any = None                     # the period's AbsorbedPeriod
    asm: Any = None                     # the sun's Assimilation, with a leaf model


def run(args: argparse.Namespace) -> int:
    """``maizeviz light``: the options read once, then each level traced by one handler per
    light asked for (sun, sky or period, absorbed light over a sun or a period) over the
    level's :class:`LightEngine`, and the tables or JSON written."""
    _check_options(args)
    check_input_options(args)
    mesh = is_mesh(args.points)
    levels = levels_from(args)
    labels = [MESH_LEVEL] if mesh else [level.label for level in levels]
    check_export(args.export, [] if mesh else levels)
    job = _job(args, labels)
    if mesh:
        t0 = time.perf_counter()
        mesh_canopy = mesh_setup(args)
        read_s = time.perf_counter() - t0
        leaves: list[Leaf] = []
        skipped: list[LeafError] = []
        layout = mesh_canopy.layout
    else:
        leaves, skipped, layout = canopy_setup(args)
    work = _costs(job, layout)
    if mesh:
        say_estimate(check([[mesh_cost(mesh_canopy.n_triangles), *work]], args.force))
    else:
        check_canopy_costs(leaves, layout, levels, args.force, work)
    records: list[dict[str, Any]] = []
    for level in [None] if mesh else levels:
        t0 = time.perf_counter()
        if level is None:
            canopy, canopy_s = mesh_canopy, read_s
        else:
            canopy = canopy_of(leaves, layout, level, args.preserve_area,
                               Progress(f"building {level}"))
            canopy_s = time.perf_counter() - t0
        records.append(_trace_level(job, canopy, canopy_s))
    if args.json:
        print(json.dumps(_jsonable(records[0] if len(records) == 1 else {"levels": records}),
                         indent=1))
    else:
        _print_tables(records, job.sun, job.heights, args)
    return leaves_summary(mesh_canopy.n_leaves if mesh else len(leaves), skipped)


def _job(args: argparse.Namespace, labels: list[str]) -> _Job:
    """The run's options read and checked (in the order their errors are said), and what
    it traces announced."""
    sun = sun_from(args)
    heights = tuple(floats(args.heights, "heights", "heights"))
    optics = _absorbed_optics(args, sun)
    leaf_model_ = _leaf_model_from(args)
    temp_c = 25.0 if args.temperature is None else args.temperature
    if optics is not None:
        optics = _checked_scattering(args, optics)
    rect = tuple(floats(args.rect, "the sample rectangle", "rect", 4)) if args.rect else None
    if not args.heatmap_bin > 0:
        raise MaizevizError(f"the heatmap bin must be > 0 cm, got {args.heatmap_bin}",
                            quantity="heatmap_bin")
    _check_paths(args, labels, sun is not None, heights)
    period = period_from(args)
    sky = sky_from(args, period)
    _announce(args, sun, sky, period)
    if temperature_note(args, period):
        say("note: " + temperature_note(args, period))
    return _Job(args, sun, heights, rect, period, sky, optics, leaf_model_, temp_c,
                bool(args.leaf_light or args.plant_light), len(labels))


def _absorbed_optics(args: argparse.Namespace, sun: Sun | None):
    """The band's optics when absorbed light is asked for (else None), refusing it without a
    sun or a period, or with an irradiance over a period."""
    if not _absorbed_asked(args):
        return None
    if sun is None and not _period_asked(args):
        raise MaizevizError("absorbed light with scattering needs a sun or a period: "
                            "give --sun-zenith/--sun-azimuth, --date, --time, --lat, "
                            "--lon, or --day", quantity="band")
    if sun is None and (args.irradiance is not None or args.diffuse):
        raise MaizevizError("over a period the irradiance is the period's (clear sky or "
                            "weather file): --irradiance and --diffuse are for one sun",
                            quantity="irradiance")
    return optics_for(args.band or "par", args.reflectance, args.transmittance,
                      args.ground_reflectance)


def _checked_scattering(args: argparse.Namespace, optics):
    """The optics with the ranks of ``--optics-table``; the irradiance, depth, seed and
    precision checked (depth and seed given their defaults in ``args``)."""
    if args.optics_table is not None:
        optics = replace(optics, ranks=read_optics_table(args.optics_table, optics.band))
    if args.irradiance is not None:
        check_range(args.irradiance, "the direct irradiance (W/m2)", 0, 5000, "irradiance")
    check_range(args.diffuse, "the diffuse irradiance (W/m2)", 0, 5000, "irradiance")
    args.depth = DEFAULT_DEPTH if args.depth is None else args.depth
    args.seed = 0 if args.seed is None else args.seed
    check_range(args.depth, "the scattering depth", 0, 10_000, "depth", whole=True)
    check_range(args.seed, "the random seed", 0, 2**32 - 1, "seed", whole=True)
    if args.precision is not None:
        check_precision(args.precision)
    return optics


def _announce(args: argparse.Namespace, sun: Sun | None, sky: Sky | None,
              period: Period | None) -> None:
    """One line each for the sun, the sky and the period about to be traced."""
    if sun is not None:
        say(f"sun: zenith {sun.zenith_deg:.2f} deg, azimuth {sun.azimuth_deg:.2f} deg"
            + (f" ({sun.when})" if sun.when else ""))
    if sky is not None:
        say(f"sky: {PEREZ_MODELS[PEREZ]}: each step's circumsolar part traced with the sun, "
            f"its isotropic part over the {sky.description}" if args.sky == PEREZ
            else f"sky: {sky.description}")
        if args.verbose:
            say(sky.table())
    if period is not None:
        say(f"period: {period.start.isoformat()} to {period.end.isoformat()}, "
            f"{period.n_steps} steps with the sun up; {period.source}")


def _costs(job: _Job, layout) -> list:
    """What tracing costs per level (the rays and maps of every direction)."""
    sampled = job.rect or layout.centre_bounds
    directions = (job.sun is not None) + (job.sky.n if job.sky is not None else 0) + \
        (job.period.n_steps if job.period is not None else 0)
    maps = (job.sun is not None) + (job.sky is not None) + (job.period is not None) \
        if job.args.heatmaps else 0
    return light_costs(sampled, job.args.density, len(job.heights), directions, maps,  # type: ignore[arg-type]
                       job.args.heatmap_bin)


def _trace_level(job: _Job, canopy: Canopy, canopy_s: float) -> dict[str, Any]:
    """One level: its engine, then each light asked for, its outputs written; its record."""
    args = job.args
    sampling = Sampling(job.heights, args.density, job.rect, args.periodic, args.threads)  # type: ignore[arg-type]
    if args.leaves_only and args.with_stalks:
        raise MaizevizError("--leaves-only and --with-stalks contradict each other: stalks "
                            "take light by default, --leaves-only leaves them out")
    engine = LightEngine(canopy, sampling, with_stalks=not args.leaves_only)
    engine.scene()
    rec: dict[str, Any] = {"level": canopy.level, "triangles": canopy.n_triangles,
                           "heights_cm": [float(h) for h in job.heights],
                           "periodic": args.periodic, "threads": args.threads,
                           "kernel": "packets" if engine.scene().packets else "embreex",
                           "seconds": {"canopy": canopy_s,
                                       "scene": engine.build_seconds[args.periodic]}}
    lv = _Level(canopy, canopy.level, engine, rec)
    if job.sun is not None:
        _trace_sun(job, lv)
    _trace_diffuse(job, lv)
    _say_once(job, lv.warnings, job.period.notes if job.period else ())
    rec["warnings"] = list(dict.fromkeys(lv.warnings))
    if job.optics is not None and job.sun is None and job.period is not None:
        _trace_absorbed_period(job, lv)
    elif job.optics is not None:
        _trace_absorbed_sun(job, lv)
    if job.sun is None:
        _without_sun(lv)
    rec["stalks"], stalk_rows = stalk_record(canopy, engine.with_stalks, lv.res, lv.sky_res,
                                             lv.ab or lv.abd, lv.per_res)
    _write_outputs(args, canopy, lv.label, job.n_levels, lv.res, lv.sky_res, lv.per_res,
                   lv.tables, lv.plant_extra, stalk_rows)
    if args.export:
        path = export_canopy(args.export, canopy,
                             light_cells(canopy, lv.res, lv.sky_res, lv.per_res, lv.ab,
                                         lv.asm))
        say(f"wrote {canopy.n_triangles:,} leaf triangles of {canopy.n_plants} plants with "
            f"their light (and their stalks) to {path}")
    return rec


def _trace_sun(job: _Job, lv: _Level) -> None:
    """The sun: transmission by height and, for the tables, its hit classes."""
    assert job.sun is not None
    res = lv.engine.sun(job.sun, classes=job.want_rows or job.n_levels == 1
                        or bool(job.args.export),
                        progress=Progress(f"tracing {lv.label}"))
    lv.res = res
    lv.warnings += res.warnings
    lv.rec.update(_sun_record(res, job.sun, lv.canopy, job.args, job.heights))
    lv.rec["seconds"].update(trace=res.seconds["trace"],
                             second_hits=res.seconds.get("second", 0.0))
    if job.want_rows:
        lv.tables.append(res.leaf_rows(lv.canopy))


def _trace_diffuse(job: _Job, lv: _Level) -> None:
    """The period (its suns and its sky) or the sky alone, and their records."""
    args, sky, period = job.args, job.sky, job.period
    if period is not None:
        lv.per_res = lv.engine.day(period, sky=PEREZ if args.sky == PEREZ else sky,
                                   directions=sky.n if sky is not None else 46,
                                   bin_cm=args.heatmap_bin,
                                   progress=Progress(f"tracing the period, {lv.label}"))
        lv.sky_res = lv.per_res.sky
        lv.warnings += lv.per_res.warnings
        lv.rec["seconds"]["period"] = lv.per_res.seconds["trace"]
    elif sky is not None:
        lv.sky_res = lv.engine.sky(sky, progress=Progress(f"tracing the sky, {lv.label}"),
                                   bin_cm=args.heatmap_bin)
        lv.warnings += lv.sky_res.warnings
        lv.rec["seconds"]["sky"] = lv.sky_res.seconds["trace"]
    if lv.sky_res is not None:
        lv.rec["diffuse"] = _sky_record(lv.sky_res, lv.canopy, args, job.heights)
        if args.sky == PEREZ:
            lv.rec["diffuse"]["part"] = "isotropic part of the Perez sky"
        if job.want_rows:
            lv.tables.append(lv.sky_res.leaf_rows(lv.canopy))
    elif sky is not None and period is not None:
        lv.rec["diffuse"] = None                   # the sun never rose: no sky traced
    if lv.per_res is not None:
        lv.rec["period"] = _period_record(lv.per_res, args)
        if job.want_rows:
            lv.tables.append(lv.per_res.leaf_rows(lv.canopy))


def _say_once(job: _Job, warnings: list[str], notes=()) -> None:
    """Each warning (a period's note as a note) said once in the run."""
    for w in warnings:
        if w not in job.said:
            job.said.add(w)
            say(f"{'note' if w in notes else 'warning'}: {w}")


def _trace_absorbed_period(job: _Job, lv: _Level) -> None:
    """Absorbed light over the period (and the leaves' assimilation), at ``--precision``."""
    args = job.args

    def trace_day(density: float):
        d = lv.engine.absorbed_day(job.period, optics=job.optics, sky=args.sky or "soc",
                                   directions=args.sky_directions or 46, depth=args.depth,
                                   seed=args.seed, photosynthesis=job.leaf_model,
                                   temperature_c=job.temp_c, density=density,
                                   progress=Progress(f"absorbed light over the period, "
                                                     f"{lv.label}"))
        if d.assimilation is not None:
            pa, g = d.assimilation, d.assimilation.ground_m2
            return (d, pa.canopy_gross_mol_m2, pa.canopy_gross_error_mol_m2 or 0.0,
                    (pa.bias_mol or 0.0) / g, (pa.bias_se_mol or 0.0) / g)
        return d, d.balance.absorbed_leaves, d.absorbed_leaves_error or 0.0

    abd = lv.abd = _traced(trace_day, args, lv.rec, job.said)
    _warn_unresolved(abd.balance, abd.depth, lv.rec, job.said)
    lv.rec["balance"] = dict(abd.balance.as_dict(), units="MJ/m2 of ground")
    lv.rec["balance_se"] = abd.balance_errors
    lv.rec["absorbed"] = _absorbed_period_record(abd)
    if abd.assimilation is not None:
        lv.rec["photosynthesis"] = abd.assimilation.as_dict()
        if job.want_rows:
            lv.tables.append(_assimilation_rows(lv.canopy, abd.assimilation))
            _merge(lv.plant_extra, _plant_errors(lv.canopy, abd.assimilation))
    if job.want_rows:
        lv.tables.append(_assimilation_rows(lv.canopy, abd))
        _merge(lv.plant_extra, _plant_errors(lv.canopy, abd))
    lv.rec["seconds"]["scatter"] = abd.seconds.get("trace", 0.0) + \
        abd.seconds.get("scatter", 0.0)


def _trace_absorbed_sun(job: _Job, lv: _Level) -> None:
    """Absorbed light under the sun (and a sky), and the leaves' assimilation, at
    ``--precision``."""
    args = job.args

    def trace_sun(density: float):
        a = lv.engine.absorbed(job.sun, optics=job.optics, direct_w_m2=args.irradiance,
                               diffuse_w_m2=args.diffuse, sky=args.sky or "soc",
                               directions=args.sky_directions or 46, depth=args.depth,
                               seed=args.seed, density=density)
        if job.leaf_model is not None:
            g = assimilate(lv.canopy, a, job.leaf_model, job.temp_c)
            return (a, g.canopy_gross_umol_m2_s, g.canopy_gross_error_umol_m2_s or 0.0,
                    g.canopy_gross_bias_umol_m2_s or 0.0,
                    (g.bias_se_umol_s or 0.0) / g.ground_m2)
        return a, a.balance.absorbed_leaves, a.absorbed_leaves_error or 0.0

    ab = lv.ab = _traced(trace_sun, args, lv.rec, job.said)
    _warn_unresolved(ab.balance, ab.depth, lv.rec, job.said)
    lv.rec["balance"] = ab.balance.as_dict()
    lv.rec["balance_se"] = ab.balance_errors
    lv.rec["absorbed"] = _absorbed_record(ab, lv.canopy)
    lv.rec["seconds"]["scatter"] = ab.seconds["trace"] + ab.seconds["scatter"]
    if job.want_rows:
        lv.tables.append(ab.leaf_rows(lv.canopy))
        _merge(lv.plant_extra, _plant_errors(lv.canopy, ab))
    if job.leaf_model is not None:
        asm = lv.asm = assimilate(lv.canopy, ab, job.leaf_model, job.temp_c)
        lv.rec["photosynthesis"] = asm.as_dict()
        _say_once(job, list(asm.warnings))
        if job.want_rows:
            lv.tables.append(_assimilation_rows(lv.canopy, asm))
            _merge(lv.plant_extra, _plant_errors(lv.canopy, asm))


def _without_sun(lv: _Level) -> None:
    """A record without a sun still says its rays, rectangle and density (the sky's or the
    period's)."""
    res = lv.per_res or lv.sky_res
    rays = res.rays if res else 0
    x0, y0, x1, y1 = res.rect if res else (0, 0, 1, 1)
    lv.rec.update(sun=None, transmission=None, rays=rays, rect_cm=[x0, y0, x1, y1],
                  density_per_cm2=rays / ((x1 - x0) * (y1 - y0)))


# ------------------------------------------------------------------------------ records
def _absorbed_record(ab: AbsorbedLight, canopy: Canopy) -> dict[str, Any]:
    """The absorbed light of a level for the JSON output (balance in W/m2 of ground)."""
    o = ab.optics
    out: dict[str, Any] = {
        "band": ab.band, "units": "W/m2 of ground",
        "optics": {"reflectance": o.reflectance, "transmittance": o.transmittance,
                   "ground_reflectance": o.ground_reflectance},
        "fraction_absorbed": ab.fraction_absorbed,
        "sunlit_lai": _sunlit_m2(ab, canopy),
        "rays": ab.rays, "directions": ab.directions, "depth": ab.depth, "seed": ab.seed,
        "scatterings": ab.events}
    se = ab.absorbed_leaves_error
    out["absorbed_leaves_se"] = se
    if ab.band == "par":
        out["absorbed_leaves_umol_m2_s"] = ab.balance.absorbed_leaves * PAR_UMOL_PER_J_PAR
        out["absorbed_leaves_umol_m2_s_se"] = None if se is None else se * PAR_UMOL_PER_J_PAR
    return out


def _absorbed_period_record(ab) -> dict[str, Any]:
    """Absorbed light over a period for the JSON output (balance in MJ/m2 of ground)."""
    o = ab.optics
    out: dict[str, Any] = {
        "band": ab.band, "units": "MJ/m2 of ground",
        "optics": {"reflectance": o.reflectance, "transmittance": o.transmittance,
                   "ground_reflectance": o.ground_reflectance},
        "fraction_absorbed": ab.fraction_absorbed, "rays": ab.rays, "depth": ab.depth,
        "seed": ab.seed,
        "step_absorbed_leaves_w_m2": [float(w) for w in ab.step_absorbed_leaves_w_m2],
        "step_incident_w_m2": [float(w) for w in ab.step_incident_w_m2]}
    se = ab.absorbed_leaves_error
    out["absorbed_leaves_se"] = se
    if ab.band == "par":
        out["absorbed_leaves_mol_m2"] = ab.absorbed_leaves_mol_m2
        out["absorbed_leaves_mol_m2_se"] = None if se is None else se * PAR_UMOL_PER_J_PAR
    return out


def _warn_unresolved(balance, depth: int, rec: dict[str, Any], said: set[str]) -> None:
    """Warn when more than 1 % of the incident light was left unresolved."""
    from maizeviz.light.results.absorbed import UNRESOLVED_WARN, unresolved_warning

    if balance.incident and balance.unresolved > UNRESOLVED_WARN * balance.incident:
        w = unresolved_warning(balance.unresolved / balance.incident, depth)
        rec["warnings"].append(w)
        if w not in said:
            said.add(w)
            say(f"warning: {w}")


def _percent(fraction: float) -> str:
    """A fraction as a percentage with three significant digits, however small (``:.2%``
    wrote a target of 1e-6 as "0.00%")."""
    return f"{100 * fraction:.3g}%"


def _traced(trace, args: argparse.Namespace, rec: dict[str, Any], said: set[str]) -> Any:
    """``trace(density)``'s result at ``--density``, or with ``--precision`` at the density
    that meets it (recorded in ``rec["precision"]``, a warning when it cannot be)."""
    if args.precision is None:
        return trace(args.density)[0]
    result, prec = trace_until(trace, args.density, args.precision)
    rec["precision"] = prec.as_dict()
    bias = ("+" if prec.bias >= 0 else "-") + _percent(abs(prec.bias))
    say(f"precision: relative standard error {_percent(prec.achieved)}, bias from the density "
        f"{bias} at {prec.density:g} rays per cm2 after {prec.passes} "
        f"trace{'s' if prec.passes > 1 else ''}")
    problems = []
    if not prec.noise_met:
        problems.append(f"the relative standard error {_percent(prec.achieved)} is above the "
                        f"{_percent(prec.target)} asked for")
    if not prec.bias_met:
        problems.append(f"the bias from the density, {bias} +- {_percent(prec.bias_se)}, "
                        f"is above the {_percent(prec.target)} asked for")
    for problem in problems:
        w = f"{problem} at the densest tracing allowed ({prec.density:g} rays per cm2)"
        said.add(w)
        say(f"warning: {w}")
        rec["warnings"].append(w)
    return result


def _assimilation_rows(canopy: Canopy, asm: Any) -> list[dict]:
    """Leaf rows of a result's leaf table (an Assimilation, PeriodAssimilation or
    AbsorbedPeriod) for the command line's leaf table."""
    frame = asm.table("leaf", canopy)
    return [] if frame.empty else frame.to_dict("records")


def _merge(into: dict[int, dict[str, float]], more: dict[int, dict[str, float]]) -> None:
    for k, v in more.items():
        into.setdefault(k, {}).update(v)


def _plant_errors(canopy: Canopy, result: Any) -> dict[int, dict[str, float]]:
    """Standard errors per plant (instance): columns ending ``_se`` of ``result``'s plant
    table (absorbed light or assimilation)."""
    frame = result.table("plant", canopy)
    cols = [c for c in frame.columns if c.endswith("_se")]
    return {int(r["instance"]): {c: float(r[c]) for c in cols}
            for r in frame.to_dict("records")}


def _sunlit_m2(ab: AbsorbedLight, canopy: Canopy) -> float:
    """Sunlit leaf area (m2) per m2 of sample ground: the sunlit leaf area index."""
    x0, y0, x1, y1 = ab.rect
    return float(ab.triangle_sunlit_cm2[:canopy.n_triangles].sum()) / ((x1 - x0) * (y1 - y0))


def _sun_record(res: LightResult, sun: Sun, canopy: Canopy, args: argparse.Namespace,
                heights: tuple[float, ...]) -> dict[str, Any]:
    rec: dict[str, Any] = {
        "sun": {"zenith_deg": sun.zenith_deg, "azimuth_deg": sun.azimuth_deg,
                "when": sun.when or None},
        "transmission": [float(t) for t in res.transmission], "rays": res.rays,
        "density_per_cm2": res.density_per_cm2, "rect_cm": list(res.rect)}
    if args.check:
        rec["beer_lambert"] = _beer_lambert_record(beer_lambert(canopy, sun, heights))
    if res.sunlit_intercepted_fraction is not None:
        rec["sunlit_intercepted_fraction"] = res.sunlit_intercepted_fraction
    return rec


def _sky_record(sky: SkyLight, canopy: Canopy, args: argparse.Namespace,
                heights: tuple[float, ...]) -> dict[str, Any]:
    x0, y0, x1, y1 = sky.rect
    rec: dict[str, Any] = {
        "sky": sky.sky.kind, "split": sky.sky.split, "directions": sky.sky.n,
        "description": sky.sky.description, "heights_cm": [float(h) for h in sky.heights_cm],
        "transmission": [float(t) for t in sky.transmission],
        "intercepted_fraction": sky.intercepted_fraction, "rays_per_direction": sky.rays,
        "density_per_cm2": sky.rays / ((x1 - x0) * (y1 - y0)), "rect_cm": list(sky.rect),
        "weights": [float(w) for w in sky.sky.weights],
        "zenith_deg": [float(z) for z in sky.sky.zenith_deg],
        "azimuth_deg": [float(a) for a in sky.sky.azimuth_deg]}
    if args.check:
        rec["beer_lambert"] = _beer_lambert_record(beer_lambert_sky(canopy, sky.sky, heights))
    return rec


def _beer_lambert_record(bl: BeerLambert) -> dict[str, Any]:
    return {"G": bl.G, "lai_above": [float(v) for v in bl.lai_above],
            "transmission": [float(v) for v in bl.transmission]}


def _period_record(pl: PeriodLight, args: argparse.Namespace) -> dict[str, Any]:
    p = pl.period
    rec: dict[str, Any] = {
        "start": p.start.isoformat(), "end": p.end.isoformat(), "steps": p.n_steps,
        "step_min": None if args.weather else (30.0 if args.step is None else args.step),
        "par_umol_per_j": p.par_umol_per_j,
        "shortwave_mj_m2": p.shortwave_mj_m2,
        "par_incident_mol_m2": pl.par_incident_mol_m2,
        "par_direct_mol_m2": pl.par_direct_mol_m2,
        "par_diffuse_mol_m2": pl.par_diffuse_mol_m2,
        "par_intercepted_mol_m2": pl.par_intercepted_mol_m2,
        "fraction_intercepted": pl.fraction_intercepted,
        "par_diffuse_intercepted_mol_m2": pl.par_diffuse_intercepted_mol_m2,
        "transmission_by_height": {
            "heights_cm": [float(h) for h in pl.heights_cm],
            "par_mol_m2": [float(v) for v in pl.par_transmitted_mol_m2],
            "fraction": [None if not math.isfinite(v) else float(v)
                         for v in pl.transmission_by_height],
            "diffuse_fraction": [None if not math.isfinite(v) else float(v)
                                 for v in pl.diffuse_transmission_by_height]},
        "source": p.source, "notes": list(p.notes)}
    d = pl.diffuse
    if d is not None:
        rec["diffuse_model"] = {
            "model": d.model, "description": d.description,
            "isotropic_par_mol_m2": math.fsum(pl.step_sky_mol_m2),
            "circumsolar_par_mol_m2": math.fsum(pl.step_circumsolar_mol_m2),
            "horizon_par_mol_m2": 0.0,
            "summary": split_summary(d, p)}
    if args.weather:
        rec["weather_file"] = str(args.weather)
        rec["weather"] = dict(p.parameters)
    else:
        rec["clear_sky_model"] = dict(p.parameters)
    return rec


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


# ------------------------------------------------------------------------------ files
def _plot_name(label: str) -> str:
    """The file of a period's plot at the mesh level labelled ``label``."""
    return f"day_{file_tag(label) or 'level'}.png"


def _check_paths(args: argparse.Namespace, labels: list[str], sun: bool,
                 heights: tuple[float, ...]) -> None:
    """Refuse, before any work, outputs (every per-level file and every file of the heatmap
    and plot folders) that would overwrite an input or each other."""
    period = _period_asked(args)
    tables = [("the mesh export", args.export), ("the leaf light table", args.leaf_light),
              ("the plant light table", args.plant_light),
              ("the time-step table", args.steps if period else None)]
    kinds = [kind for kind, asked in (("sun", sun), ("sky", args.sky is not None or period),
                                      ("period", period)) if asked]
    maps = [f"{stem}.{ext}" for label in labels for kind in kinds
            for stem in map_stems(kind, label, heights) for ext in ("png", "csv")]
    check_run_paths(
        [(what, level_path(path, label, len(labels))) for what, path in tables if path
         for label in labels],
        [(input_name(args.points), args.points), ("the layout file", args.layout),
         ("the weather file", args.weather), ("the optics table", args.optics_table)],
        [OutputFolder("the heatmap folder", args.heatmaps, maps),
         OutputFolder("the plot folder", args.plots if period else None,
                      [_plot_name(label) for label in labels])])


def _write_outputs(args: argparse.Namespace, canopy: Canopy, label: str, n_levels: int,
                   res: LightResult | None, sky: SkyLight | None, pl: PeriodLight | None,
                   tables: list[list[dict]],
                   plant_extra: dict[int, dict[str, float]] | None = None,
                   stalk_rows: list[dict] | None = None) -> None:
    if args.heatmaps:
        folder = make_folder(args.heatmaps)
        n = 0
        if res is not None:
            n += len(write_heatmaps(folder, res, args.heatmap_bin)) // 2
        if sky is not None:
            n += len(write_heatmaps(folder, sky, kind="sky")) // 2
        if pl is not None and pl.n_steps:
            n += len(write_heatmaps(folder, pl, kind="period")) // 2
        say(f"wrote {n} transmission maps (PNG + CSV) to {folder}")
    if pl is not None and args.steps:
        write_steps(level_path(args.steps, label, n_levels), pl)
    if pl is not None and args.plots:
        from maizeviz.light.report.plots import day_figure

        folder = make_folder(args.plots)
        p = pl.period
        title = (f"{p.start:%Y-%m-%d %H:%M} to {p.end:%Y-%m-%d %H:%M} ({p.start.tz}); "
                 f"{p.source}; level {label}")
        path = folder / _plot_name(label)
        save_figure(day_figure(pl, title), path)
        say(f"wrote {path}")
    if tables:
        rows = merge_rows(*tables)
        for r in rows:
            r["level"] = label
        if args.leaf_light:
            write_rows(level_path(args.leaf_light, label, n_levels), rows)
        if args.plant_light:
            plants = plant_light(rows)
            for r in plants:            # standard errors do not add: computed per plant
                r.update((plant_extra or {}).get(int(r["instance"]), {}))
            write_rows(level_path(args.plant_light, label, n_levels),
                       with_stalk_columns(plants, stalk_rows or []))


# ------------------------------------------------------------------------------ tables
def _print_tables(records: list[dict], sun: Sun | None, heights: tuple[float, ...],
                  args: argparse.Namespace) -> None:
    r0 = records[0]
    if sun is not None:
        _print_sun(records, sun, heights, args)
    if r0.get("diffuse"):
        _print_sky(records, heights, args)
    if "period" in r0:
        for r in records:
            _print_period(r, len(records) > 1)
    if "balance" in r0:
        _print_balance(records)
    line = stalk_line(records)
    if line:
        print(line)
    if r0.get("photosynthesis"):
        _print_photosynthesis(records)
    print()
    t_ref = _cost(r0)
    cols = ["level", "triangles", "canopy s", "scene s"]
    cols += ["trace s"] if sun is not None else []
    cols += ["sky s"] if "sky" in r0["seconds"] else []
    cols += ["period s"] if "period" in r0["seconds"] else []
    cols += ["scene+trace vs first"]
    rows = []
    for r in records:
        sec = r["seconds"]
        row = [r["level"], r["triangles"], f"{sec['canopy']:.2f}", f"{sec['scene']:.2f}"]
        if sun is not None:
            row.append(f"{sec['trace']:.3f}")
        if "sky" in sec:
            row.append(f"{sec['sky']:.2f}")
        if "period" in sec:
            row.append(f"{sec['period']:.2f}")
        row.append(f"{_cost(r) / t_ref:.0%}" if t_ref > 0 else "")
        rows.append(row)
    print(fmt_table(cols, rows))


def _cost(r: dict) -> float:
    sec = r["seconds"]
    return (sec["scene"] + sec.get("trace", 0.0) + sec.get("sky", 0.0)
            + sec.get("period", 0.0))


def _print_sun(records: list[dict], sun: Sun, heights: tuple[float, ...],
               args: argparse.Namespace) -> None:
    r0 = records[0]
    rc = ", ".join(f"{v:.1f}" for v in r0["rect_cm"])
    print(f"direct light: {r0['rays']:,} sensors per plane over x0,y0,x1,y1 = {rc} cm "
          f"({r0['density_per_cm2']:.2f} per cm2), sun zenith {sun.zenith_deg:.2f} deg, "
          f"azimuth {sun.azimuth_deg:.2f} deg{', periodic field' if args.periodic else ''}")
    _print_heights(heights, [(r["level"], r["transmission"]) for r in records],
                   r0["beer_lambert"] if args.check else None)
    if args.check:
        bl = r0["beer_lambert"]
        omega = clumping(r0["transmission"][0], bl["transmission"][0])
        print(f"Beer-Lambert with G = {bl['G']:.3f} and L(h) from the {r0['level']} "
              f"mesh; effective clumping at {heights[0]:g} cm: ln T / ln T_BL = {omega:.2f} "
              "(1: random foliage; below 1: clumped, T above Beer-Lambert, as in most row "
              "crops (0.7-1); above 1: more regular than random)")
    print()


def _print_sky(records: list[dict], heights: tuple[float, ...],
               args: argparse.Namespace) -> None:
    d0 = records[0]["diffuse"]
    rc = ", ".join(f"{v:.1f}" for v in d0["rect_cm"])
    part = f" (the {d0['part']}; its circumsolar part follows the sun)" if "part" in d0 else ""
    print(f"diffuse light: {d0['description']}{part}; {d0['rays_per_direction']:,} sensors per "
          f"plane and direction over x0,y0,x1,y1 = {rc} cm"
          f"{', periodic field' if args.periodic else ''}")
    _print_heights(heights, [(f"{r['level']} diffuse T", r["diffuse"]["transmission"])
                             for r in records],
                   d0["beer_lambert"] if args.check else None)
    print("leaves intercept " + ", ".join(
        f"{r['diffuse']['intercepted_fraction']:.3f}" + (f" ({r['level']})" if len(records) > 1
                                                         else "")
        for r in records) + (" of this sky's light" if "part" in d0 else " of the diffuse light")
          + " (first hits; scattering not followed)")
    if args.check:
        bl = d0["beer_lambert"]
        print(f"Beer-Lambert under the same sky: sum of w_i exp(-G_i L(h)/cos theta_i), G_i "
              f"from the {records[0]['level']} mesh (weighted mean {bl['G']:.3f})")
    print()


def _print_heights(heights: tuple[float, ...], columns: list[tuple[str, list[float]]],
                   bl: dict | None) -> None:
    """Transmission by height: a column per (name, transmission) and, when ``bl`` (a Beer-Lambert
    record) is given, Beer-Lambert's."""
    head = ["height cm"] + [name for name, _ in columns]
    head += ["Beer-Lambert"] if bl is not None else []
    rows = []
    for i, h in enumerate(heights):
        row = [f"{h:g}"] + [f"{t[i]:.3f}" for _, t in columns]
        if bl is not None:
            row.append(f"{bl['transmission'][i]:.3f}")
        rows.append(row)
    print(fmt_table(head, rows))


def _print_period(r: dict, label: bool) -> None:
    p = r["period"]
    print(f"period{' (' + r['level'] + ')' if label else ''}: {p['start']} to {p['end']}, "
          f"{p['steps']} time steps with the sun up")
    print(f"irradiance: {p['source']}")
    print(f"PAR = {p['par_umol_per_j']:.4g} umol per J of shortwave; shortwave "
          f"{p['shortwave_mj_m2']:.2f} MJ/m2")
    frac = p["fraction_intercepted"]
    if not p["steps"]:
        print("no sunlight in this period: incident, intercepted and transmitted PAR are 0")
        return
    inc = p["par_incident_mol_m2"]
    print(f"PAR incident {inc:.2f} mol/m2 of ground (direct {p['par_direct_mol_m2']:.2f}, "
          f"diffuse {p['par_diffuse_mol_m2']:.2f}, {p['par_diffuse_mol_m2'] / inc:.0%} "
          f"diffuse); intercepted by the leaves {p['par_intercepted_mol_m2']:.2f} mol/m2 "
          f"({frac:.1%})")
    tb = p["transmission_by_height"]
    diffuse = r.get("diffuse") or {}
    model = p.get("diffuse_model")
    if model is not None:
        print(model["summary"])
        print(f"diffuse PAR intercepted by the leaves {p['par_diffuse_intercepted_mol_m2']:.3f} "
              f"mol/m2 of {p['par_diffuse_mol_m2']:.3f}")
        dt = tb["diffuse_fraction"]
        diffuse_t = [f"{v:.3f}" if v is not None else "" for v in dt]
    else:
        diffuse_t = [f"{v:.3f}" for v in diffuse["transmission"]] if diffuse else \
            [""] * len(tb["heights_cm"])
    print(fmt_table(["height cm", "PAR mol/m2", "fraction", "diffuse T"],
                    [[f"{h:g}", f"{v:.2f}", f"{f:.3f}" if f is not None else "", diffuse_t[i]]
                     for i, (h, v, f) in enumerate(zip(tb["heights_cm"], tb["par_mol_m2"],
                                                       tb["fraction"]))]))
    print()


def _print_photosynthesis(records: list[dict]) -> None:
    """Canopy gross assimilation per level, with its Monte Carlo standard error."""
    ph = records[0]["photosynthesis"]
    period = "canopy_gross_mol_m2" in ph
    params = ", ".join(f"{k} {v:g}" for k, v in ph["parameters"].items()
                       if k in ("vmax", "alpha", "co2_ppm", "amax", "eff"))
    print(f"\ngross CO2 assimilation, {ph['label']} ({params}), per m2 of ground"
          + ("" if period else f", leaves at {ph['temperature_c']:g} C") + ":")
    rows = []
    for r in records:
        p = r["photosynthesis"]
        if period:
            se = p["canopy_gross_mol_m2_se"] or 0.0
            rows.append([r["level"], f"{p['canopy_gross_mol_m2']:.4f} +- {se:.4f}",
                         f"{p['canopy_gross_g_co2_m2']:.2f} +- {se * 44.0095:.2f}"])
        else:
            se = p["canopy_gross_umol_m2_s_se"] or 0.0
            rows.append([r["level"], f"{p['canopy_gross_umol_m2_s']:.2f} +- {se:.2f}",
                         f"{p['canopy_gross_kg_co2_ha_h']:.2f} +- "
                         f"{p['canopy_gross_kg_co2_ha_h_se'] or 0.0:.2f}"])
    print(fmt_table(["level", "mol CO2/m2" if period else "umol CO2/m2/s",
                     "g CO2/m2" if period else "kg CO2/ha/h"], rows))


def _print_balance(records: list[dict]) -> None:
    """Absorbed light with scattering: the energy balance per level, W/m2 of ground (MJ/m2
    over a period, with the PAR the leaves absorbed in mol/m2)."""
    ab = records[0]["absorbed"]
    o = ab["optics"]
    period = ab["units"].startswith("MJ")
    print(f"\nabsorbed {ab['band'].upper()} with scattering (leaf reflectance "
          f"{o['reflectance']:g}, transmittance {o['transmittance']:g}, ground "
          f"{o['ground_reflectance']:g}), {ab['units']}:")
    rows = []
    for r in records:
        b = r["balance"]
        mol = r["absorbed"].get("absorbed_leaves_mol_m2")
        last = ("-" if mol is None else f"{mol:.2f}") if period else \
            f"{r['absorbed']['sunlit_lai']:.2f}"
        rows.append([r["level"], f"{b['incident']:.2f}", f"{b['absorbed_leaves']:.2f}",
                     f"{b['absorbed_ground']:.2f}", f"{b['reflected_top']:.2f}",
                     f"{b['escaped_sides'] + b['unresolved']:.2f}",
                     f"{b['closure_fraction']:+.2%}", last])
    print(fmt_table(["level", "incident", "leaves", "ground", "reflected", "other",
                     "closure (of incident)", "PAR mol/m2" if period else "sunlit LAI"],
                    rows))
