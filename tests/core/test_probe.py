"""The distance and area probes (maizeviz_app.probe), Qt-free, against plain geometry."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from maizeviz_app.probe import Probe, polygon_area


def test_a_distance_is_the_straight_line_between_two_points_and_a_third_starts_anew():
    p = Probe()
    seen = []
    p.changed.connect(lambda: seen.append(p.text()))
    p.add((0, 0, 0))                                   # off: nothing happens
    assert p.points == [] and seen == []
    p.start("distance")
    p.add((0.0, 0.0, 10.0))
    p.add((3.0, 4.0, 10.0))
    assert p.text().startswith("distance 5.0 cm (across 3.0, along 4.0, up 0.0 cm)")
    p.add((1.0, 1.0, 1.0))
    assert p.points == [(1.0, 1.0, 1.0)] and "second point" in p.text()
    p.start("")
    assert not p.on and p.text() == ""
    with pytest.raises(ValueError):
        p.start("volume")


def test_an_area_is_the_polygons_and_its_shadows():
    p = Probe()
    p.start("area")
    for pt in ((0, 0, 0), (10, 0, 0), (10, 0, 20)):
        p.add(pt)
    # a vertical right triangle: 100 cm2, no shadow
    assert p.text().startswith("area 100.0 cm² (3 points; seen from above 0.0 cm²)")
    p.add((0, 0, 20))
    assert p.text().startswith("area 200.0 cm²")


@settings(max_examples=50, deadline=None)
@given(st.floats(1, 50), st.floats(1, 50), st.floats(0, 80), st.floats(-1e3, 1e3))
def test_a_tilted_rectangles_area_and_shadow(w, h, tilt_deg, z0):
    t = np.radians(tilt_deg)
    corners = np.array([[0, 0, 0], [w, 0, 0], [w, h * np.cos(t), h * np.sin(t)],
                        [0, h * np.cos(t), h * np.sin(t)]]) + [0, 0, z0]
    area, ground = polygon_area(corners)
    assert area == pytest.approx(w * h, rel=1e-9)
    assert ground == pytest.approx(w * h * np.cos(t), rel=1e-9, abs=1e-9)
