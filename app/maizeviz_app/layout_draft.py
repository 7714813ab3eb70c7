"""The layout being edited, without Qt: where each plant stands, which digitized plant it is,
its turn about its stalk; and every edit of it (move, turn, another plant, add, duplicate,
remove, a regular field of rows x plants, a tiling, a layout file).

The draft keeps every placement as the exact floats it came with, so a plant moves only when
someone moves it and a layout applied without an edit is the layout it was. Each edit says what
it changed (``edited(change, text, merge)``) so that an undo history can record it
(:mod:`maizeviz_app.undo`) and :meth:`LayoutDraft.apply` can set it back or again. Edits are
checked where they are made: a plant id the points file lacks, a position outside the 1 km the
core accepts, or removing the last plant is refused with a :class:`LayoutError` naming it.

Plants standing closer than their spacings allow (cells of row spacing x plant spacing
overlapping by more than a tenth of a spacing, the core's criterion for its warning) are listed
by :meth:`LayoutDraft.overlaps`; the top view draws them red.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from psygnal import Signal

from maizeviz.canopy.layout import (
    MAX_COORD_CM,
    MAX_PLANTS,
    CanopyLayout,
    LayoutError,
    Placement,
    block_lattice,
    check_spacing,
    layout_from_dict,
    layout_to_dict,
    tiled_layout,
)

#: Cells closer than this share of a spacing (in x and in y) overlap enough to be drawn red
#: (the core warns from the same share: plants off their place by less than a tenth of the
#: spacing are digitizing noise).
OVERLAP_REACH = 0.9


@dataclass(frozen=True, eq=False)
class Snapshot:
    """Everything a whole-layout change replaces: the ground (``base``), the placements and
    the tiling they came from (None: a layout file or rows x plants by parameters). Equal
    snapshots have the same base (the same object: a ground holds arrays) and equal
    placements, tiling and source."""

    base: CanopyLayout | None
    placements: tuple[Placement, ...]
    tiling: tuple[int, int] | None
    source: str = ""

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Snapshot) and other.base is self.base and \
            (other.placements, other.tiling, other.source) == \
            (self.placements, self.tiling, self.source)

    __hash__ = None  # type: ignore[assignment]


@dataclass(frozen=True)
class Change:
    """One edit: placement ``index`` from ``before`` to ``after`` (Placements), or, with
    ``index`` -1, the whole layout (Snapshots)."""

    index: int
    before: Any
    after: Any


def overlap_pairs(xy: np.ndarray, row_spacing: float, plant_spacing: float,
                  reach: float = OVERLAP_REACH) -> np.ndarray:
    """Pairs (k, 2) of indices of plants at ``xy`` (n, 2) cm whose cells (row spacing along x
    by plant spacing along y, centred on the stalk) overlap: closer than ``reach`` of a
    spacing in x and in y. Sorted, i < j."""
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    if len(xy) < 2:
        return np.empty((0, 2), dtype=np.int64)
    scaled = xy / [row_spacing, plant_spacing]
    from scipy.spatial import cKDTree

    # Chebyshev distance below reach: overlapping in x and in y; an open ball, as '<'
    pairs = cKDTree(scaled).query_pairs(reach * (1 - 1e-12), p=np.inf, output_type="ndarray")
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))] if len(pairs) else \
        np.empty((0, 2), dtype=np.int64)


class LayoutDraft:
    """The layout being edited (see the module docstring).

    Attributes
    ----------
    base : CanopyLayout or None
        The ground (field, cells, spacings) of the last tiling, layout file or regular field.
    placements : list[Placement]
        The placements as edited.
    tiling : (int, int) or None
        Tiles of the digitized block, when the placements are a tiling.
    source : str
        What the base came from, in words ("", a tiling: see ``tiling``).
    plants : set[int]
        The digitized plants a placement may name.
    bases : dict[int, (float, float)]
        The digitized plants' stalk bases (cm), for tilings.
    snap_cm : float
        Moves, additions and duplicates land on a grid of this step (0: off).

    Signals
    -------
    changed(index) : placement ``index`` changed; -1: everything did.
    edited(change, text, merge) : an edit was made (``merge``: a key shared by edits that
        are one step, such as the turns of one plant by the mouse wheel; None).
    replayed(change, which) : an edit undone (``which`` 0) or redone (1).
    """

    changed = Signal(int)
    edited = Signal(object, str, object)
    replayed = Signal(object, int)

    def __init__(self) -> None:
        self.base: CanopyLayout | None = None
        self.placements: list[Placement] = []
        self.tiling: tuple[int, int] | None = None
        self.source = ""
        self.plants: set[int] = set()
        self.bases: dict[int, tuple[float, float]] = {}
        self.snap_cm = 0.0

    # ------------------------------------------------------------------ reading
    def snapshot(self) -> Snapshot:
        return Snapshot(self.base, tuple(self.placements), self.tiling, self.source)

    def edits(self) -> int:
        """Placements that differ from the tiling, file or field they came from."""
        if self.base is None:
            return 0
        n = abs(len(self.placements) - len(self.base.placements))
        return n + sum(a != b for a, b in zip(self.placements, self.base.placements))

    def document(self) -> dict:
        """The layout document (schema of the README) of the edited placements."""
        if self.base is None:
            raise LayoutError("no layout to edit yet: open a points file first")
        return layout_to_dict(self.base, self.placements)

    def layout(self) -> CanopyLayout:
        """The edited layout, checked like a layout file (LayoutError names the problem).

        The ground (cells, ground area) is the base's, and the placements are the edited ones
        themselves, in their order and to the last bit: a layout applied without an edit is the
        layout it was.
        """
        checked = layout_from_dict(self.document(), self.plants, "layout")
        assert self.base is not None                    # document() refused otherwise
        return replace(self.base, placements=tuple(self.placements), warnings=checked.warnings)

    def block(self) -> tuple[int, int] | None:
        """Rows x plants per row of the digitized block (None: no stalk bases known)."""
        if not self.bases or self.base is None:
            return None
        return block_lattice(self.bases, self.base.row_spacing, self.base.plant_spacing)[0]

    def _row_counts(self) -> np.ndarray:
        """(rows,) plants in each row of the placements: stalks closer than half a row
        spacing across the rows share a row (digitizing noise stays within a row)."""
        if not self.placements:
            return np.zeros(0, dtype=np.int64)
        xs = np.sort([p.x for p in self.placements])
        half = (self.base.row_spacing if self.base is not None else 60.0) / 2
        row = np.concatenate([[0], np.cumsum(np.diff(xs) > half)])
        return np.bincount(row)

    def grid(self) -> tuple[int, int]:
        """Rows x plants per row of the placements: the rows (:meth:`_row_counts`) and the
        plants most rows hold (the larger on a tie): a stray plant does not grow the grid
        (:meth:`grid_note` says the layout is irregular)."""
        counts = self._row_counts()
        if not len(counts):
            return 0, 0
        values, times = np.unique(counts, return_counts=True)
        return len(counts), int(values[times == times.max()].max())

    def grid_note(self) -> str:
        """'' when the placements are a full grid (:meth:`grid`: every row holds as many
        plants), else what is irregular, in words."""
        counts = self._row_counts()
        rows, per_row = self.grid()
        if not len(counts) or np.all(counts == per_row):
            return ""
        odd = [f"{c}" for c in counts if c != per_row]
        return (f"irregular: {len(odd)} of the {rows} rows hold{'s' if len(odd) == 1 else ''} "
                f"{', '.join(odd)} plant{'s' if odd != ['1'] else ''}, the others {per_row}")

    def overlap_text(self, i: int, j: int) -> str:
        """What overlaps between placements ``i`` and ``j`` (named by the layout table's line
        and their plant), in cm: each stalk's ground cell, a row spacing (x) by a plant
        spacing (y) centred on it."""
        a, b = self.placements[i], self.placements[j]
        rs = self.base.row_spacing if self.base is not None else 60.0
        ps = self.base.plant_spacing if self.base is not None else 30.0
        across, along = rs - abs(a.x - b.x), ps - abs(a.y - b.y)
        return (f"table lines {i + 1} and {j + 1}: plant {a.plant}'s ground cell overlaps "
                f"plant {b.plant}'s by {across:.1f} cm across the rows and {along:.1f} cm "
                f"along them (stalks {math.hypot(a.x - b.x, a.y - b.y):.1f} cm apart)")

    def overlaps(self) -> list[tuple[int, int, float]]:
        """Placements standing on each other's ground: (i, j, distance cm), i < j."""
        if self.base is None or len(self.placements) < 2:
            return []
        xy = np.array([(p.x, p.y) for p in self.placements])
        pairs = overlap_pairs(xy, self.base.row_spacing, self.base.plant_spacing)
        d = np.hypot(*(xy[pairs[:, 0]] - xy[pairs[:, 1]]).T) if len(pairs) else []
        return [(int(i), int(j), float(dd)) for (i, j), dd in zip(pairs, d)]

    # ------------------------------------------------------------------ starting over
    def start(self, layout: CanopyLayout | None, plants: set[int],
              bases: dict[int, tuple[float, float]] | None = None) -> None:
        """A new canopy (a points file was opened): its layout, the ids of its digitized
        plants and their stalk bases (cm, for tilings; read from the layout's central tile
        when it is a tiling and they are not given). Not an edit."""
        from maizeviz_app.options import tiling_of

        tiling = tiling_of(layout)
        if bases is not None:
            self.bases = dict(bases)
        elif tiling is not None and layout is not None:
            self.bases = {p.plant: (p.x, p.y) for p in layout.placements if p.tile == (0, 0)}
        self.plants = set(plants)
        self.base, self.tiling, self.source = layout, tiling, ""
        self.placements = list(layout.placements) if layout is not None else []
        self.changed.emit(-1)

    # ------------------------------------------------------------------ edits
    def replay(self, change: Change, which: int) -> None:
        """Undo (``which`` 0) or redo (1) an edit: its state set back, said by ``replayed``
        (the editor follows an undo as it follows an edit)."""
        self.apply(change, which)
        self.replayed.emit(change, which)

    def apply(self, change: Change, which: int) -> None:
        """Set a change's ``before`` (``which`` 0) or ``after`` (1) state."""
        state = (change.before, change.after)[which]
        if change.index >= 0:
            self.placements[change.index] = state
            self.changed.emit(change.index)
        else:
            self.base, self.tiling, self.source = state.base, state.tiling, state.source
            self.placements = list(state.placements)
            self.changed.emit(-1)

    def _one(self, index: int, new: Placement, text: str, merge: Any = None) -> bool:
        old = self.placements[index]
        if new == old:
            return False
        self.placements[index] = new
        self.changed.emit(index)
        self.edited.emit(Change(index, old, new), text, merge)
        return True

    def _whole(self, after: Snapshot, text: str) -> bool:
        before = self.snapshot()
        if after == before:
            return False
        self.apply(Change(-1, before, after), 1)
        self.edited.emit(Change(-1, before, after), text, None)
        return True

    def _index(self, index: int) -> int:
        if not 0 <= index < len(self.placements):
            raise LayoutError(f"there is no plant in row {index + 1} of the layout (it has "
                              f"{len(self.placements)})")
        return index

    def _snap(self, v: float) -> float:
        step = self.snap_cm
        return round(v / step) * step if step > 0 else v

    @staticmethod
    def _coordinate(v: float, what: str) -> float:
        if not math.isfinite(v) or abs(v) > MAX_COORD_CM:
            raise LayoutError(f"{what} must be a number of cm within {MAX_COORD_CM:g} cm (1 km) "
                              f"of the origin, got {v:g}")
        return float(v)

    def move(self, index: int, x: float, y: float, snap: bool = True) -> bool:
        """Move placement ``index`` to (x, y) cm (on the snapping grid, if on and ``snap``:
        a value typed is kept as typed)."""
        p = self.placements[self._index(index)]
        if snap:
            x, y = self._snap(x), self._snap(y)
        x = self._coordinate(x, "x")
        y = self._coordinate(y, "y")
        return self._one(index, replace(p, x=x, y=y), f"move plant {p.plant}")

    def turn(self, index: int, azimuth_deg: float, merge: bool = False) -> bool:
        """Turn placement ``index`` about its stalk to ``azimuth_deg`` (kept as given within
        one turn either way, else brought into [0, 360)); ``merge``: one undo step with the
        previous turns of this plant (the mouse wheel)."""
        p = self.placements[self._index(index)]
        if not math.isfinite(azimuth_deg):
            raise LayoutError(f"row {index + 1}: the azimuth must be a number of degrees")
        az = float(azimuth_deg)
        if abs(az) > 360.0:
            az %= 360.0
        return self._one(index, replace(p, azimuth_deg=az), f"turn plant {p.plant}",
                         ("turn", index) if merge else None)

    def rotate(self, index: int, by_deg: float) -> bool:
        """Turn placement ``index`` by ``by_deg`` about its stalk (counter-clockwise seen
        from above)."""
        p = self.placements[self._index(index)]
        return self.turn(index, (p.azimuth_deg + by_deg) % 360.0)

    def set_plant(self, index: int, plant: int) -> bool:
        """Stand digitized plant ``plant`` at placement ``index``."""
        p = self.placements[self._index(index)]
        self._check_plant(plant, index)
        return self._one(index, replace(p, plant=int(plant)),
                         f"plant {p.plant} → {plant} in row {index + 1}")

    def _check_plant(self, plant: int, index: int) -> None:
        if self.plants and plant not in self.plants:
            raise LayoutError(f"row {index + 1}: plant {plant} is not in the points file (it "
                              f"has {', '.join(map(str, sorted(self.plants)))})")

    def add(self, x: float, y: float, plant: int | None = None,
            azimuth_deg: float = 0.0, text: str = "") -> bool:
        """A new placement at (x, y) cm (snapped) standing ``plant`` (default: the
        lowest digitized plant id); ``text`` names the edit (default "add plant N")."""
        if self.base is None:
            raise LayoutError("no layout to edit yet: open a points file first")
        if len(self.placements) >= MAX_PLANTS:
            raise LayoutError(f"a layout holds at most {MAX_PLANTS:,} plants")
        if plant is None:
            plant = min(self.plants) if self.plants else self.placements[0].plant
        self._check_plant(plant, len(self.placements))
        new = Placement(int(plant), self._coordinate(self._snap(x), "x"),
                        self._coordinate(self._snap(y), "y"), float(azimuth_deg) % 360.0)
        after = Snapshot(self.base, tuple(self.placements) + (new,), self.tiling, self.source)
        return self._whole(after, text or f"add plant {plant}")

    def row_end(self, index: int) -> tuple[float, float]:
        """The place one plant spacing beyond the end of placement ``index``'s row (the
        stalks closer than half a row spacing across the rows), cm."""
        p = self.placements[self._index(index)]
        rs = self.base.row_spacing if self.base is not None else 60.0
        ps = self.base.plant_spacing if self.base is not None else 30.0
        end = max(q.y for q in self.placements if abs(q.x - p.x) < rs / 2)
        return p.x, end + ps

    def free_place(self, index: int) -> tuple[float, float]:
        """Where a copy of placement ``index`` stands inside the field (cm): the nearest
        place of its lattice (whole row and plant spacings from it) inside the field whose
        ground cell overlaps no other's (:func:`overlap_pairs`), along its own row first on
        a tie; in a full field, half a plant spacing along its row (inside the field,
        overlapping: the layout editor lists it)."""
        p = self.placements[self._index(index)]
        if self.base is None:
            return self.row_end(index)
        rs, ps = self.base.row_spacing, self.base.plant_spacing
        x0, y0, x1, y1 = self.base.bounds
        eps = 1e-9 * max(abs(x0), abs(x1), abs(y0), abs(y1), rs, ps)
        i = np.arange(math.ceil((x0 - p.x - eps) / rs), math.floor((x1 - p.x + eps) / rs) + 1)
        j = np.arange(math.ceil((y0 - p.y - eps) / ps), math.floor((y1 - p.y + eps) / ps) + 1)
        ii, jj = (a.ravel() for a in np.meshgrid(i, j, indexing="ij"))
        if len(ii):
            from scipy.spatial import cKDTree

            xy = np.column_stack([p.x + ii * rs, p.y + jj * ps])
            taken = cKDTree(np.array([(q.x / rs, q.y / ps) for q in self.placements]))
            near, _ = taken.query(xy / [rs, ps], p=np.inf)
            free = near >= OVERLAP_REACH * (1 - 1e-12)
            if free.any():
                d = np.hypot(ii * rs, jj * ps)[free]
                best = np.lexsort((-jj[free], np.abs(ii[free]), d))[0]
                return float(xy[free][best, 0]), float(xy[free][best, 1])
        y = p.y + ps / 2 if p.y + ps / 2 <= y1 + eps else p.y - ps / 2
        return p.x, float(min(max(y, y0), y1))

    def duplicate(self, index: int) -> bool:
        """A copy of placement ``index`` (the same plant, turned the same) inside the field,
        at the nearest free place (:meth:`free_place`; not snapped: it is on the lattice)."""
        p = self.placements[self._index(index)]
        x, y = self.free_place(index)
        if len(self.placements) >= MAX_PLANTS:
            raise LayoutError(f"a layout holds at most {MAX_PLANTS:,} plants")
        new = Placement(p.plant, self._coordinate(x, "x"), self._coordinate(y, "y"),
                        p.azimuth_deg)
        after = Snapshot(self.base, tuple(self.placements) + (new,), self.tiling, self.source)
        return self._whole(after, f"duplicate plant {p.plant} (row {index + 1})")

    def remove(self, index: int) -> bool:
        """Take placement ``index`` out of the layout (the last one stays: a canopy has a
        plant)."""
        p = self.placements[self._index(index)]
        if len(self.placements) == 1:
            raise LayoutError("the layout's last plant cannot be removed: a canopy needs one")
        kept = tuple(self.placements[:index]) + tuple(self.placements[index + 1:])
        after = Snapshot(self.base, kept, self.tiling, self.source)
        return self._whole(after, f"remove plant {p.plant} (row {index + 1})")

    def replace_layout(self, layout: CanopyLayout, tiling: tuple[int, int] | None, text: str,
                       source: str = "") -> bool:
        """A whole new layout (a tiling, a layout file, a regular field)."""
        return self._whole(Snapshot(layout, tuple(layout.placements), tiling, source), text)

    def tile(self, n: int) -> bool:
        """Tile the digitized block ``n`` x ``n`` times at the base's spacings."""
        base, block = self.base, self.block()
        if base is None or block is None:
            raise LayoutError("no digitized block to tile: open a points file first")
        layout = tiled_layout(self.bases, (n, n), base.row_spacing, base.plant_spacing, block,
                              base.north_deg)
        return self.replace_layout(layout, (n, n), f"tile {n} x {n}")

    def regular(self, rows: int, per_row: int, row_spacing: float,
                plant_spacing: float) -> bool:
        """A regular field: ``rows`` rows ``row_spacing`` cm apart (along x), each of
        ``per_row`` plants ``plant_spacing`` cm apart (along y), centred where the layout
        is; the digitized plants repeat in the order of their block (as a tiling repeats
        them), each turned as it was digitized."""
        if self.base is None:
            raise LayoutError("no layout to edit yet: open a points file first")
        rs = check_spacing(row_spacing, "row spacing")
        ps = check_spacing(plant_spacing, "plant spacing")
        for v, what in ((rows, "rows"), (per_row, "plants per row")):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise LayoutError(f"{what} must be a whole number of 1 or more, got {v!r}")
        if rows * per_row > MAX_PLANTS:
            raise LayoutError(f"{rows} rows x {per_row} plants make {rows * per_row:,} plants; "
                              f"a canopy holds at most {MAX_PLANTS:,}")
        order = self._block_order()
        x0, y0, x1, y1 = self.base.bounds
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        xs = cx + (np.arange(rows) - (rows - 1) / 2) * rs
        ys = cy + (np.arange(per_row) - (per_row - 1) / 2) * ps
        br, bp = len(order), len(order[0])
        doc = {"maizeviz_layout": 1, "row_spacing": rs, "plant_spacing": ps,
               "north_deg": self.base.north_deg,
               "field": {"x0": float(xs[0] - rs / 2), "y0": float(ys[0] - ps / 2),
                         "x1": float(xs[-1] + rs / 2), "y1": float(ys[-1] + ps / 2)},
               "rows": [{"x": float(x), "plants": [
                   {"y": float(y), "plant": order[r % br][k % bp]}
                   for k, y in enumerate(ys)]} for r, x in enumerate(xs)]}
        layout = layout_from_dict(doc, self.plants or None, "rows x plants")
        return self.replace_layout(layout, None,
                                   f"{rows} rows x {per_row} plants, {rs:g} x {ps:g} cm",
                                   f"{rows} rows x {per_row} plants")

    def _block_order(self) -> list[list[int]]:
        """The digitized plants as rows of the block (by their stalks' lattice), so that a
        regular field repeats the block; one row of all plants when the block is not full."""
        plants = sorted(self.plants or {p.plant for p in self.placements})
        if self.bases and self.base is not None:
            (bx, by), lattice = block_lattice(self.bases, self.base.row_spacing,
                                              self.base.plant_spacing)
            if bx * by == len(lattice):
                xs = sorted({v[0] for v in lattice.values()})
                ys = sorted({v[1] for v in lattice.values()})
                grid: list[list[int | None]] = [[None] * len(ys) for _ in xs]
                for pid, (x, y) in lattice.items():
                    grid[xs.index(x)][ys.index(y)] = pid
                if all(v is not None for row in grid for v in row) and \
                        set(lattice) <= set(plants):
                    return [[int(v) for v in row if v is not None] for row in grid]
        return [plants]
