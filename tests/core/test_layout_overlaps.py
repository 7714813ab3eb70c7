"""Overlapping cells of a layout: the all-pairs path for small fields (no k-d tree to import
for the paper's 81 plants) says exactly what the k-d tree says."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.canopy import layout as layout_mod


@settings(max_examples=60, deadline=None)
@given(st.integers(2, 60), st.integers(0, 2**31 - 1), st.floats(0.2, 3.0))
def test_small_fields_say_what_the_kd_tree_says(n, seed, spread):
    rng = np.random.default_rng(seed)
    w, h = 60.0, 30.0
    xy = rng.uniform(0, spread * np.sqrt(n), (n, 2)) * [w, h]
    cells = np.column_stack([xy[:, 0] - w / 2, xy[:, 1] - h / 2, xy[:, 0] + w / 2,
                             xy[:, 1] + h / 2])
    small = layout_mod._overlaps(cells)
    saved = layout_mod.SMALL_FIELD
    layout_mod.SMALL_FIELD = 0
    try:
        tree = layout_mod._overlaps(cells)
    finally:
        layout_mod.SMALL_FIELD = saved
    if not tree:
        assert small == ""
    else:
        count = lambda text: int(text.split()[0].strip("("))      # noqa: E731
        area = lambda text: float(text.split("about ")[1].split()[0])  # noqa: E731
        assert count(small) == count(tree) and abs(area(small) - area(tree)) <= 1
