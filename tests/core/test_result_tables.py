"""Every light result tables the same way: ``table(by=None, canopy=None) -> DataFrame``, None
giving its summary (per height, or the balance), leaf and plant tables needing the canopy, the
plants' sums equal to the leaves', and the same one-line errors."""

import inspect

import pandas as pd
import pytest

import maizeviz as mv

RESULTS = (mv.LightResult, mv.SkyLight, mv.PeriodLight, mv.AbsorbedLight, mv.AbsorbedPeriod,
           mv.Assimilation, mv.PeriodAssimilation)
SUMMARY = {"LightResult": "height", "SkyLight": "height", "PeriodLight": "height",
           "AbsorbedLight": "balance", "AbsorbedPeriod": "balance", "Assimilation": "canopy",
           "PeriodAssimilation": "canopy"}
DAY = dict(date="2005-08-01", lat=39.9, lon=116.4, tz="Asia/Shanghai", step_min=120)


@pytest.fixture(scope="module")
def traced():
    canopy = mv.build_canopy(mv.read_points(mv.example_points()), tile=(1, 1), level="8")
    engine = mv.LightEngine(canopy, density=0.3, heights_cm=(0.0, 100.0), periodic=True)
    sun = engine.sun(zenith=30, azimuth=150)
    day = engine.absorbed_day(depth=1, directions=6, photosynthesis=mv.leaf_model("c4"),
                              **DAY)
    results = [sun, engine.sky("soc", 6), engine.day(sky="soc", directions=6, **DAY),
               engine.absorbed(sun.sun, depth=2), day,
               engine.photosynthesis(sun.sun, depth=1), day.assimilation]
    return canopy, results


def test_one_signature_one_default_one_return_type():
    for cls in RESULTS:
        sig = inspect.signature(cls.table)
        assert list(sig.parameters) == ["self", "by", "canopy"], cls
        assert sig.parameters["by"].default is None and sig.parameters["canopy"].default is None
        assert sig.return_annotation in ("pd.DataFrame", pd.DataFrame), cls


def test_every_result_tables_its_summary_leaves_and_plants(traced):
    canopy, results = traced
    for r in results:
        name = type(r).__name__
        summary = r.table()
        assert isinstance(summary, pd.DataFrame) and summary.equals(r.table(SUMMARY[name]))
        leaves, plants = r.table("leaf", canopy), r.table("plant", canopy)
        value = next(c for c in ("sunlit_intercepted_cm2", "diffuse_intercepted_cm2",
                                 "par_intercepted_mol", "absorbed_w", "absorbed_mj",
                                 "gross_umol_s", "gross_mol") if c in leaves)
        assert len(leaves) > len(plants) > 0, name
        assert plants[value].sum() == pytest.approx(leaves[value].sum(), rel=1e-12), name
        if hasattr(r, "leaf_rows"):
            assert pd.DataFrame(r.leaf_rows(canopy))[value].sum() == \
                pytest.approx(leaves[value].sum(), rel=1e-12), name


def test_every_result_knows_its_canopy_and_a_pickled_one_leaves_it_behind(traced):
    """The engine's results table their leaves without the canopy passed back; a result that
    crossed a process boundary (pickled) carries no canopy and takes one again."""
    import pickle

    canopy, results = traced
    for r in results:
        name = type(r).__name__
        assert r.canopy is canopy, name
        assert r.table("leaf").equals(r.table("leaf", canopy)), name
        back = pickle.loads(pickle.dumps(r))
        assert back.canopy is None and back.with_canopy(canopy).table("plant").equals(
            r.table("plant")), name


def test_every_result_refuses_alike(traced):
    canopy, results = traced
    for r in results:
        with pytest.raises(mv.MaizevizError, match="needs the canopy") as info:
            r.with_canopy(None).table("plant")
        assert info.value.quantity == "canopy"
        with pytest.raises(mv.MaizevizError, match="a light table is by") as info:
            r.table("tree", canopy)
        assert info.value.quantity == "by"
        other = "balance" if SUMMARY[type(r).__name__] != "balance" else "height"
        with pytest.raises(mv.MaizevizError, match=f"got '{other}'"):
            r.table(other, canopy)
