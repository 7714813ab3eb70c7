"""The layout being edited, without Qt: edits by hand and by parameters, each undone exactly by
its change; overlaps found as a brute-force check finds them; refused edits named."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from maizeviz_app.layout_draft import LayoutDraft, overlap_pairs

from maizeviz.canopy.layout import LayoutError, layout_to_dict, tiled_layout

#: A digitized 3 x 3 block (rows 60 cm apart along x, plants 30 cm along y), a little noisy.
BLOCK = {1 + 3 * i + j: (60.0 * i + 0.4 * j, 30.0 * j - 0.3 * i) for i in range(3)
         for j in range(3)}


def _draft(tile=(1, 1), bases=BLOCK) -> tuple[LayoutDraft, list]:
    d = LayoutDraft()
    d.start(tiled_layout(bases, tile), set(bases))
    edits: list = []
    d.edited.connect(lambda change, text, merge: edits.append((change, text)))
    return d, edits


def _same(a, b) -> bool:
    """Snapshots equal up to their ground being another object of the same values."""
    ground = (a.base is b.base) or layout_to_dict(a.base) == layout_to_dict(b.base)
    return ground and (a.placements, a.tiling, a.source) == (b.placements, b.tiling, b.source)


def test_every_edit_is_undone_and_redone_exactly_by_its_change():
    d, edits = _draft()
    start = d.snapshot()
    assert d.move(0, 12.5, -3.25) and d.turn(1, 45.0) and d.set_plant(2, 5)
    assert d.duplicate(3) and d.add(500.0, 500.0) and d.remove(4)
    assert d.regular(4, 2, 70.0, 25.0) and d.tile(3)
    states = [start]
    d2, _ = _draft()
    for change, _text in edits:                 # replaying the changes on a fresh draft
        d2.apply(change, 1)
        states.append(d2.snapshot())
    assert _same(states[-1], d.snapshot())
    for (change, _text), before in zip(reversed(edits), reversed(states[:-1])):
        d.apply(change, 0)                      # and undoing them in turn
        assert _same(d.snapshot(), before)
    assert [t for _c, t in edits][:3] == ["move plant 1", "turn plant 2",
                                         "plant 3 → 5 in row 3"]


def test_the_same_value_again_is_no_edit():
    d, edits = _draft()
    p = d.placements[0]
    assert not d.move(0, p.x, p.y) and not d.turn(0, p.azimuth_deg)
    assert not d.set_plant(0, p.plant) and not edits


def test_rows_by_plants_repeat_the_block_at_exact_spacings():
    d, _ = _draft()
    assert d.regular(6, 9, 75.0, 20.0)
    layout = d.layout()                          # checked as a layout file is
    assert len(layout.placements) == 54 and d.grid() == (6, 9)
    xs = sorted({p.x for p in layout.placements})
    ys = sorted({p.y for p in layout.placements})
    assert np.allclose(np.diff(xs), 75.0) and np.allclose(np.diff(ys), 20.0)
    assert layout.ground_area_cm2 == pytest.approx(6 * 75.0 * 9 * 20.0)
    assert not d.overlaps() and not layout.warnings
    # the plant at row r, place k is the block's plant at (r mod 3, k mod 3), as a tiling
    # repeats it
    for p in layout.placements:
        r, k = xs.index(p.x), ys.index(p.y)
        assert p.plant == 1 + 3 * (r % 3) + k % 3
    # a tiling of the block and the same rows x plants stand the same plants in the same
    # lattice places
    t, _ = _draft((3, 3))
    tiled = sorted(t.placements, key=lambda p: (round(p.x / 60), round(p.y / 30)))
    d.regular(9, 9, 60.0, 30.0)
    regular = sorted(d.placements, key=lambda p: (p.x, p.y))
    assert [p.plant for p in tiled] == [p.plant for p in regular]


def test_snapping_puts_dragged_and_added_plants_on_the_grid_and_typed_values_stay():
    d, _ = _draft()
    d.snap_cm = 5.0
    d.move(0, 12.4, -7.6)
    assert (d.placements[0].x, d.placements[0].y) == (10.0, -10.0)
    d.add(33.0, 91.0)
    assert (d.placements[-1].x, d.placements[-1].y) == (35.0, 90.0)
    d.move(1, 12.4, 7.61, snap=False)
    assert (d.placements[1].x, d.placements[1].y) == (12.4, 7.61)


def test_a_duplicate_overlaps_until_moved_and_the_overlap_is_named():
    d, _ = _draft()
    assert not d.overlaps()
    d.move(1, d.placements[0].x + 3.0, d.placements[0].y + 4.0)     # typed onto plant 1
    (i, j, dist), = d.overlaps()
    assert (i, j) == (0, 1) and dist == pytest.approx(5.0)
    d.move(1, 200.0, 200.0)
    assert not d.overlaps()


@pytest.mark.parametrize("edit, message", [
    (lambda d: d.set_plant(0, 99), "plant 99 is not in the points file"),
    (lambda d: d.move(0, 2e5, 0.0), "within 100000 cm"),
    (lambda d: d.move(12, 0.0, 0.0), "no plant in row 13"),
    (lambda d: d.regular(0, 3, 60.0, 30.0), "rows must be a whole number of 1 or more"),
    (lambda d: d.regular(3, 3, 0.5, 30.0), "row spacing is 0.5 cm"),
    (lambda d: d.regular(400, 400, 60.0, 30.0), "160,000 plants"),
])
def test_refused_edits_are_named_and_change_nothing(edit, message):
    d, edits = _draft()
    before = d.snapshot()
    with pytest.raises(LayoutError, match=message):
        edit(d)
    assert d.snapshot() == before and not edits


def test_the_last_plant_stays():
    d, _ = _draft(bases={1: (0.0, 0.0)})
    with pytest.raises(LayoutError, match="last plant cannot be removed"):
        d.remove(0)


def test_an_unedited_draft_is_its_layout_exactly():
    d, _ = _draft((3, 3))
    layout = d.layout()
    assert layout.placements == d.base.placements
    assert layout_to_dict(layout) == layout_to_dict(d.base)


@settings(max_examples=60)
@given(st.lists(st.tuples(st.floats(-200, 200), st.floats(-200, 200)), max_size=40),
       st.sampled_from([(60.0, 30.0), (75.0, 20.0), (10.0, 10.0)]))
def test_overlaps_are_what_a_brute_force_check_finds(points, spacing):
    xy = np.array(points, dtype=np.float64).reshape(-1, 2)
    rs, ps = spacing
    found = {tuple(p) for p in overlap_pairs(xy, rs, ps).tolist()}
    brute = {(i, j) for i, j in itertools.combinations(range(len(xy)), 2)
             if abs(xy[i, 0] - xy[j, 0]) < 0.9 * rs * (1 - 1e-12)
             and abs(xy[i, 1] - xy[j, 1]) < 0.9 * ps * (1 - 1e-12)}
    assert found == brute
