"""A field traced in sub-plots (maizeviz.light.trace.subplots) gives the whole field's answer:
per height the sensors that see the sun, per plant (and per leaf) the rays whose first and
second hits are its leaves, with 2 and 4 sub-plots, for suns whose sensor planes are answered
by ray families and by occlusion queries."""

import numpy as np
import pytest

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.leaf.fit import fit_leaves
from maizeviz.leaf.synth import block_grids
from maizeviz.light.engine import LightEngine
from maizeviz.light.scene.rays import grid_shape
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.subplots import (
    default_top,
    family_used,
    halo_cm,
    plants_within,
    reach,
    sub_canopy,
    trace_window,
    whole_counts,
    windows,
)
from maizeviz.mesh.levels import parse_level

HEIGHTS = (0.0, 50.0, 100.0, 150.0, 200.0, 225.0)


@pytest.fixture(scope="module")
def canopy():
    leaves, _ = fit_leaves(block_grids(4, 6, seed=4))
    return build_canopy(leaves, layout_for(leaves, (1, 1)), parse_level("36"))


def split(canopy, sun, parts, density):
    rect = canopy.layout.centre_bounds
    shape = grid_shape(rect, density)
    top = default_top(canopy)
    s = sun.direction(canopy.layout.north_deg)
    halo = halo_cm(top, s, rect, shape)
    n_place = len(canopy.layout.placements)
    total, sizes = None, []
    for w in windows(shape, parts):
        near = plants_within(canopy, reach(w.rect(rect, shape), halo))
        sub, index = sub_canopy(canopy, near)
        sizes.append(sub.n_triangles)
        got = trace_window(sub, index, n_place, w, rect, density, HEIGHTS, top, s,
                           canopy.layout.bounds)
        total = got if total is None else total.add(got)
    return total, sizes


@pytest.mark.parametrize("zenith, azimuth", [(10.0, 200.0), (35.0, 120.0), (75.0, 150.0)])
@pytest.mark.parametrize("parts", [(2, 1), (2, 2)])
def test_sub_plots_add_up_to_the_whole_field(canopy, zenith, azimuth, parts):
    density = 0.5
    sun = Sun(zenith, azimuth)
    # sub-plots trace the leaves (the paper's canopy): the whole field traced leaves-only
    whole = LightEngine(canopy, heights_cm=HEIGHTS, density=density,
                        with_stalks=False).sun(sun, classes=True)
    expect = whole_counts(canopy, whole.first_hits, whole.second_hits, whole.transmission,
                          whole.rays)
    got, sizes = split(canopy, sun, parts, density)
    assert got.rays == whole.rays
    np.testing.assert_array_equal(got.lit, expect.lit)                   # per height
    np.testing.assert_array_equal(got.transmission, whole.transmission)
    np.testing.assert_array_equal(got.first.sum(axis=1), expect.first.sum(axis=1))  # per plant
    np.testing.assert_array_equal(got.second.sum(axis=1), expect.second.sum(axis=1))
    np.testing.assert_array_equal(got.first, expect.first)               # and per leaf
    assert expect.first.sum() > 0.2 * whole.rays and expect.second.sum() > 0      # real hits
    if zenith <= 10.0:              # a high sun's halo holds only part of the field
        assert min(sizes) < canopy.n_triangles


def test_both_ways_of_answering_the_planes_are_covered(canopy):
    rect = canopy.layout.centre_bounds
    shape = grid_shape(rect, 0.5)
    top = default_top(canopy)
    used = [family_used(shape, rect, np.array(HEIGHTS), top,
                        Sun(z, 150.0).direction(0.0)) for z in (10.0, 35.0, 75.0)]
    assert True in used and False in used


def test_windows_cover_the_lattice_once():
    shape = (37, 23)
    for parts in ((1, 1), (2, 3), (5, 4), (40, 1)):
        cells = np.zeros(shape, int)
        for w in windows(shape, parts):
            cells[w.i0:w.i1, w.j0:w.j1] += 1
        assert (cells == 1).all()


def test_on_dask_workers_each_building_its_plants_from_the_file(tmp_path, capsys):
    """The sub-plots traced on a local Dask cluster of 2 workers, each reading and building its
    own plants from the Parquet points file: the whole field's answer; and the command."""
    pytest.importorskip("distributed")
    import json

    from maizeviz.canopy.field import FieldLeaves, canopy_of
    from maizeviz.cli import main
    from maizeviz.io.points import write_points
    from maizeviz.sweep.run import dask_client
    from maizeviz.sweep.subplots import trace_field

    path = tmp_path / "field.parquet"
    write_points(path, block_grids(4, 6, seed=4))
    field = FieldLeaves(path)
    layout = layout_for(field, (1, 1))
    level = parse_level("36")
    canopy = canopy_of(field, layout, level)
    sun = Sun(30.0, 160.0)
    whole = LightEngine(canopy, heights_cm=HEIGHTS, density=0.5,
                        with_stalks=False).sun(sun, classes=True)
    expect = whole_counts(canopy, whole.first_hits, whole.second_hits, whole.transmission,
                          whole.rays)
    with dask_client(workers=2) as (client, _):
        got, plan = trace_field(client, field, layout, level, sun.direction(0.0),
                                layout.centre_bounds, 0.5, HEIGHTS, (2, 2))
    assert len(plan) == 4 and all(len(p.placements) for p in plan)
    np.testing.assert_array_equal(got.lit, expect.lit)
    np.testing.assert_array_equal(got.first.sum(axis=1), expect.first.sum(axis=1))
    np.testing.assert_array_equal(got.second.sum(axis=1), expect.second.sum(axis=1))
    capsys.readouterr()
    table = tmp_path / "plants.csv"
    assert main(["subplots", str(path), "--parts", "2x1", "--sun-zenith", "30",
                 "--sun-azimuth", "160", "--density", "0.5", "--workers", "2",
                 "--plant-light", str(table), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["transmission"] == whole.transmission.tolist()
    rows = table.read_text().splitlines()
    assert len(rows) == 1 + len(layout.placements)
