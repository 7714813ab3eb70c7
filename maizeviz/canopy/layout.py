"""Where plants stand: the paper's tiling of a digitized block, or a layout file.

Field coordinates are centimetres, z up; by default x = east and y = north, and rows run along
y: ``row_spacing`` is the distance between rows along x (60 cm in the paper), ``plant_spacing``
the distance between plants of a row along y (30 cm). Each plant owns a cell of
row spacing x plant spacing centred on its stalk base; the ground of a canopy is the union of
its cells (tiling) or the field rectangle (layout file).
"""

from __future__ import annotations

import hashlib
import json
import math
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.io.atomic import write_text
from maizeviz.io.inputs import read_input, refuse_zero_tail
from maizeviz.io.points import MAX_ID as MAX_PLANT_ID  # plant ids as in points files
from maizeviz.leaf.fit import Leaf
from maizeviz.leaf.grid import stalk_base
from maizeviz.numbers import whole

LAYOUT_SCHEMA = 1
#: Plants a layout may hold (a hectare at 60 x 30 cm is about 55,000).
MAX_PLANTS = 100_000
#: Shortest spacing and field side (cm): below a centimetre plants would stand inside each
#: other and a leaf area index divides by almost nothing.
MIN_LENGTH_CM = 1.0
#: Farthest coordinate and longest spacing or field side (cm, 1 km): a field plot is far
#: smaller; larger numbers are typing mistakes that would place plants nowhere near the others.
MAX_COORD_CM = 100_000.0
#: Largest random displacement of a plant about its place (cm): farther, it has another place.
MAX_JITTER_CM = 100.0
#: Largest angle (degrees, either sign) for north and plant azimuths: one full turn.
MAX_ANGLE_DEG = 360.0
#: Seeds of the jitter's random generator: whole numbers 0 .. 2^32 - 1.
MAX_SEED = 2**32 - 1
#: Largest layout file read (bytes).
MAX_LAYOUT_BYTES = 20_000_000


class LayoutError(MaizevizError):
    """A layout that cannot be used; the message names the field."""


@dataclass(frozen=True)
class Placement:
    """One plant standing in the canopy.

    Attributes
    ----------
    plant : int
        Id of the digitized plant (in the points file) that stands here.
    x, y : float, cm
        Where its stalk base stands.
    azimuth_deg : float
        Rotation about its stalk, counter-clockwise seen from above, applied to the digitized
        plant.
    tile : tuple[int, int]
        Tile index (0, 0 is the digitized block itself) when the canopy comes from tiling.
    """

    plant: int
    x: float
    y: float
    azimuth_deg: float = 0.0
    tile: tuple[int, int] = (0, 0)


@dataclass(frozen=True)
class CanopyLayout:
    """Placements plus the ground they stand on.

    Attributes
    ----------
    placements : tuple[Placement, ...]
    cells : (k, 4) float64, cm
        Ground rectangles x0, y0, x1, y1 whose union is the ground.
    row_spacing, plant_spacing : float, cm
    north_deg : float
        Angle from north to the field's +y axis, clockwise (0: y points north, x east).
    centre_cells : (j, 4) float64, cm
        Cells of the central tile (or of the whole field), the default light sample area.
    warnings : tuple[str, ...]
    ground_area : float, cm2, or None: the union of the cells
    quantity : the input that set the plants (see :data:`maizeviz.errors.QUANTITIES`):
        "tile" for a tiling, "layout" for a layout document; costs name it
    period : (x0, y0, x1, y1) cm or None: the smallest rectangle the plot repeats, as a mesh
        file says it (:mod:`maizeviz.canopy.from_mesh`); a claim the light verifies before
        using it. A tiling's is :func:`field_period`.
    """

    placements: tuple[Placement, ...]
    cells: np.ndarray
    row_spacing: float
    plant_spacing: float
    north_deg: float = 0.0
    centre_cells: np.ndarray = field(default_factory=lambda: np.empty((0, 4)))
    warnings: tuple[str, ...] = ()
    ground_area: float | None = None
    quantity: str = "tile"
    period: tuple[float, float, float, float] | None = None

    @property
    def ground_area_cm2(self) -> float:
        """Area of the ground (cm2): the union of the cells; for a tiling, exactly the number
        of tiles times the block footprint (tiles are disjoint translations of it)."""
        return self.ground_area if self.ground_area is not None else union_area(self.cells)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """x0, y0, x1, y1 of the ground (cm)."""
        c = self.cells
        return float(c[:, 0].min()), float(c[:, 1].min()), float(c[:, 2].max()), float(c[:, 3].max())

    @property
    def centre_bounds(self) -> tuple[float, float, float, float]:
        c = self.centre_cells if len(self.centre_cells) else self.cells
        return float(c[:, 0].min()), float(c[:, 1].min()), float(c[:, 2].max()), float(c[:, 3].max())


def field_period(layout: CanopyLayout) -> tuple[float, float, float, float] | None:
    """The rectangle (x0, y0, x1, y1) cm a periodic field of ``layout``'s plot repeats, when
    smaller than the plot: a tiling's block (its central tile, the default sample rectangle),
    or the period a mesh file carried; None otherwise (a layout file, one tile)."""
    if layout.period is not None:
        return layout.period
    if layout.quantity == "tile" and len({p.tile for p in layout.placements}) >= 2:
        return layout.centre_bounds
    return None


#: Columns of :func:`placements_array`.
PLACEMENT_COLUMNS = ("plant", "x_cm", "y_cm", "azimuth_deg", "tile_i", "tile_j")


def placements_array(layout: CanopyLayout) -> np.ndarray:
    """(n, 6) float64: plant, x, y (cm), azimuth (degrees), tile i, tile j of each stand, in
    the layout's order."""
    rows = [(p.plant, p.x, p.y, p.azimuth_deg, p.tile[0], p.tile[1]) for p in layout.placements]
    return np.array(rows, np.float64).reshape(-1, len(PLACEMENT_COLUMNS))


def stands_identity(layout: CanopyLayout) -> dict[str, Any]:
    """``{"n": stands, "sha256": hex}``: what identifies the stands of a canopy, in order (the
    digitized plant of each, where it stands to 1e-6 cm, its rotation to 1e-6 degrees and its
    tile). Every traced light result carries that of the canopy it was traced on, so that it
    is never stored or shown on other stands."""
    a = placements_array(layout)
    key = np.round(a, 6) + 0.0             # + 0.0 turns -0.0 into 0.0
    return {"n": int(len(a)), "sha256": hashlib.sha256(key.tobytes()).hexdigest()}


def union_area(rects: np.ndarray) -> float:
    """Exact area of the union of axis-aligned rectangles (k, 4) x0, y0, x1, y1 (cm2).

    Coordinate compression: the distinct x and y edges cut the plane into cells, each either
    inside some rectangle or not.
    """
    rects = np.asarray(rects, dtype=np.float64).reshape(-1, 4)
    if not len(rects):
        return 0.0
    xs = np.unique(rects[:, [0, 2]])
    ys = np.unique(rects[:, [1, 3]])
    cx = 0.5 * (xs[:-1] + xs[1:])
    cy = 0.5 * (ys[:-1] + ys[1:])
    covered = np.zeros((len(cx), len(cy)), dtype=bool)
    for x0, y0, x1, y1 in rects:
        covered |= ((cx > x0) & (cx < x1))[:, None] & ((cy > y0) & (cy < y1))[None, :]
    return math.fsum((np.diff(xs)[:, None] * np.diff(ys)[None, :])[covered])


def _cell(x, y, row_spacing, plant_spacing):
    return [x - row_spacing / 2, y - plant_spacing / 2, x + row_spacing / 2, y + plant_spacing / 2]


def check_spacing(value, name: str = "row spacing") -> float:
    """A spacing (``name``: "row spacing" or "plant spacing") as a number of cm within
    :data:`MIN_LENGTH_CM` .. :data:`MAX_COORD_CM`; LayoutError otherwise."""
    f = _finite(value)
    if f is None or f <= 0:
        raise LayoutError(f"{name} must be a positive number of cm, got {_shown(value)}",
                          quantity=name.replace(" ", "_"))
    if not MIN_LENGTH_CM <= f <= MAX_COORD_CM:
        raise LayoutError(f"{name} is {f:g} cm; it must be from {MIN_LENGTH_CM:g} to "
                          f"{MAX_COORD_CM:g} cm (1 km)", quantity=name.replace(" ", "_"))
    return f


def _check_spacing(row_spacing, plant_spacing):
    """Both spacings numbers of cm within :data:`MIN_LENGTH_CM` .. :data:`MAX_COORD_CM`."""
    check_spacing(row_spacing, "row spacing")
    check_spacing(plant_spacing, "plant spacing")


def _check_count(v, what: str, limit: int, quantity: str | None = None) -> int:
    """A whole number 1 .. limit (numpy integers too)."""
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 1 <= v <= limit:
        raise LayoutError(f"{what} must be a whole number from 1 to {limit:,}, got {_shown(v)}",
                          quantity=quantity)
    return int(v)


def parse_shape(text: str, quantity: str = "tile") -> tuple[int, int]:
    """``"3x3"`` -> (3, 3); both factors whole numbers >= 1 (``quantity`` names the input in
    messages: "tile", "block", "plants")."""
    what = quantity.replace("_", " ")
    parts = str(text).lower().replace(" ", "").split("x")
    try:
        a, b = (whole(p) for p in parts)
    except ValueError:
        raise LayoutError(f"{what} must look like 3x3, got '{text}'", quantity=quantity) from None
    if a < 1 or b < 1:
        raise LayoutError(f"{what} must be at least 1x1, got '{text}'", quantity=quantity)
    return a, b


def plant_bases(leaves: list[Leaf]) -> dict[int, tuple[float, float]]:
    """Stalk base (x, y) in cm of each digitized plant: the median of its leaves' collar
    midrib points (the insertions) seen from above."""
    grids: dict[int, list] = defaultdict(list)
    for lf in leaves:
        grids[lf.grid.plant].append(lf.grid)
    return {p: stalk_base(g) for p, g in grids.items()}


def _clusters(values: np.ndarray, spacing: float) -> np.ndarray:
    """Cluster index of each value: values closer than half a spacing in sorted order share one."""
    order = np.argsort(values)
    breaks = np.concatenate([[0], np.cumsum(np.diff(values[order]) > spacing / 2)])
    out = np.empty(len(values), dtype=int)
    out[order] = breaks
    return out


def check_tile(tile, plants: int = 1) -> tuple[int, int]:
    """The tile count (A, B) as whole numbers, refused when A x B copies of a block of
    ``plants`` plants exceed :data:`MAX_PLANTS`; cheap, so callers can check it before
    reading any points (with ``plants=1``) and again once the block is known."""
    try:
        parts = tuple(tile)
    except TypeError:
        parts = ()
    if len(parts) != 2:
        raise LayoutError(f"the tile count must be two numbers (across rows, along rows), "
                          f"got {_shown(tile)}", quantity="tile")
    a, b = (_check_count(v, "the tile count", MAX_PLANTS, "tile") for v in parts)
    if a * b * plants > MAX_PLANTS:
        block = f"a block of {plants} plants" if plants > 1 else "one plant"
        raise LayoutError(f"{a} x {b} tiles of {block} make {a * b * plants:,} plants; a "
                          f"canopy holds at most {MAX_PLANTS:,}", quantity="tile")
    return a, b


def check_block(block) -> tuple[int, int]:
    """The shape of a digitized block (rows, plants per row) as whole numbers 1 ..
    :data:`MAX_PLANTS`; LayoutError otherwise."""
    if len(block) != 2:
        raise LayoutError(f"the block shape must be two numbers, got {_shown(block)}")
    return (_check_count(block[0], "the block shape", MAX_PLANTS, "block"),
            _check_count(block[1], "the block shape", MAX_PLANTS, "block"))


def block_lattice(bases: dict[int, tuple[float, float]], row_spacing: float,
                  plant_spacing: float) -> tuple[tuple[int, int], dict[int, tuple[float, float]]]:
    """Rows x plants per row of a digitized block, and each plant's lattice position (cm).

    Stalks closer than half a row spacing along x share a row, and likewise along y; the
    lattice is regular at the nominal spacings and placed where it best fits the stalks, so
    digitizing noise in the stalk positions leaves no gap or overlap between cells.
    """
    ids = list(bases)
    xy = np.array([bases[i] for i in ids], dtype=np.float64).reshape(-1, 2)
    rx = _clusters(xy[:, 0], row_spacing)
    ry = _clusters(xy[:, 1], plant_spacing)
    # a regular lattice at the nominal spacings, placed where it fits the stalks best
    mx = (xy[:, 0] - rx * row_spacing).mean() + np.arange(rx.max() + 1) * row_spacing
    my = (xy[:, 1] - ry * plant_spacing).mean() + np.arange(ry.max() + 1) * plant_spacing
    return (len(mx), len(my)), {i: (float(mx[a]), float(my[b])) for i, a, b in zip(ids, rx, ry)}


def tiled_layout(bases: dict[int, tuple[float, float]], tile: tuple[int, int],
                 row_spacing: float = 60.0, plant_spacing: float = 30.0,
                 block: tuple[int, int] | None = None, north_deg: float = 0.0) -> CanopyLayout:
    """Repeat a digitized block ``tile`` = (A, B) times (A along x across rows, B along y).

    Parameters
    ----------
    bases : {plant id: (x, y) cm}
        Stalk base of every digitized plant in field coordinates.
    block : (rows, plants per row), optional
        Shape of the digitized block; inferred from ``bases`` when not given.

    The tiles are translations of the block footprint by (rows x row_spacing) along x and
    (plants x plant_spacing) along y, centred on the digitized block, which stays tile (0, 0).
    """
    _check_spacing(row_spacing, plant_spacing)
    if not bases:
        raise LayoutError("no plant to lay out")
    if len(bases) > MAX_PLANTS:
        raise LayoutError(f"{len(bases):,} digitized plants; a canopy holds at most {MAX_PLANTS:,}")
    for pid, xy in bases.items():
        if len(xy) != 2 or not all(_finite(v) is not None and abs(v) <= MAX_COORD_CM
                                   for v in xy):
            raise LayoutError(f"plant {pid}: its stalk base {tuple(xy)} cm is not within "
                              f"{MAX_COORD_CM:g} cm (1 km) of the origin")
    a, b = check_tile(tile, len(bases))
    if block is not None:
        block = check_block(block)
    north_deg = _angle(north_deg, "north")
    warnings = []
    inferred, lattice = block_lattice(bases, row_spacing, plant_spacing)
    if block is None:
        block = inferred
        warnings.append(f"block inferred from stalk positions: {block[0]} rows x {block[1]} "
                        f"plants per row ({len(bases)} plants)")
    elif block[0] * block[1] != len(bases):
        warnings.append(f"the block shape {block[0]}x{block[1]} has {block[0] * block[1]} places "
                        f"but the file has {len(bases)} plants")
    step_x, step_y = block[0] * row_spacing, block[1] * plant_spacing
    placements, cells, centre = [], [], []
    for ti in range(a):
        for tj in range(b):
            key = (ti - (a - 1) // 2, tj - (b - 1) // 2)
            dx, dy = key[0] * step_x, key[1] * step_y
            for pid, (x, y) in sorted(bases.items()):
                placements.append(Placement(pid, x + dx, y + dy, 0.0, key))
                lx, ly = lattice[pid]
                c = _cell(lx + dx, ly + dy, row_spacing, plant_spacing)
                cells.append(c)
                if key == (0, 0):
                    centre.append(c)
    overlap = _overlaps(np.array(centre))
    if overlap:
        warnings.append(f"digitized plants {overlap} stand closer than the spacing: their "
                        "cells overlap")
    return CanopyLayout(tuple(placements), np.array(cells), float(row_spacing),
                        float(plant_spacing), north_deg, np.array(centre), tuple(warnings),
                        a * b * union_area(np.array(centre)))


#: Above this many overlapping pairs of cells, the warning gives their count only (the area
#: counted twice would need every pair in memory).
MAX_OVERLAP_PAIRS = 2_000_000
#: Up to this many cells, overlaps are found among all pairs with numpy (20,000 pairs at most);
#: above, with a k-d tree (900 cells: 0.17 s for all pairs, 0.01 s with the tree; the layout
#: editor checks a layout at every edit).
SMALL_FIELD = 200


def _overlaps(cells: np.ndarray) -> str:
    """How much ground equal-sized cells (k, 4) count twice, in words ('' when none).

    Cells of one size overlap only with neighbours closer than one cell in x and in y, found
    with a k-d tree in the Chebyshev metric, so a large field costs O(k log k). Plants off
    their place by less than a tenth of the spacing (digitizing noise, a stalk not quite in
    line) are not worth a warning.
    """
    if len(cells) < 2:
        return ""
    w = cells[0, 2] - cells[0, 0]
    h = cells[0, 3] - cells[0, 1]
    centres = np.column_stack([(cells[:, 0] + cells[:, 2]) / (2 * w),
                               (cells[:, 1] + cells[:, 3]) / (2 * h)])
    if len(centres) <= SMALL_FIELD:             # every pair at once: no k-d tree to import
        i, j = np.triu_indices(len(centres), 1)
        near = np.max(np.abs(centres[i] - centres[j]), axis=1) <= 0.9    # as query_pairs
        pairs = np.column_stack([i[near], j[near]])
    else:
        from scipy.spatial import cKDTree

        tree = cKDTree(centres)
        # count first (no pairs held): plants packed far closer than the spacing (100,000
        # plants 1 cm apart with a 30 cm spacing) make ~10^8 pairs, gigabytes if listed
        n_pairs = (int(tree.count_neighbors(tree, 0.9, p=np.inf)) - len(centres)) // 2
        if n_pairs > MAX_OVERLAP_PAIRS:
            return f"({n_pairs:,} overlapping pairs)"
        pairs = tree.query_pairs(0.9, p=np.inf, output_type="ndarray")
    if not len(pairs):
        return ""
    d = np.abs(centres[pairs[:, 0]] - centres[pairs[:, 1]])
    twice = float(np.sum((1 - d[:, 0]) * (1 - d[:, 1]))) * w * h
    return (f"({len(pairs)} overlapping {_pairs(len(pairs))}, about {twice:.0f} cm2 counted "
            "twice)")


def _pairs(n: int) -> str:
    """'pair' or 'pairs' after a count of ``n``."""
    return "pair" if n == 1 else "pairs"


# ------------------------------------------------------------------------- layout files
def _shown(v, limit: int = 40) -> str:
    """A value as JSON for a message, shortened; never fails."""
    try:
        text = json.dumps(v)
    except (TypeError, ValueError, RecursionError):
        try:
            text = str(v)                                  # numpy numbers, tuples
        except ValueError:                                 # an integer of over 4300 digits
            text = "a number too long to show"
    return text if len(text) <= limit else text[:limit] + "..."


def _finite(v) -> float | None:
    """``v`` as a finite float, or None for anything else (bools, text, NaN, 10**400)."""
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        return None
    try:
        f = float(v)
    except OverflowError:
        return None
    return f if math.isfinite(f) else None


def _angle(v, what: str) -> float:
    """An angle in degrees within +-:data:`MAX_ANGLE_DEG`."""
    f = _finite(v)
    if f is None or abs(f) > MAX_ANGLE_DEG:
        raise LayoutError(f"{what} must be an angle from -{MAX_ANGLE_DEG:g} to "
                          f"{MAX_ANGLE_DEG:g} degrees, got {_shown(v)}")
    return f


def _number(obj, key, where, default=None, positive=False, low=None, high=None, unit=" cm"):
    """``obj[key]`` as a finite float within ``low`` .. ``high``; a LayoutError names
    ``where`` and ``key`` (the field) otherwise; ``default`` when absent (None: required)."""
    if key not in obj:
        if default is None:
            raise LayoutError(f"{where}: '{key}' is missing")
        return default
    v = obj[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise LayoutError(f"{where}: '{key}' must be a number, got {_shown(v)}")
    try:
        f = float(v)
    except OverflowError:                                   # an integer of 309 digits or more
        f = math.inf
    if not math.isfinite(f):
        raise LayoutError(f"{where}: '{key}' must be a number, got {_shown(v)}")
    if positive and f <= 0:
        raise LayoutError(f"{where}: '{key}' must be positive, got {f:g}")
    if (low is not None and f < low) or (high is not None and f > high):
        raise LayoutError(f"{where}: '{key}' is {f:g}{unit}; it must be from {low:g} to "
                          f"{high:g}{unit}")
    return f


def load_layout(path: str | Path, plants: set[int] | None = None) -> CanopyLayout:
    """Read a layout file (schema in the README): a regular file of at most
    :data:`MAX_LAYOUT_BYTES` bytes of UTF-8 JSON.

    Parameters
    ----------
    plants : set of int, optional
        Ids of the digitized plants available; a position naming another is an error.

    Raises
    ------
    LayoutError
        Naming the field that is wrong.
    """
    path = Path(path)
    raw = refuse_zero_tail(read_input(path, "layout file", MAX_LAYOUT_BYTES, LayoutError), path,
                           "layout file", LayoutError)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise LayoutError(f"{path}: cannot be read (not UTF-8 text: byte {exc.start})") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise LayoutError(f"{path}: not valid JSON ({exc})") from None
    except RecursionError:
        raise LayoutError(f"{path}: not valid JSON (nested too deeply)") from None
    except ValueError:                                   # an integer of over 4300 digits
        raise LayoutError(f"{path}: not valid JSON (a number too long to read)") from None
    return layout_from_dict(data, plants, str(path))


def _field(data: dict, source: str) -> tuple[float, float, float, float]:
    """A layout document's ``field`` {x0, y0, x1, y1} [cm], each side at least
    :data:`MIN_LENGTH_CM`."""
    coord = {"low": -MAX_COORD_CM, "high": MAX_COORD_CM}
    fld = data.get("field")
    if not isinstance(fld, dict):
        raise LayoutError(f"{source}: 'field' must be an object {{x0, y0, x1, y1}} in cm")
    x0, y0, x1, y1 = (_number(fld, k, f"{source}: field", **coord) for k in ("x0", "y0", "x1", "y1"))
    if x1 <= x0 or y1 <= y0:
        raise LayoutError(f"{source}: field must have x1 > x0 and y1 > y0")
    if x1 - x0 < MIN_LENGTH_CM or y1 - y0 < MIN_LENGTH_CM:
        raise LayoutError(f"{source}: field is {x1 - x0:g} x {y1 - y0:g} cm; each side must be "
                          f"at least {MIN_LENGTH_CM:g} cm")
    return x0, y0, x1, y1


def _stand(pos, x: float, w: str, plants: set[int] | None,
           rng: np.random.Generator) -> tuple[Placement, float]:
    """One plant of a row at ``x`` [cm]: its placement (moved by its jitter, drawn from
    ``rng``) and the y [cm] it was given at."""
    coord = {"low": -MAX_COORD_CM, "high": MAX_COORD_CM}
    if not isinstance(pos, dict):
        raise LayoutError(f"{w} must be an object {{y, plant}}")
    y = _number(pos, "y", w, **coord)
    pid = _plant_id(pos, w, plants)
    az = _number(pos, "azimuth_deg", w, default=0.0, low=-MAX_ANGLE_DEG,
                 high=MAX_ANGLE_DEG, unit=" degrees")
    jitter = _number(pos, "jitter_cm", w, default=0.0)
    if not 0 <= jitter <= MAX_JITTER_CM:
        raise LayoutError(f"{w}: 'jitter_cm' is {jitter:g} cm; it must be from 0 to "
                          f"{MAX_JITTER_CM:g} cm (farther, the plant has another place: "
                          "give that position)")
    px, py = x, y
    if jitter > 0:
        r, t = jitter * np.sqrt(rng.random()), 2 * np.pi * rng.random()
        px, py = x + r * np.cos(t), y + r * np.sin(t)
    return Placement(pid, px, py, az, (0, 0)), y


def layout_from_dict(data, plants: set[int] | None = None, source: str = "layout") -> CanopyLayout:
    """Validate a layout document (already parsed JSON); see :func:`load_layout`.

    Every value is checked by type and range (spacings and field sides
    :data:`MIN_LENGTH_CM` .. :data:`MAX_COORD_CM`, coordinates within :data:`MAX_COORD_CM`,
    jitter up to :data:`MAX_JITTER_CM`, angles within :data:`MAX_ANGLE_DEG`, the seed
    0 .. :data:`MAX_SEED`); a :class:`LayoutError` names the field, e.g.
    ``rows[1].plants[0]: 'jitter_cm'``.
    """
    if not isinstance(data, dict):
        raise LayoutError(f"{source}: a layout is a JSON object")
    version = data.get("maizeviz_layout")
    if isinstance(version, bool) or version != LAYOUT_SCHEMA:
        raise LayoutError(f"{source}: 'maizeviz_layout' is {_shown(version)}; this version of "
                          f"maizeviz reads schema {LAYOUT_SCHEMA}")
    length = {"low": MIN_LENGTH_CM, "high": MAX_COORD_CM}
    coord = {"low": -MAX_COORD_CM, "high": MAX_COORD_CM}
    rs = _number(data, "row_spacing", source, positive=True, **length)
    ps = _number(data, "plant_spacing", source, positive=True, **length)
    north = _number(data, "north_deg", source, default=0.0, low=-MAX_ANGLE_DEG,
                    high=MAX_ANGLE_DEG, unit=" degrees")
    x0, y0, x1, y1 = _field(data, source)
    rows = data.get("rows")
    if not isinstance(rows, list) or not rows:
        raise LayoutError(f"{source}: 'rows' must be a non-empty list")
    count = sum(len(r.get("plants", [])) if isinstance(r, dict) and
                isinstance(r.get("plants"), list) else 0 for r in rows)
    if count > MAX_PLANTS:
        raise LayoutError(f"{source}: {count} plants; a layout holds at most {MAX_PLANTS}")
    seed = _seed(data, source)
    rng = np.random.default_rng(seed)
    placements, cells, warnings, outside = [], [], [], []
    for i, row in enumerate(rows):
        where = f"{source}: rows[{i}]"
        if not isinstance(row, dict):
            raise LayoutError(f"{where} must be an object {{x, plants}}")
        x = _number(row, "x", where, **coord)
        plist = row.get("plants")
        if not isinstance(plist, list):
            raise LayoutError(f"{where}: 'plants' must be a list")
        for j, pos in enumerate(plist):
            w = f"{where}.plants[{j}]"
            place, y = _stand(pos, x, w, plants, rng)
            if not (x0 <= place.x <= x1 and y0 <= place.y <= y1):
                outside.append(f"{w}: plant at ({place.x:.1f}, {place.y:.1f}) cm")
            placements.append(place)
            cells.append(_cell(x, y, rs, ps))
    if not placements:
        raise LayoutError(f"{source}: no plant stands in the layout: every row's 'plants' "
                          "list is empty")
    if outside:
        more = f" and {len(outside) - 1} more" if len(outside) > 1 else ""
        warnings.append(f"{outside[0]} stands outside the field{more}")
    overlap = _overlaps(np.array(cells))
    if overlap:
        warnings.append(f"{source}: some positions are closer than the spacing {overlap}")
    field_rect = np.array([[x0, y0, x1, y1]])
    return CanopyLayout(tuple(placements), field_rect, rs, ps, north, field_rect, tuple(warnings),
                        quantity="layout")


def _seed(data: dict, source: str) -> int:
    """The jitter seed: a whole number 0 .. :data:`MAX_SEED` (0 when absent)."""
    v = data.get("seed", 0)
    whole = isinstance(v, int) or (isinstance(v, float) and math.isfinite(v) and v.is_integer())
    if isinstance(v, bool) or not whole or not 0 <= v <= MAX_SEED:
        raise LayoutError(f"{source}: 'seed' must be a whole number from 0 to {MAX_SEED}, "
                          f"got {_shown(v)}")
    return int(v)


def _plant_id(pos: dict, where: str, plants: set[int] | None) -> int:
    """The digitized plant a position names, checked against the plants available."""
    pid = pos.get("plant")
    if isinstance(pid, bool) or not isinstance(pid, int) or abs(pid) > MAX_PLANT_ID:
        raise LayoutError(f"{where}: 'plant' must be an integer plant id (at most "
                          f"{MAX_PLANT_ID:,}), got {_shown(pid)}")
    if plants is not None and pid not in plants:
        have = sorted(plants)
        shown = ", ".join(map(str, have[:10])) + (f" and {len(have) - 10} more"
                                                  if len(have) > 10 else "")
        raise LayoutError(f"{where}: plant {pid} is not in the points file (it has {shown})")
    return pid


def rows_of(placements: list[Placement] | tuple[Placement, ...]) -> list[dict]:
    """Placements grouped into the rows of a layout document, by x (to 1e-6 cm), sorted by x;
    values are kept exactly as they are."""
    rows: dict[float, list[dict]] = {}
    xs: dict[float, float] = {}
    for p in placements:
        key = round(p.x, 6)
        xs.setdefault(key, p.x)
        rows.setdefault(key, []).append(
            {"y": p.y, "plant": p.plant, "azimuth_deg": p.azimuth_deg})
    return [{"x": xs[k], "plants": ps} for k, ps in sorted(rows.items())]


def layout_to_dict(layout: CanopyLayout,
                   placements: list[Placement] | tuple[Placement, ...] | None = None) -> dict:
    """A layout document (schema :data:`LAYOUT_SCHEMA`) for a layout, or for other
    ``placements`` on the same field and spacings (an edited layout)."""
    x0, y0, x1, y1 = layout.bounds
    return {"maizeviz_layout": LAYOUT_SCHEMA, "row_spacing": layout.row_spacing,
            "plant_spacing": layout.plant_spacing, "north_deg": layout.north_deg,
            "field": {"x0": x0, "y0": y0, "x1": x1, "y1": y1},
            "rows": rows_of(layout.placements if placements is None else placements)}


def save_layout(path: str | Path, layout: CanopyLayout) -> None:
    """Write a layout file (atomically)."""
    write_text(path, json.dumps(layout_to_dict(layout), indent=1) + "\n")


def layout_for(leaves: list[Leaf], tile: tuple[int, int] = (1, 1), row_spacing: float = 60.0,
               plant_spacing: float = 30.0, block: tuple[int, int] | None = None,
               layout_file: str | Path | None = None) -> CanopyLayout:
    """Where the digitized plants of ``leaves`` stand: a layout file if given, else the
    digitized block tiled ``tile`` times (the paper's 3 x 3). ``leaves``: fitted leaves, or a
    field's (:class:`~maizeviz.canopy.field.FieldLeaves`, which knows its plants' bases)."""
    field_bases = getattr(leaves, "bases", None)
    if field_bases is not None:
        if not field_bases:
            raise LayoutError("no leaf could be reconstructed; the canopy is empty")
        if layout_file is not None:
            return load_layout(layout_file, set(field_bases))
        return tiled_layout(field_bases, tile, row_spacing, plant_spacing, block)
    plants = {lf.grid.plant for lf in leaves}
    if not plants:
        raise LayoutError("no leaf could be reconstructed; the canopy is empty")
    if layout_file is not None:
        return load_layout(layout_file, plants)
    return tiled_layout(plant_bases(leaves), tile, row_spacing, plant_spacing, block)
