"""The layout editor says what overlaps and keeps a duplicate in the field (a new user's
report): after a small drag it listed "plants 4 and 5 (rows 40 and 41) stand 46.0 cm apart"
as an overlap though the plants stand 30 cm apart in their rows (what overlaps is their
ground cells, and "rows 40 and 41" were the table's lines, not field rows); Duplicate put the
copy outside the field, and the rows x plants boxes then grew from 9 x 9 to 9 x 11. Without
Qt (the panel shows these texts)."""

from __future__ import annotations

import pytest
from maizeviz_app.layout_draft import LayoutDraft

from maizeviz.canopy.layout import tiled_layout

#: A digitized 3 x 3 block: rows 60 cm apart along x, plants 30 cm along y.
BLOCK = {1 + 3 * i + j: (60.0 * i, 30.0 * j) for i in range(3) for j in range(3)}


def _nine_by_nine() -> LayoutDraft:
    d = LayoutDraft()
    d.start(tiled_layout(BLOCK, (3, 3)), set(BLOCK))
    assert d.grid() == (9, 9) and not d.grid_note() and not d.overlaps()
    return d


def test_an_overlap_says_which_cells_overlap_by_how_much():
    d = _nine_by_nine()
    p = d.placements[39]
    # a drag of 20 cm across the rows and 8 along: its cell now overlaps its neighbours'
    assert d.move(39, p.x + 20.0, p.y + 8.0, snap=False)
    pairs = d.overlaps()
    assert pairs and all(39 in (i, j) for i, j, _ in pairs)
    for i, j, dist in pairs:
        a, b = d.placements[i], d.placements[j]
        text = d.overlap_text(i, j)
        across, along = 60.0 - abs(a.x - b.x), 30.0 - abs(a.y - b.y)
        assert across > 6.0 and along > 3.0                 # beyond a tenth of a spacing
        assert text.startswith(f"table lines {i + 1} and {j + 1}: ")
        want = (f"plant {a.plant}'s ground cell overlaps plant {b.plant}'s by {across:.1f} "
                f"cm across the rows and {along:.1f} cm along them")
        assert want in text
        assert f"(stalks {dist:.1f} cm apart)" in text
        assert "rows " not in text.split(":")[0]              # the table's lines, not rows


def test_a_duplicate_in_a_full_field_stays_in_it_and_the_grid_stays_9_by_9():
    d = _nine_by_nine()
    x0, y0, x1, y1 = d.base.bounds
    last = max(range(len(d.placements)), key=lambda k: (d.placements[k].x,
                                                        d.placements[k].y))
    assert d.duplicate(last)                                # the end of the last row
    new = d.placements[-1]
    assert x0 <= new.x <= x1 and y0 <= new.y <= y1
    assert not any("outside the field" in w for w in d.layout().warnings)
    assert (new.plant, new.azimuth_deg) == (d.placements[last].plant,
                                            d.placements[last].azimuth_deg)
    # next to its original along the row, and said to overlap it (the field is full)
    assert new.x == d.placements[last].x and abs(new.y - d.placements[last].y) == 15.0
    assert any(len(d.placements) - 1 in (i, j) for i, j, _ in d.overlaps())
    assert d.grid() == (9, 9)                               # not grown by one stray plant
    assert d.grid_note() == "irregular: 1 of the 9 rows holds 10 plants, the others 9"


def test_a_duplicate_goes_to_the_nearest_free_place_in_the_field():
    d = _nine_by_nine()
    gap = d.placements[40]
    assert d.remove(40)                                     # a free place mid-field
    near = min(range(len(d.placements)),
               key=lambda k: (d.placements[k].x - gap.x) ** 2 + (d.placements[k].y - gap.y) ** 2)
    assert d.duplicate(near)
    new = d.placements[-1]
    assert (new.x, new.y) == pytest.approx((gap.x, gap.y))
    assert not d.overlaps() and d.grid() == (9, 9) and not d.grid_note()
