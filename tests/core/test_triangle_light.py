"""Light classes per triangle (the colouring of the canopy and its export)."""

import numpy as np
import pytest

from maizeviz.canopy.build import Canopy, build_canopy
from maizeviz.canopy.layout import layout_for, layout_from_dict
from maizeviz.leaf.fit import read_leaves
from maizeviz.light.results.per_leaf import NOT_TRACED
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.beam import trace_light
from maizeviz.mesh.levels import Level
from maizeviz.resources import example_points


def squares(specs, field=(0, 0, 100, 100)):
    v, f = [], []
    for k, (x, y, a, z) in enumerate(specs):
        v += [[x, y, z], [x + a, y, z], [x + a, y + a, z], [x, y + a, z]]
        f += [[4 * k, 4 * k + 1, 4 * k + 2], [4 * k, 4 * k + 2, 4 * k + 3]]
    x0, y0, x1, y1 = field
    layout = layout_from_dict({"maizeviz_layout": 1, "row_spacing": 60, "plant_spacing": 30,
                               "field": {"x0": x0, "y0": y0, "x1": x1, "y1": y1},
                               "rows": [{"x": 50, "plants": [{"y": 50, "plant": 1}]}]})
    return Canopy.from_triangles(np.array(v, float), np.array(f), layout,
                                 np.repeat(np.arange(1, len(specs) + 1), 2))


def test_stacked_leaves_direct_second_and_untraced():
    # two stacked squares above the sample rectangle, one square far outside it
    c = squares([(20, 20, 20, 80), (20, 20, 20, 40), (70, 70, 10, 50)])
    r = trace_light(c, LightRequest(Sun(0, 0), Sampling((0,), 4, (10, 10, 50, 50))))
    classes = r.triangle_light(c)
    assert list(classes) == [2, 2, 1, 1, NOT_TRACED, NOT_TRACED]


@pytest.fixture(scope="module")
def tiled():
    leaves = read_leaves(example_points()).leaves
    return build_canopy(leaves, layout_for(leaves, (3, 3)), Level(triangles=8))


def test_every_copy_of_a_plant_is_classified_like_the_others_in_a_periodic_tiling(tiled):
    r = trace_light(tiled, LightRequest(Sun(22.3, 167), Sampling((0,), 1, None, periodic=True)))
    classes = r.triangle_light(tiled)
    assert (classes >= 0).all(), "a tile-periodic field is classified everywhere"
    inst = tiled.face_instance
    by_plant = {}
    for i, pl in enumerate(tiled.layout.placements):
        by_plant.setdefault(pl.plant, []).append(classes[inst == i])
    for copies in by_plant.values():
        assert len(copies) == 9 and all((c == copies[0]).all() for c in copies)
    assert 0.2 < (classes == 2).mean() < 0.8


def test_an_open_field_marks_what_no_ray_reached(tiled):
    r = trace_light(tiled, LightRequest(Sun(22.3, 167), Sampling((0,), 1, None, periodic=False)))
    classes = r.triangle_light(tiled)
    centre = np.array([pl.tile == (0, 0) for pl in tiled.layout.placements])[tiled.face_instance]
    unreached = classes == NOT_TRACED
    assert unreached[~centre].mean() > 0.5                    # outer tiles: mostly unreached
    assert unreached[centre].mean() < unreached[~centre].mean() / 2
    hit = (r.first_hits[:len(classes)] > 0) | (r.second_hits[:len(classes)] > 0)
    assert not (hit & unreached).any(), "a triangle a ray hit is never 'not traced'"
