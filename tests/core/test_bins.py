"""Binning sensor planes into heatmap bins: a grid binned by its rows and columns is the
binning of its points."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.light.results.maps import bin_edges, binned, binned_grid
from maizeviz.light.scene.rays import grid_shape, ray_grid


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 40), st.integers(1, 40), st.floats(-3, 3), st.floats(-3, 3),
       st.floats(0.3, 12), st.integers(0, 2**31))
def test_grid_binning_is_the_binning_of_its_points(nx, ny, dx, dy, bin_cm, seed):
    """binned_grid (by rows and columns) gives exactly binned's counts for every grid point."""
    rect = (-7.3, 2.1, -7.3 + nx * 0.9, 2.1 + ny * 0.6)
    pts, _ = ray_grid(rect, 1 / 0.54)
    gx, gy = grid_shape(rect, 1 / 0.54)
    lit = np.random.default_rng(seed).random(gx * gy) < 0.4
    xe, ye = bin_edges(rect, bin_cm)
    xs, ys = pts[::gy, 0] + dx, pts[:gy, 1] + dy
    want = binned(pts + [dx, dy], lit, xe, ye)
    got = binned_grid(xs, ys, lit, xe, ye)
    assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
