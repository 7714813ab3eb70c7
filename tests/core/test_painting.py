"""Painting a sun's light honestly: a leaf's sunlit share is the per-leaf table's sunlit area
over the leaf's area; triangles are painted one by one only where the rays sample them."""

from __future__ import annotations

import numpy as np
import pytest

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.leaf.fit import read_leaves
from maizeviz.light.results.painting import (
    MIN_RAYS,
    expected_rays,
    leaf_sunlit_share,
    sun_painting,
)
from maizeviz.light.results.per_leaf import tile_representatives
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.beam import trace_light
from maizeviz.mesh.levels import parse_level


@pytest.fixture(scope="module")
def leaves(tmp_path_factory):
    from maizeviz.cli import main

    path = tmp_path_factory.mktemp("paint") / "plants.csv"
    assert main(["synth", "--plants", "1x2", "--seed", "5", "--out", str(path)]) == 0
    return read_leaves(path).leaves


def _sun(canopy, density, periodic=True):
    return trace_light(canopy, LightRequest(Sun(30.0, 150.0),
                                            Sampling((0.0, 100.0), density, None, periodic),
                                            classes=True))


@pytest.mark.parametrize("tiles, periodic", [((3, 3), True), ((1, 1), False)])
def test_a_leafs_share_is_the_leaf_tables_sunlit_area_over_its_area(leaves, tiles, periodic):
    canopy = build_canopy(leaves, layout_for(leaves, tiles), parse_level("16"))
    result = _sun(canopy, 1.0, periodic)
    share = leaf_sunlit_share(canopy, result)
    classes = result.triangle_light(canopy)
    rows = result.leaf_rows(canopy)
    assert rows
    checked = 0
    for row in rows:
        inst, rank = int(row["instance"]) - 1, int(row["leaf"])
        mine = (canopy.face_instance == inst) & (canopy.face_leaf == rank)
        if not mine.any() or (classes[mine] < 0).any():        # partly outside the sample
            continue
        # every triangle of the leaf carries one share
        assert np.ptp(share[mine]) == 0
        want = row["sunlit_area_cm2"] / row["leaf_area_cm2"]
        assert share[mine][0] == pytest.approx(want, rel=1e-5)
        checked += 1
    assert checked >= 5
    # leaves no ray lit have a share of 0, and no share leaves 0..1
    finite = share[np.isfinite(share)]
    assert finite.min() >= 0 and finite.max() <= 1
    # (a plant's copies in a periodic field are reported under one of them)
    rep = tile_representatives(canopy.layout, result.rect, result.periodic)
    lit_keys = {(int(r["instance"]) - 1, int(r["leaf"])) for r in rows
                if r["sunlit_area_cm2"] > 0}
    dark = 0
    for inst, rank in {(int(i), int(k)) for i, k in zip(canopy.face_instance,
                                                        canopy.face_leaf)}:
        mine = (canopy.face_instance == inst) & (canopy.face_leaf == rank)
        if (int(rep[inst]), rank) not in lit_keys:
            assert np.all((share[mine] == 0) | np.isnan(share[mine]))
            dark += 1
        else:
            assert np.all(share[mine] > 0)
    assert dark > 0


def test_triangles_are_painted_only_when_the_rays_sample_them(leaves):
    fine = build_canopy(leaves, layout_for(leaves, (1, 1)), parse_level("K4"))
    coarse = build_canopy(leaves, layout_for(leaves, (1, 1)), parse_level("36"))
    at_2 = sun_painting(fine, _sun(fine, 2.0))
    # the K = 4 view: most triangles classed unlit though their leaves are in the sun
    unlit = at_2.classes == 0
    lit_leaf = at_2.share > 0.2
    assert (unlit & lit_leaf).sum() > 0.5 * lit_leaf.sum()
    assert at_2.per == "leaves" and at_2.rays_per_triangle < 1
    assert "too few to class each triangle" in at_2.note()
    # expected rays grow with the density, exactly
    r1, r2 = expected_rays(fine, _sun(fine, 1.0)), expected_rays(fine, _sun(fine, 2.0))
    np.testing.assert_allclose(r2, 2.0 * r1 * (_sun(fine, 2.0).density_per_cm2 /
                                               (2.0 * _sun(fine, 1.0).density_per_cm2)))
    # enough rays for the K = 4 triangles: each is painted with its class
    dense = MIN_RAYS / at_2.rays_per_triangle * 2.0 * 1.2
    at_dense = sun_painting(fine, _sun(fine, dense))
    assert at_dense.per == "triangles" and at_dense.rays_per_triangle >= MIN_RAYS
    # 36 triangles a leaf at 2 rays/cm2: triangles large enough
    assert sun_painting(coarse, _sun(coarse, 2.0)).per == "triangles"
    # asked for, either way; the note says when the triangles are too small
    assert at_2.chosen("triangles") == "triangles"
    assert "many sunlit triangles get no ray" in at_2.note("triangles")
    with pytest.raises(ValueError, match="paint per 'pixels'"):
        at_2.chosen("pixels")


def test_a_leafs_share_hardly_depends_on_the_mesh_level(leaves):
    """The per-leaf share is an estimate of the same leaf's light at any level: between K = 4
    and 36 triangles a leaf (the same leaves, differently meshed), the canopy's area-weighted
    share agrees within a few hundredths, where the triangles' classes disagree wildly."""
    shares = {}
    for level in ("K4", "36"):
        canopy = build_canopy(leaves, layout_for(leaves, (3, 3)), parse_level(level))
        p = sun_painting(canopy, _sun(canopy, 2.0))
        from maizeviz.mesh.tessellate import triangle_areas_normals

        area, _ = triangle_areas_normals(canopy.vertices, canopy.faces)
        ok = np.isfinite(p.share)
        shares[level] = (float(np.sum(p.share[ok] * area[ok]) / area[ok].sum()),
                         float(np.sum((p.classes[ok] == 2) * area[ok]) / area[ok].sum()))
    assert shares["K4"][0] == pytest.approx(shares["36"][0], abs=0.05)
    assert shares["K4"][1] < 0.5 * shares["36"][1]          # classes: direct area halves
