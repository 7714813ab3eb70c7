"""The run of ``maizeviz light``: the options read into a sun, a sky, a period and optics,
checked against their cost, each mesh level traced, the outputs written and the tables said.

The options are :mod:`maizeviz.cli.light`'s; the JSON records of the results
:mod:`maizeviz.cli.light_records`'.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.export import export_canopy
from maizeviz.canopy.field import canopy_of
from maizeviz.canopy.from_mesh import MESH_LEVEL
from maizeviz.cli.common import (
    Progress,
    canopy_setup,
    check_canopy_costs,
    check_export,
    check_input_options,
    floats,
    input_name,
    is_mesh,
    leaves_summary,
    level_path,
    levels_from,
    mesh_setup,
    say,
    say_estimate,
)
from maizeviz.cli.light_records import (
    absorbed_period_record,
    absorbed_record,
    assimilation_rows,
    jsonable,
    merge,
    period_record,
    plant_errors,
    print_tables,
    sky_record,
    sun_record,
    traced,
    warn_unresolved,
)
from maizeviz.cli.stalk_light import stalk_record, with_stalk_columns
from maizeviz.cli.sun_options import WHERE_IS_THE_SUN, sun_from_options, sun_place_given
from maizeviz.cost import check, light_costs, mesh_cost
from maizeviz.errors import LeafError, MaizevizError, check_range
from maizeviz.io.atomic import file_tag, make_folder, write_rows
from maizeviz.io.outputs import OutputFolder, check_run_paths
from maizeviz.leaf.fit import Leaf
from maizeviz.light.engine import LightEngine
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
    Period,
    WeatherFileError,
    clear_sky_period,
    read_weather,
    weather_period,
)
from maizeviz.light.sources.perez import PEREZ_MODELS
from maizeviz.light.sources.sky import Sky, make_sky
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.optics import optics_for, read_optics_table
from maizeviz.light.trace.precision import check_precision
from maizeviz.light.trace.scatter import DEFAULT_DEPTH
from maizeviz.photosynthesis.split import LeafModel, leaf_model

#: ``--sky`` of a period whose diffuse light is split by Perez's model, step by step.
PEREZ = "perez"


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
    if _period_asked(args):
        return None
    explicit = args.sun_zenith is not None or args.sun_azimuth is not None
    if not explicit and not sun_place_given(args):
        if args.sky is not None:
            return None
        raise MaizevizError(WHERE_IS_THE_SUN + "; or --sky soc for an overcast sky, or --day "
                            "for a whole day")
    return sun_from_options(args)


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
        print(json.dumps(jsonable(records[0] if len(records) == 1 else {"levels": records}),
                         indent=1))
    else:
        print_tables(records, job.sun, job.heights, args)
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
                                             lv.ab or lv.abd, lv.per_res, args.periodic)
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
                        or bool(job.args.export), sunlit=job.want_rows,
                        progress=Progress(f"tracing {lv.label}"))
    lv.res = res
    lv.warnings += res.warnings
    lv.rec.update(sun_record(res, job.sun, lv.canopy, job.args, job.heights))
    lv.rec["seconds"].update(trace=res.seconds["trace"],
                             second_hits=res.seconds.get("second", 0.0))
    if "sunlit" in res.seconds:                 # the leaf tables' sampled sunlit areas
        lv.rec["seconds"]["sunlit"] = res.seconds["sunlit"]
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
        lv.rec["diffuse"] = sky_record(lv.sky_res, lv.canopy, args, job.heights)
        if args.sky == PEREZ:
            lv.rec["diffuse"]["part"] = "isotropic part of the Perez sky"
        if job.want_rows:
            lv.tables.append(lv.sky_res.leaf_rows(lv.canopy))
    elif sky is not None and period is not None:
        lv.rec["diffuse"] = None                   # the sun never rose: no sky traced
    if lv.per_res is not None:
        lv.rec["period"] = period_record(lv.per_res, args)
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

    abd = lv.abd = traced(trace_day, args, lv.rec, job.said)
    warn_unresolved(abd.balance, abd.depth, lv.rec, job.said)
    lv.rec["balance"] = dict(abd.balance.as_dict(), units="MJ/m2 of ground")
    lv.rec["balance_se"] = abd.balance_errors
    lv.rec["absorbed"] = absorbed_period_record(abd)
    if abd.assimilation is not None:
        lv.rec["photosynthesis"] = abd.assimilation.as_dict()
        if job.want_rows:
            lv.tables.append(assimilation_rows(lv.canopy, abd.assimilation))
            merge(lv.plant_extra, plant_errors(lv.canopy, abd.assimilation))
    if job.want_rows:
        lv.tables.append(assimilation_rows(lv.canopy, abd))
        merge(lv.plant_extra, plant_errors(lv.canopy, abd))
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

    ab = lv.ab = traced(trace_sun, args, lv.rec, job.said)
    warn_unresolved(ab.balance, ab.depth, lv.rec, job.said)
    lv.rec["balance"] = ab.balance.as_dict()
    lv.rec["balance_se"] = ab.balance_errors
    lv.rec["absorbed"] = absorbed_record(ab, lv.canopy)
    lv.rec["seconds"]["scatter"] = ab.seconds["trace"] + ab.seconds["scatter"]
    if job.want_rows:
        lv.tables.append(ab.leaf_rows(lv.canopy))
        merge(lv.plant_extra, plant_errors(lv.canopy, ab))
    if job.leaf_model is not None:
        asm = lv.asm = assimilate(lv.canopy, ab, job.leaf_model, job.temp_c)
        lv.rec["photosynthesis"] = asm.as_dict()
        _say_once(job, list(asm.warnings))
        if job.want_rows:
            lv.tables.append(assimilation_rows(lv.canopy, asm))
            merge(lv.plant_extra, plant_errors(lv.canopy, asm))


def _without_sun(lv: _Level) -> None:
    """A record without a sun still says its rays, rectangle and density (the sky's or the
    period's)."""
    res = lv.per_res or lv.sky_res
    rays = res.rays if res else 0
    x0, y0, x1, y1 = res.rect if res else (0, 0, 1, 1)
    lv.rec.update(sun=None, transmission=None, rays=rays, rect_cm=[x0, y0, x1, y1],
                  density_per_cm2=rays / ((x1 - x0) * (y1 - y0)))


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
