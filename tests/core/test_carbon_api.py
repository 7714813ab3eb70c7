"""The Python path to carbon: a model's name wherever a model is taken, results typed end to
end (a user's script under mypy sees them), results that know their canopy, and one base for
the absorbed-light and assimilation results."""

import re
from pathlib import Path

import numpy as np
import pytest

import maizeviz as mv
from maizeviz.light.results.assimilation import assimilate
from maizeviz.light.results.on_triangles import OnCanopy, TriangleResult
from maizeviz.photosynthesis.split import as_leaf_model

ROOT = Path(__file__).resolve().parents[2]
DAY = dict(date="2005-08-01", lat=39.9, lon=116.4, tz="Asia/Shanghai", step_min=120)


@pytest.fixture(scope="module")
def engine():
    canopy = mv.build_canopy(mv.read_points(mv.example_points()), tile=(1, 1), level="8")
    return mv.LightEngine(canopy, density=0.3, heights_cm=(0.0,), periodic=True)


def test_a_models_name_is_taken_wherever_a_model_is(engine):
    """``absorbed_day(..., photosynthesis="c4")`` (an AttributeError in 0.2),
    ``photosynthesis(model="wofost")`` and ``assimilate(canopy, light, "c4")`` give what the
    model objects give, to the bit (the same computation)."""
    by_name = engine.absorbed_day(depth=1, directions=6, photosynthesis="c4", **DAY)
    by_model = engine.absorbed_day(depth=1, directions=6, photosynthesis=mv.leaf_model("c4"),
                                   **DAY)
    assert by_name.assimilation is not None and by_model.assimilation is not None
    assert by_name.assimilation.as_dict() == by_model.assimilation.as_dict()
    noon = engine.photosynthesis(zenith=30, azimuth=180, depth=1, model="wofost")
    assert noon.model["model"] == "wofost"
    light = engine.absorbed(zenith=30, azimuth=180, depth=1)
    a = assimilate(engine.canopy, light, "c4", 30.0)
    b = assimilate(engine.canopy, light, mv.leaf_model("c4"), 30.0)
    assert a.as_dict() == b.as_dict() and a.canopy_gross_umol_m2_s > 0
    with pytest.raises(mv.MaizevizError, match="unknown photosynthesis model 'c3'"):
        engine.absorbed_day(depth=1, directions=6, photosynthesis="c3", **DAY)
    with pytest.raises(mv.MaizevizError, match="a leaf model is a name") as err:
        as_leaf_model(3)                                   # type: ignore[arg-type]
    assert "\n" not in str(err.value)


def test_absorbed_and_assimilation_results_share_one_base(engine):
    """The four carbon results are TriangleResults: their totals and standard errors come
    from one place and equal what each reports in its own terms."""
    day = engine.absorbed_day(depth=1, directions=6, photosynthesis="c4", **DAY)
    sun = engine.photosynthesis(zenith=30, azimuth=180, depth=1)
    light = engine.absorbed(zenith=30, azimuth=180, depth=1)
    carbon = day.assimilation
    assert carbon is not None
    for r in (light, day, sun, carbon):
        assert isinstance(r, TriangleResult) and isinstance(r, OnCanopy), type(r).__name__
        assert r.canopy is engine.canopy and r.triangle_total_error is not None
    assert sun.canopy_gross_umol_m2_s == pytest.approx(sun.triangle_total / sun.ground_m2,
                                                       rel=1e-12)
    assert carbon.canopy_gross_error_mol_m2 == pytest.approx(
        carbon.triangle_total_error / carbon.ground_m2, rel=1e-12)
    # the leaves' absorbed light's error is the triangles' total's, in the balance's units
    assert light.absorbed_leaves_error == pytest.approx(
        light.triangle_total_error * light.balance.absorbed_leaves / light.triangle_total,
        rel=1e-12)
    # tables per leaf without the canopy passed back, their sums the totals
    leaves = day.triangle_absorbed_j[:engine.canopy.n_triangles]        # then the stalks'
    assert day.table("leaf")["absorbed_mj"].sum() == pytest.approx(leaves.sum() * 1e-6,
                                                                   rel=1e-9)
    assert np.isclose(carbon.table("plant")["gross_mol"].sum(), carbon.triangle_total)


USER_SCRIPT = """\
import maizeviz as mv

plants = mv.read_points(mv.example_points())
canopy = mv.build_canopy(plants, tile=(1, 1), level="8")
engine = mv.LightEngine(canopy, periodic=True, density=0.3)
day = engine.absorbed_day(date="2005-08-01", lat=39.9, lon=116.4, photosynthesis="c4")
noon = engine.photosynthesis(zenith=30, azimuth=180, model="wofost")
carbon = day.assimilation
reveal_type(carbon)
assert carbon is not None
reveal_type(carbon.canopy_gross_g_m2)
reveal_type(day.period)
reveal_type(noon)
reveal_type(noon.canopy_gross_error_umol_m2_s)
reveal_type(noon.table("leaf"))
grams: str = carbon.canopy_gross_g_m2
"""


def test_a_users_mypy_sees_the_carbon_types(tmp_path, request):
    """mypy on a user's script (maizeviz's own modules followed silently, as installed
    packages are): the assimilation of a day, its period and the engine's photosynthesis have
    their real types, not Any, and a wrong use is caught."""
    pytest.importorskip("mypy")             # the test tools' (not the min-versions run's)
    from mypy import api

    script = tmp_path / "user_carbon.py"
    script.write_text(USER_SCRIPT)
    cache = tmp_path / "mypy-cache"         # pytest's cache may be off (-p no:cacheprovider)
    out, err, _ = api.run([str(script), "--follow-imports", "silent", "--cache-dir",
                           str(cache), "--python-version", "3.11"])
    revealed = re.findall(r'Revealed type is "([^"]+)"', out)
    assert revealed == ["maizeviz.light.results.assimilation.PeriodAssimilation | None",
                        "float", "maizeviz.light.sources.irradiance.Period",
                        "maizeviz.light.results.assimilation.Assimilation", "float | None",
                        "pandas.core.frame.DataFrame"], out + err
    errors = [line for line in out.splitlines() if ": error:" in line]
    assert len(errors) == 1 and "user_carbon.py:16: error" in errors[0] and \
        '"float", variable has type "str"' in errors[0], out
