"""Per-leaf light for colouring and tables (maizeviz.light.report.tables), and a period that crosses
process boundaries (pickled) and a weather-file error that names its quantity."""

import pickle

import numpy as np
import pytest

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.io.atomic import write_rows
from maizeviz.io.points import write_points
from maizeviz.leaf.fit import read_leaves
from maizeviz.leaf.synth import block_grids
from maizeviz.light.report.tables import leaf_values, write_steps
from maizeviz.light.results.per_leaf import plant_light
from maizeviz.light.scene.request import Sampling
from maizeviz.light.sources.irradiance import WeatherFileError, clear_sky_period, read_weather
from maizeviz.light.sources.sky import make_sky
from maizeviz.light.trace.directions import trace_period
from maizeviz.mesh.levels import parse_level


@pytest.fixture(scope="module")
def tiled(tmp_path_factory):
    """Two plants tiled 3 x 3 (18 stands): copies of a plant are one in a periodic field."""
    path = tmp_path_factory.mktemp("rep") / "two.csv"
    write_points(path, block_grids(1, 2, seed=3))
    found = read_leaves(path)
    return build_canopy(found.leaves, layout_for(found.leaves, (3, 3)), parse_level("16"))


@pytest.fixture(scope="module")
def day(tiled):
    period = clear_sky_period("2005-08-01", 39.9, 116.4, "Asia/Shanghai", step_min=120)
    return trace_period(tiled, period, Sampling((0.0, 100.0), 0.3, None, True, 2),
                        make_sky("soc", 6))


def test_leaf_values_put_each_leafs_light_on_all_its_triangles_and_copies(tiled, day):
    rows = day.leaf_rows(tiled)
    assert {r["instance"] for r in rows} <= {p + 1 for p in range(18)}
    assert len({r["plant"] for r in rows}) == 2 and len({r["instance"] for r in rows}) == 2
    values = leaf_values(tiled, rows, "par_intercepted_mol", day.rect, True)
    assert values.shape == (tiled.n_triangles,) and np.all(np.isfinite(values))
    # every copy of a leaf shows the value of the leaf in the rows, per m2 of leaf
    for r in rows:
        plant, leaf = r["plant"], r["leaf"]
        on = (tiled.face_plant == plant) & (tiled.face_leaf == leaf)
        assert np.allclose(values[on], r["par_mol_per_m2_leaf"])
    # per plant: the leaves summed; the plants take what the canopy intercepts
    plants = plant_light(rows)
    total = sum(p["par_intercepted_mol"] for p in plants)
    assert total == pytest.approx(day.par_intercepted_mol_m2 * day.rect_area_m2, rel=1e-9)


def test_an_open_field_marks_plants_outside_the_rectangle_not_traced(tiled, day):
    rows = day.leaf_rows(tiled)
    open_field = leaf_values(tiled, rows, "par_intercepted_mol", day.rect, False)
    assert np.isnan(open_field).any() and np.isfinite(open_field).any()


def test_steps_and_rows_files(tiled, day, tmp_path):
    write_steps(tmp_path / "steps.csv", day)
    lines = (tmp_path / "steps.csv").read_text().splitlines()
    assert len(lines) == day.n_steps + 1 and lines[0].startswith("time,step_s,zenith_deg")
    write_rows(tmp_path / "leaves.csv", day.leaf_rows(tiled))
    assert (tmp_path / "leaves.csv").read_text().startswith("instance,plant,leaf")


def test_a_period_pickles_and_a_weather_error_names_its_quantity(tmp_path):
    period = clear_sky_period("2005-08-01", 39.9, 116.4, "Asia/Shanghai", step_min=60)
    back = pickle.loads(pickle.dumps(period))
    assert back.par_mol_m2 == period.par_mol_m2 and dict(back.parameters) == \
        dict(period.parameters)
    bad = tmp_path / "w.csv"
    bad.write_text("time,ghi\n2005-08-01T12:00+08:00,1\n2005-08-01T13:00+08:00,-1\n")
    with pytest.raises(WeatherFileError) as err:
        read_weather(bad)
    assert err.value.quantity == "weather"
