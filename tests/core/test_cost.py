"""Cost estimates before any work: exact triangle counts, refusals that name the input."""

import pytest

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.cli import EXIT_FAIL, main
from maizeviz.cost import (
    BYTES_PER_TRIANGLE,
    Cost,
    canopy_cost,
    check,
    heatmap_cost,
    leaf_triangles,
    light_cost,
)
from maizeviz.errors import MaizevizError
from maizeviz.leaf.fit import read_leaves
from maizeviz.mesh.levels import Level, mesh_leaves
from maizeviz.resources import example_points


@pytest.fixture(scope="module")
def block():
    return read_leaves(example_points()).leaves


@pytest.mark.parametrize("level", [Level(interp=0), Level(interp=1), Level(interp=4),
                                   Level(triangles=36), Level(triangles=4)])
def test_leaf_triangles_match_the_meshes(block, level):
    meshes = mesh_leaves(block[:20], level)
    for lf, m in zip(block[:20], meshes):
        expect = leaf_triangles(*lf.grid.shape, lf.grid.tip_collapsed, level)
        if level.interp is not None:
            assert m.n_triangles == expect          # exact for K levels
        else:
            assert m.n_triangles <= expect          # an upper bound below the standard mesh


def test_canopy_cost_counts_every_placed_triangle(block):
    layout = layout_for(block, (2, 1))
    placed = {}
    for p in layout.placements:
        placed[p.plant] = placed.get(p.plant, 0) + 1
    cost = canopy_cost(block, placed, Level(interp=1))
    canopy = build_canopy(block, layout, Level(interp=1))
    assert cost.count == canopy.n_triangles and cost.quantity == "tile"
    assert cost.bytes == cost.count * BYTES_PER_TRIANGLE


def test_check_refuses_what_does_not_fit_and_what_is_slow():
    big = Cost("the canopy", "tile", 10**9, "triangles", 400 * 10**9, 500.0)
    with pytest.raises(MaizevizError, match="more than the .* of memory") as err:
        check([[big]], force=True, available=16 * 2**30)
    assert err.value.quantity == "tile"
    slow = Cost("tracing", "density", 10**10, "rays", 2**20, 4000.0)
    with pytest.raises(MaizevizError, match="force it") as err:
        check([[slow]], available=16 * 2**30)
    assert err.value.quantity == "density"
    check([[slow]], force=True, available=16 * 2**30)          # forced: runs
    # stages run one after the other: their memory is not added up
    half = Cost("a level", "tile", 1, "triangles", 9 * 2**30, 1.0)
    check([[half], [half]], available=16 * 2**30)
    with pytest.raises(MaizevizError):
        check([[half, half]], available=16 * 2**30)


def test_light_and_heatmap_costs_scale_with_density_and_bins():
    rect = (0.0, 0.0, 180.0, 90.0)
    one = light_cost(rect, 1.0, 6)
    assert one.count == 180 * 90 and light_cost(rect, 4.0, 6).count == 4 * one.count
    assert light_cost(rect, 1.0, 6, directions=46).count == 46 * one.count
    assert heatmap_cost(rect, 5.0, 6).count == 36 * 18 * 6
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(MaizevizError):
            light_cost(rect, bad, 1)
        with pytest.raises(MaizevizError):
            heatmap_cost(rect, bad, 1)


def test_absurd_tiling_is_refused_before_the_file_is_read(capsys, tmp_path):
    missing = tmp_path / "never_read.csv"
    assert main(["canopy", str(missing), "--tile", "1000x1000"]) == EXIT_FAIL
    err = capsys.readouterr().err
    assert "1,000,000 plants" in err and "(--tile)" in err and "no such file" not in err


@pytest.mark.parametrize("argv, says, flag", [
    (["canopy", "--tile", "30x30", "--interp", "4"], "GiB of memory", "--tile"),
    (["light", "--tile", "3x3", "--sun-zenith", "20", "--sun-azimuth", "0", "--density",
      "24000"], "GiB of memory", "--density"),
    (["light", "--tile", "3x3", "--sun-zenith", "20", "--sun-azimuth", "0", "--density", "1",
      "--heatmap-bin", "0.01", "--heatmaps", "HM"], "heatmap cells", "--heatmap-bin"),
])
def test_work_that_would_not_fit_is_refused_with_its_option(capsys, tmp_path, argv, says, flag):
    argv = [a.replace("HM", str(tmp_path / "maps")) for a in argv]
    assert main([argv[0], str(example_points()), *argv[1:]]) == EXIT_FAIL
    out, err = capsys.readouterr()
    line = [ln for ln in err.splitlines() if ln.startswith("error:")]
    assert len(line) == 1 and says in line[0] and line[0].endswith(f"({flag})")
    assert not out and not (tmp_path / "maps").exists()


def test_slow_work_is_its_own_error_with_the_estimate_apart_from_the_advice(block):
    from maizeviz.cost import TooSlow, layout_cost

    slow = Cost("tracing", "density", 10**10, "rays", 2**20, 4000.0)
    with pytest.raises(TooSlow) as err:
        check([[slow]], available=16 * 2**30)
    assert isinstance(err.value, MaizevizError) and err.value.quantity == "density"
    assert "force it" in str(err.value) and "force" not in err.value.estimate
    assert err.value.estimate.startswith("tracing: 10,000,000,000 rays")
    big = Cost("the canopy", "tile", 10**9, "triangles", 400 * 10**9, 1.0)
    with pytest.raises(MaizevizError) as err:                   # memory: never just slow
        check([[big]], available=16 * 2**30)
    assert not isinstance(err.value, TooSlow)
    layout = layout_for(block, (3, 2))
    assert layout_cost(block, layout, Level(interp=0)).count == \
        build_canopy(block, layout, Level(interp=0)).n_triangles
