"""``import maizeviz as mv``: cheap to import, every public name there, results as tables."""

import subprocess
import sys

import numpy as np
import pytest

import maizeviz as mv
from maizeviz.light.engine import LightEngine
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.beam import trace_light


def test_import_maizeviz_loads_no_numpy_qt_or_embree():
    code = ("import sys, maizeviz; print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "('numpy', 'PySide6', 'embreex', 'pandas', 'pvlib')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_every_public_name_resolves_and_dir_lists_them():
    for name in mv.__all__:
        assert getattr(mv, name) is not None
    assert sorted(mv.__all__) == dir(mv)
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        mv.nope  # noqa: B018


@pytest.fixture(scope="module")
def small():
    plants = mv.read_points(mv.example_points())
    return mv.build_canopy(plants, tile=(1, 1), level="16")


def test_the_engine_traces_what_trace_light_traces(small):
    """The façade's sun equals the core's trace on a fresh scene, number for number."""
    engine = mv.LightEngine(small, density=0.5, heights_cm=(0, 100))
    got = engine.sun(zenith=30.0, azimuth=150.0)
    want = trace_light(small, LightRequest(Sun(30.0, 150.0), Sampling((0.0, 100.0), 0.5)),
                       with_stalks=True)            # the engine's default: stalks take light
    assert np.array_equal(got.transmission, want.transmission)
    assert np.array_equal(got.first_hits, want.first_hits)
    table = got.table()
    assert list(table.columns) == ["height_cm", "transmission"]
    assert table["transmission"].tolist() == want.transmission.tolist()


def test_the_engine_builds_each_scene_once(small):
    engine = LightEngine(small, density=0.25, heights_cm=(0,))
    engine.sun(zenith=20.0, azimuth=100.0)
    first = engine.scene(False)
    again = engine.sun(zenith=40.0, azimuth=200.0)
    assert engine.scene(False) is first and again.seconds["build"] == 0.0
    assert engine.scene(True) is not first              # a periodic field has its own


def test_a_day_reuses_the_sky_the_engine_traced(small):
    engine = LightEngine(small, density=0.25, heights_cm=(0, 100))
    sky = engine.sky("soc", 6)
    calls = []
    day = engine.day(date="2005-08-01", lat=39.9, lon=116.4, tz="Asia/Shanghai", step_min=120,
                     sky=sky.sky, progress=lambda done, total: calls.append(total))
    assert day.sky is sky and calls[-1] == day.n_steps     # only the sun steps traced


def test_per_plant_tables_sum_the_per_leaf_tables(small):
    light = mv.LightEngine(small, density=0.5).sun(zenith=25.0, azimuth=180.0)
    leaves, plants = light.table("leaf", small), light.table("plant", small)
    by_plant = leaves.groupby("plant")["sunlit_area_cm2"].sum()
    assert np.allclose(plants.set_index("plant")["sunlit_area_cm2"], by_plant)
    # the engine's results know their canopy; one without it asks for it
    assert light.table("leaf").equals(leaves) and light.canopy is small
    with pytest.raises(mv.MaizevizError, match="needs the canopy"):
        light.with_canopy(None).table("leaf")
    with pytest.raises(mv.MaizevizError, match="height, leaf, plant"):
        light.table("tile", small)


def test_threads_sharing_an_engine_build_its_scene_once(small):
    from concurrent.futures import ThreadPoolExecutor

    engine = LightEngine(small, density=0.25, heights_cm=(0,))
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda z: engine.sun(zenith=z, azimuth=90.0, classes=False),
                                [10.0, 20.0, 30.0, 40.0]))
    builds = [r.seconds["build"] for r in results]
    assert sum(b > 0 for b in builds) == 1 and max(builds) == engine.build_seconds[False]


def test_the_package_example_runs_as_a_doctest():
    """The example of ``maizeviz/__init__.py``'s docstring, run as written."""
    import doctest

    import maizeviz

    result = doctest.testmod(maizeviz, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted >= 7 and result.failed == 0
