"""``maizeviz light``: sunlight and skylight through the canopy with Embree (Table 3 and beyond).

Its options are here (argparse); the run is :mod:`maizeviz.cli.light_run`, the JSON records
and printed tables it makes of the results :mod:`maizeviz.cli.light_records`.

Three things can be asked, alone or together: a single sun (angles, or a place and a clock
time), a diffuse sky (``--sky``), and a day or a period (``--day``, ``--from/--to``,
``--weather``), whose diffuse part uses the sky traced once for the whole period.
"""

from __future__ import annotations

import argparse
import os

from maizeviz.cli.common import NUMBER_ARG, WHOLE_ARG, add_canopy_options, add_level_options
from maizeviz.cli.light_run import PEREZ, run
from maizeviz.cli.sun_options import add_altitude_option, add_sun_options
from maizeviz.light.sources.irradiance import DEFAULT_LINKE_TURBIDITY, DEFAULT_PAR_UMOL_PER_J
from maizeviz.light.sources.sky import SKY_KINDS
from maizeviz.light.trace.optics import BANDS
from maizeviz.light.trace.scatter import DEFAULT_DEPTH
from maizeviz.mesh.levels import CANOPY_LEVELS
from maizeviz.photosynthesis.c4 import TEMPERATURE_RESPONSES
from maizeviz.photosynthesis.split import MODELS

#: The subcommand.
NAME = "light"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        NAME, help="sunlight and skylight through the canopy with Embree (Table 3)",
        description="Trace parallel rays through a canopy for a sun, a diffuse sky or a whole "
                    "day: transmission on sensor planes at several heights over a sample "
                    "rectangle, light intercepted per leaf and per plant, per mesh level with "
                    "timings.")
    add_canopy_options(p)
    add_level_options(p, CANOPY_LEVELS)
    add_sun_options(p, altitude=False)
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
    add_altitude_option(per)
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


