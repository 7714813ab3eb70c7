"""maizeviz.fspm.caribu: Caribu's interface on maizeviz's tracer, against what holds exactly
(a lit square, a wall, Beer's law in a homogeneous canopy, the energy balance, invariance) and
the interface itself (inputs as Caribu takes them, its files, its errors)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from square_leaves import spherical_normals, square_corners

from maizeviz.fspm.caribu import CaribuScene, CaribuSceneError
from maizeviz.io.canestra import encode_label, write_can, write_light, write_opt, write_pattern

SQUARE = [[(0, 0, 1), (1, 0, 1), (1, 1, 1)], [(0, 0, 1), (1, 1, 1), (0, 1, 1)]]


def lattice_tolerance(perimeter_cm: float, area_cm2: float, density: float) -> float:
    """Relative error of counting lattice rays in a shape: at most one ray spacing along its
    perimeter, with a margin of 2."""
    return 2.0 * perimeter_cm / math.sqrt(density) / area_cm2


def homogeneous(lai: float, side_m: float, seed: int = 3) -> dict:
    """Square leaves (two triangles) with spherical normals in a 1 x 1 m pattern, 0.1-1.1 m."""
    rng = np.random.default_rng(seed)
    n = int(round(lai / side_m ** 2))
    c = np.column_stack([rng.random(n), rng.random(n), 0.1 + rng.random(n)])
    p = square_corners(c, spherical_normals(rng, n), side_m)
    tris = np.stack([p[:, [0, 1, 2]], p[:, [0, 2, 3]]], 1)          # (n, 2, 3, 3)
    return {i: tris[i] for i in range(n)}


def test_a_square_under_a_vertical_light_receives_the_light_and_absorbs_its_share():
    scene = CaribuScene(scene={"leaf": SQUARE}, light=[(2.0, (0, 0, -1))],
                        opt={"par": {"leaf": (0.06, 0.07)}}, density=4)
    raw, agg = scene.run(direct=True)
    tol = lattice_tolerance(400, 10_000, 4)
    assert agg["par"]["area"]["leaf"] == pytest.approx(1.0)
    assert agg["par"]["Ei"]["leaf"] == pytest.approx(2.0, rel=tol)
    for ei, eabs in zip(raw["par"]["Ei"]["leaf"], raw["par"]["Eabs"]["leaf"]):
        assert eabs == pytest.approx(ei * (1 - 0.06 - 0.07), rel=1e-12)


@pytest.mark.parametrize("zenith", [30.0, 60.0])
def test_a_wall_facing_an_oblique_light_receives_its_normal_share_on_its_lit_side(zenith):
    z = math.radians(zenith)
    # the light travels toward -x: the wall at x = 0, normal +x, faces it
    wall = [[(0, 0, 0.5), (0, 1, 0.5), (0, 1, 1.5)], [(0, 0, 0.5), (0, 1, 1.5), (0, 0, 1.5)]]
    scene = CaribuScene(scene={"wall": wall}, light=[(1.0, (-math.sin(z), 0, -math.cos(z)))],
                        opt={"par": (0.1, 0.05)}, density=4)
    _, agg = scene.run(direct=True, split_face=True)
    shadow = 100 * math.tan(z)                         # cm of ground the wall shades
    tol = lattice_tolerance(2 * (100 + shadow), 100 * shadow, 4)
    assert agg["par"]["Ei"]["wall"] == pytest.approx(math.tan(z), rel=tol)
    assert agg["par"]["Ei_sup"]["wall"] == agg["par"]["Ei"]["wall"]
    assert agg["par"]["Ei_inf"]["wall"] == 0.0


def test_the_scene_unit_scales_areas_and_energies():
    cm = CaribuScene(scene={"leaf": (np.array(SQUARE) * 100).tolist()}, scene_unit="cm",
                     light=[(1.0, (0, 0, -1))], opt={"par": (0.1, 0.05)}, density=4)
    m = CaribuScene(scene={"leaf": SQUARE}, light=[(1.0, (0, 0, -1))],
                    opt={"par": (0.1, 0.05)}, density=4)
    a, b = cm.run()[1]["par"], m.run()[1]["par"]
    assert a["area"]["leaf"] == pytest.approx(b["area"]["leaf"])
    assert a["Ei"]["leaf"] == pytest.approx(b["Ei"]["leaf"], rel=1e-9)


@pytest.mark.parametrize("zenith", [0.0, 45.0])
def test_a_homogeneous_infinite_canopy_intercepts_by_beers_law(zenith):
    """Small leaves with spherical normals (G = 0.5) placed at random: the share of a beam
    intercepted is 1 - exp(-G LAI / cos(zenith)); the random canopy's own deviation is about
    the binomial error over leaf-sized cells of the pattern, taken 5 times."""
    lai, side = 1.5, 0.01
    z = math.radians(zenith)
    scene = CaribuScene(scene=homogeneous(lai, side), pattern=(0, 0, 1, 1),
                        light=[(1.0, (math.sin(z), 0.0, -math.cos(z)))],
                        opt={"par": (0.0, 0.0)}, density=9)
    _, agg = scene.run(direct=True, infinite=True)
    got = sum(agg["par"]["Ei"][k] * agg["par"]["area"][k] for k in agg["par"]["area"])
    expected = 1 - math.exp(-0.5 * lai / math.cos(z))
    cells = 1.0 / side ** 2
    assert got == pytest.approx(expected, abs=5 * math.sqrt(expected * (1 - expected) / cells))


def test_with_scattering_the_parts_add_up_to_the_incident_light():
    scene = CaribuScene(scene=homogeneous(2.0, 0.02), pattern=(0, 0, 1, 1),
                        light=[(1.0, (0.3, 0.1, -1.0))], opt={"par": (0.1, 0.05)},
                        soil_reflectance={"par": 0.2}, soil_mesh=1, density=4)
    raw, agg = scene.run(direct=False, infinite=True)
    b = scene.balance["par"]
    parts = b["leaves"] + b["soil"] + b["top"] + b["sides"] + b["unresolved"]
    # deposits are exact expectations: closure within a few times sqrt(events) / rays
    assert parts == pytest.approx(b["incident"], rel=0.01)
    assert b["sides"] == 0.0                        # a periodic field loses nothing sideways
    leaves = sum(agg["par"]["Eabs"][k] * agg["par"]["area"][k] for k in agg["par"]["area"])
    assert leaves == pytest.approx(b["leaves"], rel=1e-9)
    direct = CaribuScene(scene=homogeneous(2.0, 0.02), pattern=(0, 0, 1, 1),
                         light=[(1.0, (0.3, 0.1, -1.0))], opt={"par": (0.1, 0.05)},
                         density=4).run(direct=True, infinite=True)[1]
    first = sum(direct["par"]["Eabs"][k] * direct["par"]["area"][k] for k in agg["par"]["area"])
    assert leaves > first                           # scattered light adds to the first hits
    qi, einc = scene.getSoilEnergy()
    assert 0 < qi < 1 and einc == pytest.approx(qi)


def test_moving_triangles_by_whole_patterns_changes_nothing_in_an_infinite_canopy():
    leaves = homogeneous(1.0, 0.03, seed=5)
    moved = {k: v + np.array([2.0 * (k % 3), -1.0 * (k % 2), 0.0]) for k, v in leaves.items()}
    kwargs = dict(pattern=(0, 0, 1, 1), light=[(1.0, (0.2, 0.3, -1.0))],
                  opt={"par": (0.1, 0.05)}, density=4)
    a = CaribuScene(scene=leaves, **kwargs).run(direct=True, infinite=True)[1]["par"]["Ei"]
    b = CaribuScene(scene=moved, **kwargs).run(direct=True, infinite=True)[1]["par"]["Ei"]
    total_a, total_b = sum(a.values()), sum(b.values())
    # the same rays meet the same triangles, up to rounding at a triangle's edge
    assert total_b == pytest.approx(total_a, rel=1e-3)


def test_bands_and_labels_take_their_own_materials():
    scene = CaribuScene(scene={"leaf": SQUARE, "stem": (np.array(SQUARE) + [2, 0, 0]).tolist()},
                        light=[(1.0, (0, 0, -1))], density=4,
                        opt={"par": {"leaf": (0.06, 0.07), "stem": (0.13,)},
                             "nir": {"leaf": (0.45, 0.4), "stem": (0.4,)}},
                        soil_reflectance={"par": 0.1, "nir": 0.2})
    raw, agg = scene.run(direct=True)
    assert set(agg) == {"par", "nir"}
    for band, (leaf_kept, stem_kept) in {"par": (0.87, 0.87), "nir": (0.15, 0.6)}.items():
        assert agg[band]["Eabs"]["leaf"] == pytest.approx(agg[band]["Ei"]["leaf"] * leaf_kept)
        assert agg[band]["Eabs"]["stem"] == pytest.approx(agg[band]["Ei"]["stem"] * stem_kept)
    raw1, agg1 = CaribuScene(scene={"leaf": SQUARE}, density=4).run(simplify=True)
    assert set(agg1) == {"Eabs", "Ei", "area"}              # one band: no band level


def test_a_caribu_script_on_canestra_files_runs_with_one_import_changed(tmp_path):
    labels = [encode_label(1, True, 1, 1), encode_label(2, False, 1, 2)]
    write_can(tmp_path / "scene.can", {labels[0]: SQUARE,
                                       labels[1]: (np.array(SQUARE) + [0, 0, -0.5]).tolist()})
    write_light(tmp_path / "sky.light", [(0.6, (0, 0, -1)), (0.4, (0.5, 0, -0.866))])
    write_opt(tmp_path / "par.opt", 0.15, {1: (0.06, 0.07), 2: (0.13,)})
    write_pattern(tmp_path / "p.8", (-1, -1, 2, 2))
    scene = CaribuScene(scene=str(tmp_path / "scene.can"), light=str(tmp_path / "sky.light"),
                        opt=[str(tmp_path / "par.opt")], pattern=str(tmp_path / "p.8"),
                        density=4)
    raw, agg = scene.run(direct=False, infinite=True)
    assert set(agg["par"]["Eabs"]) == set(labels)
    assert scene.material["par"][labels[1]] == (0.13,)            # an opaque stem species
    assert agg["par"]["Ei"][labels[0]] > agg["par"]["Ei"][labels[1]]   # the lower one is shaded
    qi, qem, einc = scene.getIncidentEnergy()
    assert qi == pytest.approx(1.0) and einc == pytest.approx(9.0)
    assert qem == pytest.approx(0.6 + 0.4 / 0.866, rel=1e-3)


@pytest.mark.parametrize("kwargs, run, words", [
    (dict(light=[(1.0, (0, 0, 1))]), {}, "does not come from above"),
    (dict(light=[(1.0, (0, 0))]), {}, "light 0"),
    (dict(opt={"par": {"leaf": (0.7, 0.6)}}), {}, "sum to at most 1"),
    (dict(opt={"par": {"other": (0.1,)}}), {}, "no material for label(s) leaf"),
    (dict(opt={"par": {"leaf": (0.1, 0.1, 0.1)}}), {}, "1, 2 or 4"),
    (dict(pattern=(0, 0, 0, 1)), {}, "encloses no area"),
    (dict(scene_unit="ft"), {}, "unknown scene unit"),
    (dict(soil_mesh=1), {}, "needs the scene's pattern"),
    ({}, dict(infinite=True), "needs its pattern"),
    ({}, dict(sensors={1: SQUARE}), "sensors are not traced"),
    ({}, dict(direct=False, split_face=True), "direct light only"),
    (dict(density=0), {}, "ray density must be > 0"),
    (dict(z_soil=1.5), {}, "below the soil"),
])
def test_inputs_caribu_would_not_take_are_refused_in_one_line(kwargs, run, words):
    with pytest.raises(CaribuSceneError, match=None) as err:
        CaribuScene(scene={"leaf": SQUARE}, **kwargs).run(**run)
    assert words in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("scene, words", [
    ({"leaf": [[(0, 0, 0), (1, 0, 0)]]}, "shape"),
    ({"leaf": [[(0, 0, float("nan")), (1, 0, 0), (0, 1, 0)]]}, "not finite"),
    ({}, "non-empty"),
    ([1, 2], "non-empty"),
])
def test_a_malformed_scene_is_refused_naming_its_label(scene, words):
    with pytest.raises(CaribuSceneError) as err:
        CaribuScene(scene=scene)
    assert words in str(err.value)
