"""What the app shows of photosynthesis (maizeviz_app.jobs, no Qt): an absorbed-PAR result
traced with a leaf model gives each leaf's gross assimilation per m2 of leaf on its triangles
and the plants' rows with their gross assimilation and its error, adding up to the canopy."""

from __future__ import annotations

import numpy as np
import pytest
from maizeviz_app.jobs import absorbed_of

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.io.points import write_points
from maizeviz.leaf.fit import read_leaves
from maizeviz.leaf.synth import block_grids
from maizeviz.light.engine import LightEngine
from maizeviz.light.specs import OpticsSpec
from maizeviz.mesh.levels import parse_level


@pytest.fixture(scope="module")
def canopy(tmp_path_factory):
    path = tmp_path_factory.mktemp("app") / "four.csv"
    write_points(path, block_grids(2, 2, seed=3))
    leaves = read_leaves(path).leaves
    return build_canopy(leaves, layout_for(leaves, (2, 2)), parse_level("16"))


def test_absorbed_par_with_a_leaf_model_shows_its_assimilation(canopy):
    eng = LightEngine(canopy, density=0.5, heights_cm=(0.0,), periodic=True, threads=1)
    sun = eng.sun(zenith=30, azimuth=180).sun
    spec = OpticsSpec("par", diffuse_w_m2=60.0, photosynthesis="wofost", temperature_c=28.0)
    light = spec.absorbed(eng, sun)
    shown = absorbed_of(canopy, light, spec)
    a = shown.assimilation
    assert a is not None and a.model["model"] == "wofost"
    plants = shown.plant_rows
    assert {"gross_umol_s", "gross_umol_s_se", "absorbed_w"} <= set(plants[0])
    total = sum(r["gross_umol_s"] for r in plants)
    assert total / a.ground_m2 == pytest.approx(a.canopy_gross_umol_m2_s, rel=1e-9)
    # each leaf's value on its triangles: its gross umol/s over its area
    leaves = a.table("leaf", canopy)
    first = leaves.iloc[0]
    on = (canopy.face_instance == first["instance"] - 1) & (canopy.face_leaf == first["leaf"])
    want = first["gross_umol_s"] / (first["leaf_area_cm2"] * 1e-4)
    np.testing.assert_allclose(shown.gross_value[on], want, rtol=1e-6)
    assert np.nanmax(shown.gross_value) < 60.0              # umol/m2 leaf/s: a leaf's rate
    # without a leaf model, nothing more than before
    plain = absorbed_of(canopy, light, OpticsSpec("par", diffuse_w_m2=60.0))
    assert plain.assimilation is None and plain.gross_value is None
    assert "gross_umol_s" not in plain.plant_rows[0]
