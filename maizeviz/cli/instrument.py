"""``maizeviz instrument``: read a virtual ceptometer, canopy analyser or hemispherical camera
in a canopy (docs/instruments.md)."""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.field import canopy_of
from maizeviz.cli.common import (
    NUMBER_ARG,
    WHOLE_ARG,
    Progress,
    add_canopy_options,
    add_level_options,
    canopy_setup,
    check_canopy_costs,
    check_input_options,
    floats,
    fmt_table,
    is_mesh,
    leaves_summary,
    levels_from,
    mesh_setup,
    say,
    suffixed,
)
from maizeviz.cli.sun_options import add_sun_options, sun_from_options
from maizeviz.errors import MaizevizError
from maizeviz.instruments.sight import default_place
from maizeviz.mesh.levels import CANOPY_LEVELS

#: The subcommand.
NAME = "instrument"
KINDS = ("ceptometer", "analyser", "hemiphoto")


def _common(p: argparse.ArgumentParser) -> None:
    add_canopy_options(p)
    add_level_options(p, CANOPY_LEVELS)
    p.add_argument("--at", action="append", metavar="X,Y",
                   help="where the instrument is held, field x,y in cm (x across the rows, y "
                        "along them); repeat for several readings (default: between the rows "
                        "and plants nearest the plot's middle)")
    p.add_argument("--height", type=NUMBER_ARG, default=0.0, metavar="CM",
                   help="height of the sensors above the ground, cm (default 0)")
    p.add_argument("--periodic", action="store_true",
                   help="lines of sight leaving the plot go on through the next copy of it "
                        "(an infinite field)")
    p.add_argument("--leaves-only", action="store_true",
                   help="stalks do not block the view (the paper's leaves-only canopy)")
    p.add_argument("--json", action="store_true", help="print JSON instead of tables")


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        NAME, help="read a virtual ceptometer, canopy analyser or hemispherical camera",
        description="What field instruments would read in the canopy: a line ceptometer "
                    "(LP-80 style), a plant canopy analyser (LAI-2200 style) or hemispherical "
                    "photographs, through the light engine's Embree scenes.")
    kinds = p.add_subparsers(dest="instrument", metavar="INSTRUMENT", required=True)
    cep = kinds.add_parser("ceptometer", help="a line ceptometer (LP-80 style): PAR per "
                           "sensor, tau, intercepted fraction, LAI")
    _common(cep)
    add_sun_options(cep)
    cep.add_argument("--orientation", default="across", metavar="ALONG|ACROSS|DEG",
                     help="the probe along the rows, across them, or an azimuth in degrees "
                          "clockwise from the rows' direction (default across)")
    cep.add_argument("--length", type=NUMBER_ARG, default=80.0, metavar="CM",
                     help="probe length, cm (default 80)")
    cep.add_argument("--spacing", type=NUMBER_ARG, default=1.0, metavar="CM",
                     help="distance between sensors, cm (default 1: 80 sensors)")
    cep.add_argument("--par", type=NUMBER_ARG, default=2000.0, metavar="UMOL",
                     help="PAR above the canopy, umol/m2/s (default 2000)")
    cep.add_argument("--beam-fraction", type=NUMBER_ARG, default=0.8, metavar="FB",
                     help="the sun's share of the PAR above, 0 to 1 (default 0.8)")
    cep.add_argument("--sky", choices=("soc", "uoc"), default="soc",
                     help="radiance of the diffuse part (default soc)")
    cep.add_argument("--sky-directions", type=WHOLE_ARG, default=46, metavar="N",
                     help="sky directions traced (default 46)")
    cep.add_argument("--leaf-x", type=NUMBER_ARG, default=1.0, metavar="X",
                     help="ellipsoidal leaf angle parameter of the LAI inversion (default 1, "
                          "spherical)")
    cep.add_argument("--absorptivity", type=NUMBER_ARG, default=0.9, metavar="A",
                     help="leaf PAR absorptivity of the LAI inversion (default 0.9)")
    cep.add_argument("--csv", metavar="PATH", help="write every sensor's reading")
    cep.set_defaults(run=run)
    ana = kinds.add_parser("analyser", help="a plant canopy analyser (LAI-2200 style): five "
                           "rings' gap fractions, LAI, MTA")
    _common(ana)
    ana.add_argument("--view-cap", type=NUMBER_ARG, default=360.0, metavar="DEG",
                     help="azimuth seen: 45, 90, 180, 270 or 360 (no cap; default)")
    ana.add_argument("--heading", type=NUMBER_ARG, default=0.0, metavar="DEG",
                     help="azimuth the view cap is centred on, clockwise from the rows' "
                          "direction (default 0)")
    ana.add_argument("--rays", type=WHOLE_ARG, default=2000, metavar="N",
                     help="lines of sight per ring and position (default 2000)")
    ana.add_argument("--sky", choices=("uoc", "soc"), default="uoc",
                     help="sky radiance weighting the lines of sight (default uoc: the gap "
                          "fraction)")
    ana.add_argument("--seed", type=WHOLE_ARG, default=0, help="seed of the sampling")
    ana.set_defaults(run=run)
    hem = kinds.add_parser("hemiphoto", help="hemispherical photographs (equidistant "
                           "fisheye PNG), gap fraction per ring")
    _common(hem)
    hem.add_argument("--size", type=WHOLE_ARG, default=512, metavar="PX",
                     help="pixels a side (default 512)")
    hem.add_argument("--black", action="store_true",
                     help="plants black (default: leaves green, stalks brown)")
    hem.add_argument("--png", metavar="PATH",
                     help="write the photograph (several --at: PATH_1.png, PATH_2.png...)")
    hem.set_defaults(run=run)


def _positions(args: argparse.Namespace) -> list[tuple[float, float]]:
    """The --at positions (x, y) cm; empty: the default place, once the canopy is built."""
    out: list[tuple[float, float]] = []
    for text in args.at or ():
        x, y = floats(text, "the position X,Y", "at_instrument", 2)
        if not (math.isfinite(x) and math.isfinite(y)):
            raise MaizevizError(f"the position X,Y must be finite numbers, got '{text}'",
                                quantity="at_instrument")
        out.append((x, y))
    return out


def _canopy(args: argparse.Namespace) -> tuple[Canopy, int, list]:
    """The canopy of the options (one level), the leaves reconstructed and those skipped."""
    check_input_options(args)
    if is_mesh(args.points):
        canopy = mesh_setup(args)
        return canopy, canopy.n_leaves, []
    levels = levels_from(args)
    if len(levels) > 1:
        raise MaizevizError("an instrument reads one canopy: give --interp or --triangles, "
                            "not --levels", quantity="level")
    leaves, skipped, layout = canopy_setup(args)
    check_canopy_costs(leaves, layout, levels, args.force, [])
    canopy = canopy_of(leaves, layout, levels[0], args.preserve_area,
                       Progress(f"building {levels[0]}"))
    return canopy, len(leaves), skipped


def _check_settings(args: argparse.Namespace) -> None:
    """Refuse the instrument's settings before the canopy is built."""
    from maizeviz.instruments.analyser import check_view_cap
    from maizeviz.instruments.ceptometer import Probe, lp80_lai, probe_azimuth
    from maizeviz.instruments.hemiphoto import MAX_SIZE, MIN_SIZE
    from maizeviz.io.atomic import check_output

    if args.instrument == "ceptometer":
        Probe(0.0, 0.0, args.height, probe_azimuth(args.orientation), args.length,
              args.spacing)
        if not (math.isfinite(args.par) and args.par > 0):
            raise MaizevizError(f"the PAR above must be > 0 umol/m2/s, got {args.par:g}",
                                quantity="par")
        lp80_lai(1.0, 0.0, args.beam_fraction, args.leaf_x, args.absorptivity)
        if args.csv:
            check_output(args.csv)
    elif args.instrument == "analyser":
        check_view_cap(args.view_cap)
        if not 1 <= args.rays <= 10_000_000:
            raise MaizevizError(f"lines of sight per ring must be from 1 to 10,000,000, got "
                                f"{args.rays}", quantity="rays")
    else:
        if not MIN_SIZE <= args.size <= MAX_SIZE:
            raise MaizevizError(f"the photograph's size must be from {MIN_SIZE} to {MAX_SIZE} "
                                f"pixels, got {args.size}", quantity="size")
        if args.png:
            check_output(args.png)
    if not (math.isfinite(args.height) and args.height >= 0):
        raise MaizevizError(f"the instrument's height must be >= 0 cm, got {args.height:g}",
                            quantity="height_cm")


def run(args: argparse.Namespace) -> int:
    from maizeviz.instruments.sight import Sight

    sun = sun_from_options(args) if args.instrument == "ceptometer" else None    # before the canopy
    _check_settings(args)
    positions = _positions(args)
    canopy, n_leaves, skipped = _canopy(args)
    positions = positions or [default_place(canopy)]
    t0 = time.perf_counter()
    sight = Sight.of(canopy, args.periodic, not args.leaves_only)
    if args.instrument == "ceptometer":
        rec = _ceptometer(args, sight, canopy, positions, sun)
    elif args.instrument == "analyser":
        rec = _analyser(args, sight, positions)
    else:
        rec = _hemiphoto(args, sight, canopy, positions)
    rec.update(periodic=args.periodic, stalks=not args.leaves_only and
               len(canopy.stalk_faces) > 0, trace_s=time.perf_counter() - t0)
    if args.json:
        print(json.dumps(rec, indent=1))
    for note in rec.get("notes", []):
        say(f"note: {note}")
    return leaves_summary(n_leaves, skipped)


def _ceptometer(args, sight, canopy, positions, sun) -> dict:
    from maizeviz.instruments.ceptometer import Probe, probe_azimuth, read_ceptometer

    az = probe_azimuth(args.orientation)
    probes = [Probe(x, y, args.height, az, args.length, args.spacing) for x, y in positions]
    r = read_ceptometer(sight, probes, sun, par_umol=args.par,
                        beam_fraction=args.beam_fraction, sky=args.sky,
                        directions=args.sky_directions, north_deg=canopy.layout.north_deg,
                        x=args.leaf_x, absorptivity=args.absorptivity)
    if args.csv:
        from maizeviz.io.atomic import write_text

        write_text(args.csv, r.table().to_csv(index=False))
        say(f"wrote {r.par_umol.size} sensor readings to {args.csv}")
    rec = r.as_dict()
    if not args.json:
        print(f"ceptometer: {probes[0].n_sensors} sensors on {args.length:g} cm, "
              f"{args.height:g} cm high, azimuth {az:g} deg; sun zenith "
              f"{sun.zenith_deg:.1f} deg, azimuth {sun.azimuth_deg:.1f} deg; PAR above "
              f"{args.par:g} umol/m2/s, beam fraction {args.beam_fraction:g}")
        print(fmt_table(["probe", "x cm", "y cm", "tau", "intercepted", "mean PAR"],
                        [[i + 1, f"{p['x_cm']:.1f}", f"{p['y_cm']:.1f}", f"{p['tau']:.4f}",
                          f"{p['intercepted']:.4f}",
                          f"{sum(p['par_umol_m2_s']) / len(p['par_umol_m2_s']):.1f}"]
                         for i, p in enumerate(rec["probes"])]))
        lai = rec["lai"]
        print(f"tau {r.tau:.4f}, intercepted {r.intercepted:.4f}, LAI (LP-80, x "
              f"{args.leaf_x:g}, a {args.absorptivity:g}) "
              f"{'inf' if lai is None else f'{lai:.3f}'}")
    return rec


def _analyser(args, sight, positions) -> dict:
    from maizeviz.instruments.analyser import AnalyserPosition, read_analyser

    pos = [AnalyserPosition(x, y, args.height, args.heading) for x, y in positions]
    r = read_analyser(sight, pos, view_cap_deg=args.view_cap, sky=args.sky,
                      rays_per_ring=args.rays, seed=args.seed)
    rec = r.as_dict()
    if not args.json:
        print(f"canopy analyser: {len(pos)} position(s) {args.height:g} cm high, view cap "
              f"{args.view_cap:g} deg, {args.rays} lines of sight per ring, {args.sky} sky")
        print(fmt_table(["ring", "zenith deg", "weight", "above", "below", "T", "K"],
                        [[g["ring"], f"{g['from_deg']:g}-{g['to_deg']:g}", g["weight"],
                          f"{g['above']:.4f}", f"{g['below']:.4f}",
                          f"{g['transmission']:.4f}",
                          "inf" if g["contact"] is None else f"{g['contact']:.4f}"]
                         for g in rec["rings"]]))
        lai, mta = rec["lai"], rec["mta_deg"]
        print(f"LAI {'inf' if lai is None else f'{lai:.3f}'}, MTA "
              f"{'-' if mta is None else f'{mta:.1f}'} deg")
    return rec


def _hemiphoto(args, sight, canopy, positions) -> dict:
    from maizeviz.instruments.hemiphoto import hemiphoto

    photos = []
    for k, (x, y) in enumerate(positions, 1):
        ph = hemiphoto(sight, x, y, args.height, size=args.size, colour=not args.black,
                       north_deg=canopy.layout.north_deg)
        d = ph.as_dict()
        if args.png:
            path = Path(args.png) if len(positions) == 1 else suffixed(args.png, str(k))
            ph.save_png(path)
            d["png"] = str(path)
            say(f"wrote {path}")
        photos.append(d)
        if not args.json:
            print(f"hemispherical photograph {k}: x {x:g}, y {y:g}, {args.height:g} cm high, "
                  f"{args.size} px, openness {d['openness']:.4f}")
            print(fmt_table(["ring", "zenith deg", "pixels", "gap fraction"],
                            [[g["ring"], f"{g['from_deg']:g}-{g['to_deg']:g}", g["pixels"],
                              f"{g['gap_fraction']:.4f}"] for g in d["rings"]]))
    notes = sorted({n for d in photos for n in d.pop("notes")})
    return {"instrument": "hemiphoto", "photos": photos, "notes": notes}
