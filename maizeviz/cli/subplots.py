"""``maizeviz subplots POINTS --parts AxB``: a field's sunlight traced in sub-plots on Dask.

Exit codes as ``maizeviz``'s: 0 done; 1 nothing could be done (a bad file, the scheduler); 2
bad command-line usage; 3 done, but some leaves were skipped.
"""

from __future__ import annotations

import argparse
import csv
import json

from maizeviz.errors import MaizevizError

#: The subcommand (``maizeviz.cli`` lists this module among its commands).
NAME = "subplots"
#: Most sub-plots one run cuts a field into (``--parts``): each is a task building every
#: plant within a shadow's reach of it, so more parts than this build the field many times.
MAX_SUBPLOTS = 1024


def add_parser(sub: argparse._SubParsersAction) -> None:
    from maizeviz.cli.common import NUMBER_ARG, WHOLE_ARG, add_canopy_options
    from maizeviz.sweep.run import CONNECT_TIMEOUT_S

    p = sub.add_parser(
        NAME, help="a field's sunlight traced in sub-plots on Dask (past one machine)",
        description="Cut the sample rectangle of a field (a Parquet points file) into AxB "
                    "sub-plots, each traced on a Dask worker through the plants within reach "
                    "of its rays (a halo as wide as the sun's shadows), and merge them: the "
                    "whole field's transmission by height and light per plant. Each worker "
                    "reads its own plants from the points file.")
    add_canopy_options(p)
    p.add_argument("--parts", default="2x2", metavar="AxB",
                   help="sub-plots across x and along y (default 2x2)")
    p.add_argument("--level", default="36", help="mesh level (default 36 triangles a leaf)")
    p.add_argument("--no-preserve-area", dest="preserve_area", action="store_false")
    p.add_argument("--sun-zenith", type=NUMBER_ARG, required=True, metavar="DEG")
    p.add_argument("--sun-azimuth", type=NUMBER_ARG, required=True, metavar="DEG")
    p.add_argument("--heights", default="0,50,100,150,200,225", metavar="CM,...")
    p.add_argument("--density", type=NUMBER_ARG, default=1.0,
                   help="rays per cm2 of the sample rectangle (default 1)")
    p.add_argument("--rect", metavar="X0,Y0,X1,Y1", help="sample rectangle, cm (default: the "
                                                           "central tile, as light's)")
    p.add_argument("--plant-light", metavar="CSV", help="write the light of every plant")
    p.add_argument("--workers", type=WHOLE_ARG, metavar="N",
                   help="worker processes of a local Dask cluster (default: one per core)")
    p.add_argument("--scheduler", metavar="ADDR",
                   help="a running Dask scheduler, e.g. tcp://10.0.0.5:8786 (its workers need "
                        "maizeviz and the points file at the same path)")
    p.add_argument("--connect-timeout", type=NUMBER_ARG, default=CONNECT_TIMEOUT_S, metavar="S")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.set_defaults(run=run)


def _field(field_leaves, args: argparse.Namespace, progress):
    """The field surveyed plant chunk by plant chunk; a file that cannot be (records the
    CSV reader must check, a plant's records apart: it ended in NotStreamable) refused in
    one line naming the file and what reads it."""
    from maizeviz.io.parquet import NotStreamable

    try:
        return field_leaves(args.points, args.strict, progress=progress)
    except NotStreamable as exc:
        why = str(exc).removeprefix(str(args.points)).lstrip(": ") or (
            "its records need the CSV reader's checks (a missing value, a text cell or a "
            "status column)")
        raise MaizevizError(
            f"{args.points}: {why}: sub-plots read a Parquet file plant by plant on every "
            "worker, which needs each plant's records together as plain numbers; 'maizeviz "
            "light' reads it whole, 'maizeviz convert' writes its checked records to a new "
            "file") from None


def run(args: argparse.Namespace) -> int:
    from maizeviz.canopy.field import FieldLeaves
    from maizeviz.canopy.layout import layout_for, parse_shape
    from maizeviz.cli.common import Progress, floats, fmt_table, leaves_summary, say
    from maizeviz.io.outputs import check_run_paths
    from maizeviz.io.parquet import is_parquet
    from maizeviz.light.scene.rays import grid_shape, ray_count
    from maizeviz.light.scene.request import check_heights, check_rect_in_plot
    from maizeviz.light.sources.sun import Sun
    from maizeviz.mesh.levels import parse_level
    from maizeviz.sweep.run import dask_client, max_local_workers
    from maizeviz.sweep.subplots import trace_field

    parts = parse_shape(args.parts, "parts")
    if parts[0] * parts[1] > MAX_SUBPLOTS:
        raise MaizevizError(f"{parts[0]:,} x {parts[1]:,} sub-plots; at most {MAX_SUBPLOTS:,} "
                            "are traced (each builds every plant within a shadow's reach of "
                            "it) (--parts)")
    try:
        level = parse_level(args.level)
    except MaizevizError as exc:                 # the level's own flag here, not --triangles
        raise MaizevizError(f"{exc} (--level)") from None
    heights = tuple(floats(args.heights, "the sensor heights", "heights"))
    check_heights(heights)
    check_run_paths([("the plant table", args.plant_light)], [("the points file", args.points)])
    if args.workers is not None and args.scheduler:
        raise MaizevizError("--workers sizes the local cluster; with --scheduler the cluster "
                            "has its own")
    if args.workers is not None and not 1 <= args.workers <= max_local_workers():
        raise MaizevizError(f"--workers must be from 1 to {max_local_workers()} on this machine "
                            f"(4 a core), got {args.workers:,}")
    if not is_parquet(args.points):
        raise MaizevizError(f"{args.points}: sub-plots read a Parquet points file, plant by "
                            "plant, on every worker (maizeviz convert writes one)")
    sun = Sun(args.sun_zenith, args.sun_azimuth)
    field = _field(FieldLeaves, args, Progress("reading the field"))
    layout = layout_for(field, parse_shape(args.tile or "1x1", "tile"),
                        args.row_spacing,
                        args.plant_spacing,
                        parse_shape(args.block, "block") if args.block else None, args.layout)
    for warning in layout.warnings:
        say(f"note: {warning}")
    rect = layout.centre_bounds
    if args.rect:
        x0, y0, x1, y1 = floats(args.rect, "the sample rectangle", "rect", 4)
        rect = check_rect_in_plot((x0, y0, x1, y1), layout.bounds)
    lattice = grid_shape(rect, args.density)          # the density checked before the cluster
    if parts[0] > lattice[0] or parts[1] > lattice[1]:
        raise MaizevizError(f"{parts[0]:,} x {parts[1]:,} sub-plots of a lattice of "
                            f"{lattice[0]:,} x {lattice[1]:,} rays: a sub-plot needs a ray "
                            "across each way (--parts)")
    toward = sun.direction(layout.north_deg)
    with dask_client(args.workers, args.scheduler, args.connect_timeout) as (client, kind):
        say(f"{kind}: {len(client.scheduler_info().get('workers', {}))} workers, "
            f"{parts[0]}x{parts[1]} sub-plots")
        counts, plan = trace_field(client, field, layout, level, toward, rect, args.density,
                                   heights, parts, args.preserve_area,
                                   Progress("tracing sub-plots"))
    rays = ray_count(rect, args.density)
    ray_area = (rect[2] - rect[0]) * (rect[3] - rect[1]) / rays
    out = {"parts": [list(parts)], "rays": rays, "level": level.label,
           "heights_cm": list(heights), "transmission": counts.transmission.tolist(),
           "plants_per_part": [int(len(p.placements)) for p in plan],
           "plants": len(layout.placements),
           "sunlit_intercepted_m2": float(counts.first.sum() * ray_area / 1e4)}
    if args.plant_light:
        from maizeviz.io.atomic import atomic_open

        with atomic_open(args.plant_light, "w", newline="") as fh:
            table = csv.writer(fh)
            table.writerow(["instance", "plant", "x_cm", "y_cm", "sunlit_cm2", "second_cm2"])
            for k, pl in enumerate(layout.placements):
                table.writerow([k + 1, pl.plant, f"{pl.x:.2f}", f"{pl.y:.2f}",
                            f"{counts.first[k].sum() * ray_area:.2f}",
                            f"{counts.second[k].sum() * ray_area:.2f}"])
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        print(fmt_table(["height cm", "transmission"],
                        [[f"{h:g}", f"{t:.4f}"] for h, t in zip(heights, counts.transmission)]))
        print(f"\n{out['plants']:,} plants in {len(plan)} sub-plots "
              f"({', '.join(map(str, out['plants_per_part']))} plants each), {rays:,} rays; "
              f"intercepted by sunlit leaves: the beam of {out['sunlit_intercepted_m2']:.2f} m2 "
              "of the sample rectangle")
    return leaves_summary(len(field), field.skipped)
