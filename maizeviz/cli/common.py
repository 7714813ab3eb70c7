"""What the subcommands share: options, the terminal progress bar, tables, messages, exit codes."""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.from_mesh import UNITS, UP_AXES, read_mesh_canopy
from maizeviz.canopy.layout import CanopyLayout, check_tile, layout_for, parse_shape
from maizeviz.cost import Cost, check, layout_cost
from maizeviz.errors import LeafError, MaizevizError
from maizeviz.io.atomic import file_tag
from maizeviz.io.mesh_data import MESH_SUFFIXES
from maizeviz.io.points import shown
from maizeviz.leaf.fit import Leaf, read_leaves
from maizeviz.mesh.levels import Level, parse_levels
from maizeviz.numbers import NUMBER_ARG as NUMBER_ARG
from maizeviz.numbers import WHOLE_ARG as WHOLE_ARG
from maizeviz.numbers import number
from maizeviz.progress import ProgressCallback

EXIT_OK, EXIT_FAIL, EXIT_USAGE, EXIT_PARTIAL = 0, 1, 2, 3
#: Most numbers one list option takes (``--heights``): counted before any is read.
MAX_LIST_ITEMS = 1_000

#: The flag (or flags) through which each quantity of :data:`maizeviz.errors.QUANTITIES`
#: reaches the core: errors about a quantity name it.
FLAGS = {
    "density": "--density", "heights": "--heights", "rect": "--rect", "threads": "--threads",
    "heatmap_bin": "--heatmap-bin", "cover_resolution": "--cover-resolution",
    "row_spacing": "--row-spacing", "plant_spacing": "--plant-spacing", "tile": "--tile",
    "layout": "--layout",
    "block": "--block", "level": "--levels", "interp": "--interp", "triangles": "--triangles",
    "degree": "--degree", "params": "--params", "sun": "--sun-zenith/--sun-azimuth",
    "date": "--date", "time": "--time", "place": "--lat/--lon", "tz": "--tz", "cols": "--cols",
    "plants": "--plants", "sections": "--sections", "at": "--at", "periodic": "--periodic",
    "sky": "--sky", "sky_directions": "--sky-directions", "step": "--step",
    "period": "--from/--to", "par_factor": "--par-factor", "linke_turbidity": "--linke-turbidity",
    "altitude": "--altitude", "weather": "--weather",
    "baud": "--baud", "points_across": "--points-across", "seed": "--seed", "plant": "--plant",
    "pace": "--pace", "noise": "--noise", "answer_timeout": "--answer-timeout",
    "resume": "--resume", "band": "--band", "reflectance": "--reflectance",
    "transmittance": "--transmittance", "ground_reflectance": "--ground-reflectance",
    "irradiance": "--irradiance/--diffuse", "depth": "--depth",
    "mesh_unit": "--mesh-unit", "up": "--up", "field": "--field",
    "mesh_ids": "--mesh-plant/--mesh-leaf",
    "photosynthesis": "--photosynthesis", "temperature": "--temperature", "co2": "--co2",
    "precision": "--precision",
    # maizeviz instrument
    "at_instrument": "--at", "height_cm": "--height", "orientation": "--orientation",
    "length_cm": "--length", "spacing_cm": "--spacing", "par": "--par",
    "beam_fraction": "--beam-fraction", "x": "--leaf-x", "absorptivity": "--absorptivity",
    "view_cap": "--view-cap", "rays": "--rays", "size": "--size",
}


def say(msg: str) -> None:
    """A line on stderr (notes, warnings, errors: stdout carries the results)."""
    print(msg, file=sys.stderr)


def error_line(exc: MaizevizError) -> str:
    """``error: <message> (<flag>)``: the core's words plus the flag that carried the value."""
    flag = FLAGS.get(exc.quantity or "")
    return f"error: {exc}" + (f" ({flag})" if flag else "")


def fmt_table(headers: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A plain-text table, right-aligned columns."""
    cells = [list(headers)] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


#: Seconds a piece of work runs before its progress is written to a log (not a terminal).
QUIET_SECONDS = 5.0


class Progress:
    """A progress callback for the core: a bar on stderr when it is a terminal; otherwise (a
    log, a batch job) a line each tenth of work that has run for :data:`QUIET_SECONDS`."""

    def __init__(self, label: str):
        self.label = label
        self.tty = sys.stderr.isatty()
        self.last = -1
        self.start = time.monotonic()

    def __call__(self, done: int, total: int) -> bool | None:
        if total <= 0:
            return None
        if not self.tty:
            tenth = int(10 * done / total)
            if tenth > self.last and time.monotonic() - self.start >= QUIET_SECONDS:
                self.last = tenth
                sys.stderr.write(f"{self.label}: {100 * done / total:.0f}% "
                                 f"({time.monotonic() - self.start:.0f} s)\n")
                sys.stderr.flush()
            return None
        pct = int(100 * done / total)
        if pct != self.last:
            self.last = pct
            bar = "#" * (pct // 4)
            sys.stderr.write(f"\r{self.label} [{bar:<25}] {pct:3d}%")
            if done >= total:
                sys.stderr.write("\n")
            sys.stderr.flush()
        return None


# ------------------------------------------------------------------------------ options
def add_level_options(p: argparse.ArgumentParser, default_levels: str) -> None:
    lv = p.add_mutually_exclusive_group()
    lv.add_argument("--interp", type=WHOLE_ARG, metavar="K",
                    help="K points interpolated between data points (0 = standard mesh; "
                         "default 4, the paper's reference mesh)")
    lv.add_argument("--triangles", type=WHOLE_ARG, metavar="N",
                    help="at most N triangles per leaf (inverse multi-line segment splitting)")
    lv.add_argument("--levels", nargs="?", const=default_levels, metavar="LIST",
                    help=f"compare levels (default {default_levels})")
    p.add_argument("--no-preserve-area", dest="preserve_area", action="store_false",
                   help="below the standard mesh, do not widen cross-sections to keep the "
                        "smooth surface's area")


def check_export(path: str | None, levels: list[Level]) -> None:
    """Refuse, before any work, a mesh export of several levels or to an unusable path."""
    if path is None:
        return
    if len(levels) > 1:
        raise MaizevizError("--export writes one level: use it with --interp or --triangles")
    from maizeviz.io.meshfile import check_mesh_path  # the writers: when a mesh is written

    check_mesh_path(path)


def levels_from(args: argparse.Namespace, default_k: int = 4) -> list[Level]:
    """The levels asked for by --levels, --triangles or --interp (default K = 4)."""
    if args.levels is not None:
        return parse_levels(args.levels)
    if args.triangles is not None:
        return [Level(triangles=args.triangles)]
    return [Level(interp=default_k if args.interp is None else args.interp)]


def add_canopy_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("points", help="points file of the digitized plants (CSV or Parquet; field coordinates, cm), "
                                  "a .maizeviz project (its points and its layout), or a mesh "
                                  "file (.ply, .obj) with a plant and leaf id per face")
    p.add_argument("--tile", metavar="AxB",
                   help="repeat the digitized block A times across rows (x) and B times along "
                        "them (y); the paper uses 3x3 (default 1x1; a project's own layout)")
    p.add_argument("--block", metavar="RxP",
                   help="rows x plants per row of the digitized block (default: inferred from "
                        "the stalk positions)")
    p.add_argument("--row-spacing", type=NUMBER_ARG, default=60.0, metavar="CM",
                   help="distance between rows along x, cm (default 60)")
    p.add_argument("--plant-spacing", type=NUMBER_ARG, default=30.0, metavar="CM",
                   help="distance between plants in a row along y, cm (default 30)")
    p.add_argument("--layout", metavar="JSON", help="a layout file instead of tiling")
    p.add_argument("--strict", action="store_true",
                   help="stop at the first bad leaf instead of skipping it")
    p.add_argument("--force", action="store_true",
                   help="run work estimated to take longer than 15 min (what would not fit in "
                        "memory is refused anyway)")
    m = p.add_argument_group("a mesh file as the canopy (.ply, .obj; see docs/cli.md)")
    m.add_argument("--mesh-unit", choices=sorted(UNITS), default=None,
                   help="length unit of the mesh file (default cm, refusing a mesh under 5 or "
                        "over 1000 units tall, which is likely in m or mm)")
    m.add_argument("--up", choices=UP_AXES, default=None,
                   help="the mesh file's up axis: z (default; OpenAlea, Helios) or y (many "
                        "scanners: field x, y, z = file x, -z, y)")
    m.add_argument("--field", metavar="X0,Y0,X1,Y1",
                   help="the ground of the mesh canopy, cm (default: the mesh's bounding box "
                        "seen from above): LAI, ground cover, default sample rectangle and the "
                        "tile of --periodic")
    m.add_argument("--mesh-plant", metavar="NAME",
                   help="PLY face property holding the plant id (default: plant, plant_id, "
                        "plantid)")
    m.add_argument("--mesh-leaf", metavar="NAME",
                   help="PLY face property holding the leaf id (default: leaf, leaf_id, "
                        "leafid, organ, organ_id, label, object_label)")


def check_canopy_costs(leaves: list[Leaf], layout: CanopyLayout, levels: list[Level],
                       force: bool, per_level: Sequence[Cost] = ()) -> None:
    """Refuse, before building anything, canopies (plus ``per_level`` work on each) that would
    not fit in memory, or take too long unless ``force``."""
    say_estimate(check([[layout_cost(leaves, layout, level), *per_level] for level in levels],
                       force))


def say_estimate(estimate) -> None:
    """Tell the estimate (:func:`maizeviz.cost.check`'s) of work long enough to wait for."""
    from maizeviz.cost import SAY_SECONDS

    if estimate is not None and estimate.seconds >= SAY_SECONDS:
        say(f"estimate: {estimate.describe()}")


def load_leaves(path: str, strict: bool = False, degree: int = 3, method: str = "chord",
                progress: ProgressCallback | None = None) -> tuple[list[Leaf], list[LeafError]]:
    """Read, grid and fit a points file, saying skipped lines and repairs on stderr. A field
    (:func:`maizeviz.canopy.field.field_input`: a large Parquet file) is surveyed instead,
    its leaves fitted when a canopy is built (:class:`~maizeviz.canopy.field.FieldLeaves`)."""
    if degree == 3 and method == "chord":
        from maizeviz.canopy.field import field_input, read_field

        if field_input(path):
            field = read_field(path, strict, progress or Progress("reading the field"),
                               workers=os.cpu_count() or 1)
            if field is not None:
                for note in field.notes:
                    say(f"note: {note}")
                say(f"note: {path}: a field of {len(field.bases):,} plants and {len(field):,} "
                    "leaves, read plant by plant")
                return field, field.skipped  # type: ignore[return-value]
    found = read_leaves(path, strict, degree, method, progress)
    for problem in found.problems:
        say(f"warning: {problem}")
    for note in found.notes:
        say(f"note: {note}")
    return found.leaves, found.skipped


def canopy_setup(args: argparse.Namespace) -> tuple[list[Leaf], list[LeafError], CanopyLayout]:
    """Leaves and layout from the canopy options, or from a ``.maizeviz`` project given as
    the points (its points and the layout it opens with; ``--layout`` replaces that layout,
    ``--tile`` and ``--block`` retile its block); warnings on stderr."""
    tile = check_tile(parse_shape(args.tile or "1x1", "tile"))   # refused before reading
    block = parse_shape(args.block, "block") if args.block else None
    if is_project(args.points):
        leaves, skipped, layout = _project_setup(args)
        if args.layout is None and args.tile is None and args.block is None:
            return leaves, skipped, layout
    else:
        leaves, skipped = load_leaves(args.points, args.strict)
    if not leaves:
        for e in skipped:
            say(f"skipped: {e}")
        raise MaizevizError("no leaf could be reconstructed; the canopy is empty")
    layout = layout_for(leaves, tile, args.row_spacing, args.plant_spacing, block, args.layout)
    for w in layout.warnings:
        say(f"note: {w}")
    return leaves, skipped, layout


def is_mesh(path: str | Path) -> bool:
    """Whether ``path`` names a mesh file (.ply, .obj) to trace as it is."""
    return Path(path).suffix.lower() in MESH_SUFFIXES


def input_name(path: str | Path) -> str:
    """What the canopy input is, in words: "the mesh file", "the project", "the points file"."""
    return "the mesh file" if is_mesh(path) else "the project" if is_project(path) \
        else "the points file"


#: Options that shape a canopy of digitized plants, refused with a mesh file (flag, what
#: makes it given).
_DIGITIZED_ONLY = (("--tile", "tile"), ("--block", "block"), ("--layout", "layout"),
                   ("--interp", "interp"), ("--triangles", "triangles"), ("--levels", "levels"),
                   ("--save-layout", "save_layout"))
_MESH_ONLY = (("--mesh-unit", "mesh_unit"), ("--up", "up"), ("--field", "field"),
              ("--mesh-plant", "mesh_plant"), ("--mesh-leaf", "mesh_leaf"))


def check_input_options(args: argparse.Namespace) -> None:
    """Refuse options that do not fit the input: tiling, layouts and mesh levels with a mesh
    file (it is traced as it is), mesh options with digitized plants."""
    if is_mesh(args.points):
        given = [flag for flag, name in _DIGITIZED_ONLY if getattr(args, name, None) is not None]
        if not getattr(args, "preserve_area", True):
            given.append("--no-preserve-area")
        if given:
            raise MaizevizError(f"{', '.join(given)}: a mesh file is traced as it is, its plants "
                                "where they stand (no tiling, layout or mesh levels)")
        return
    given = [flag for flag, name in _MESH_ONLY if getattr(args, name, None) is not None]
    if given:
        raise MaizevizError(f"{', '.join(given)}: for a mesh file (.ply, .obj) given in place of "
                            "the points")


def mesh_setup(args: argparse.Namespace) -> Canopy:
    """The canopy of a mesh file given as the points, with the mesh options; what was read and
    decided on stderr."""
    field = tuple(floats(args.field, "the field X0,Y0,X1,Y1", "field", 4)) if args.field \
        else None
    canopy, mesh, notes = read_mesh_canopy(args.points, args.mesh_unit, args.up or "z", field,  # type: ignore[arg-type]
                                           args.mesh_plant, args.mesh_leaf)
    for note in notes:
        say(f"note: {note}")
    for w in canopy.layout.warnings:
        say(f"note: {w}")
    poly = f", {mesh.polygons:,} polygons cut into triangles" if mesh.polygons else ""
    stalk = f" and {len(canopy.stalk_faces):,} stalk" if len(canopy.stalk_faces) else ""
    say(f"{args.points}: {mesh.kind}, {mesh.file_faces:,} faces{poly}: "
        f"{canopy.n_triangles:,} leaf{stalk} triangles, {canopy.n_leaves:,} leaves of "
        f"{canopy.n_plants:,} plants (ids from {mesh.ids}); unit {args.mesh_unit or 'cm'}, "
        f"{args.up or 'z'} up")
    return canopy


def is_project(path: str | Path) -> bool:
    """Whether ``path`` names a ``.maizeviz`` project (by its name, as the app's File menu)."""
    from maizeviz.io.archive import SUFFIX  # zipfile and hashlib: when a project is read

    return Path(path).suffix.lower() == SUFFIX


def _project_setup(args: argparse.Namespace) -> tuple[list[Leaf], list[LeafError], CanopyLayout]:
    from maizeviz.project.study import read_study

    study = read_study(args.points)
    for note in study.notes:
        say(f"note: {note}")
    say(f"{args.points}: {len(study.plants.leaves)} leaves, {len(study.layout.placements)} "
        f"plants as the project lays them out; {len(study.results)} stored light results "
        "(not used by this command)")
    if args.strict and study.plants.skipped:
        raise MaizevizError(f"{args.points}: {study.plants.skipped[0]}", quantity="strict")
    return list(study.plants.leaves), list(study.plants.skipped), study.layout


def floats(text: str, what: str, quantity: str, count: int | None = None,
           most: int = MAX_LIST_ITEMS) -> list[float]:
    """Numbers separated by commas (``"0,50,100"``), at most ``most`` of them.

    An empty item (``0,,50``, a trailing comma) is refused rather than dropped: a number left
    out by a slip should not pass unseen. So are underscores (``1_000``) and anything else
    :func:`maizeviz.numbers.number` does not read.
    """
    text = str(text)
    if text.count(",") >= most:
        raise MaizevizError(f"{what}: {text.count(',') + 1:,} values; at most {most:,} are "
                            "taken", quantity=quantity)
    items = text.split(",")
    vals = []
    for k, item in enumerate(items, 1):
        if not item.strip():
            if len(items) == 1:
                raise MaizevizError(f"{what}: no number given", quantity=quantity)
            raise MaizevizError(f"{what}: item {k} of {len(items)} is empty in '{shown(text)}'; "
                                "write numbers separated by single commas", quantity=quantity)
        try:
            vals.append(number(item))
        except ValueError:
            raise MaizevizError(f"{what} must be numbers separated by commas, got "
                                f"'{shown(item)}' in '{shown(text)}'", quantity=quantity) from None
    if count is not None and len(vals) != count:
        raise MaizevizError(f"{what} needs {count} numbers, got '{shown(text)}'",
                            quantity=quantity)
    return vals


def suffixed(path: str | Path, label: str) -> Path:
    """``light.csv`` + ``"K=4"`` -> ``light_K_4.csv`` (one file per level)."""
    p = Path(path)
    return p.with_name(f"{p.stem}_{file_tag(label)}{p.suffix}")


def level_path(path: str | Path, label: str, n_levels: int) -> Path:
    """The file an output of one level goes to: ``path`` itself for a single level, else
    :func:`suffixed` by the level's label."""
    return Path(path) if n_levels == 1 else suffixed(path, label)


def leaves_summary(done: int, skipped: list[LeafError]) -> int:
    """Say the skipped leaves; the exit code (0 all done, 3 some skipped, 1 none done)."""
    for e in skipped:
        say(f"skipped: {e}")
    if skipped:
        say(f"{done} leaves done, {len(skipped)} skipped")
    if done == 0:
        say("error: no leaf could be processed")
        return EXIT_FAIL
    return EXIT_PARTIAL if skipped else EXIT_OK
