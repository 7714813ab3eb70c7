"""Work that would not fit in memory is refused before anything is allocated, naming the
option that drives it: ``leaf --interp 50`` like ``canopy`` and ``light``, and a layout of
100,000 plants 1 cm apart (a layout file or a tiling)."""

import json
import resource
import subprocess
import sys

import pytest

from maizeviz.cli import EXIT_FAIL, main
from maizeviz.cost import (
    BYTES_PER_DEVIATION_POINT,
    BYTES_PER_LEAF_TRIANGLE,
    check,
    deviation_points,
    leaves_cost,
)
from maizeviz.errors import MaizevizError
from maizeviz.leaf.fit import read_leaves
from maizeviz.mesh.levels import Level
from maizeviz.resources import example_points

B = str(example_points())
#: Address space a refused run may use: the interpreter and its libraries, no more.
LIMIT_BYTES = 3 * 2**30


def _limited():
    resource.setrlimit(resource.RLIMIT_AS, (LIMIT_BYTES, LIMIT_BYTES))


def _run_limited(*argv):
    """``maizeviz argv`` in a child that cannot map more than LIMIT_BYTES."""
    proc = subprocess.run([sys.executable, "-m", "maizeviz", *argv], capture_output=True,
                          text=True, timeout=300, preexec_fn=_limited)
    errors = [ln for ln in proc.stderr.splitlines() if ln.startswith(("error", "internal"))]
    return proc.returncode, errors, proc.stderr


def test_leaf_cost_counts_the_triangles_the_command_makes(capsys):
    found = read_leaves(B)
    cost = leaves_cost(found.leaves, Level(interp=16), "interp", batch=4096)
    assert main(["leaf", B, "--interp", "16"]) == 0
    total = int(capsys.readouterr().out.split("leaves, ")[1].split(" triangles")[0])
    assert cost.count == total                     # the estimate is the data, not a guess
    largest = max(deviation_points(*lf.grid.shape) for lf in found.leaves)
    assert cost.bytes == total * BYTES_PER_LEAF_TRIANGLE + largest * BYTES_PER_DEVIATION_POINT
    kept = leaves_cost(found.leaves, Level(interp=16), "interp", batch=10, keep=True)
    assert kept.bytes == cost.bytes                # one batch of 140 or all kept: the same
    small = leaves_cost(found.leaves, Level(interp=16), "interp", batch=10)
    assert small.bytes < cost.bytes / 10


def test_leaf_interp_50_refused_against_the_memory_available():
    found = read_leaves(B)
    stage = [leaves_cost(found.leaves, Level(interp=50), "interp", batch=4096)]
    with pytest.raises(MaizevizError) as err:
        check([stage], available=4 * 2**30)
    assert err.value.quantity == "interp" and "31,2" in str(err.value)


def test_leaf_interp_50_refused_before_any_mesh(monkeypatch, capsys):
    monkeypatch.setattr("maizeviz.cost.memory_available", lambda: 2 * 2**30)
    assert main(["leaf", B, "--interp", "50"]) == EXIT_FAIL
    err = capsys.readouterr().err
    line = [ln for ln in err.splitlines() if ln.startswith(("error", "internal"))]
    assert len(line) == 1 and line[0].startswith("error: meshing 140 leaves at K=50")
    assert line[0].endswith("(--interp)")


def _grid_layout(path, spacing_rows, spacing_plants, n=316):
    rows = [{"x": float(i), "plants": [{"y": float(j), "plant": 1 + (i + j) % 9}
                                       for j in range(n)]} for i in range(n)]
    path.write_text(json.dumps({"maizeviz_layout": 1, "row_spacing": spacing_rows,
                                "plant_spacing": spacing_plants,
                                "field": {"x0": -1, "y0": -1, "x1": n + 1, "y1": n + 1},
                                "rows": rows}))
    return path


@pytest.mark.parametrize("spacing", [(1, 1), (60, 30)])
def test_a_layout_of_100000_plants_1_cm_apart_is_refused_naming_the_layout(tmp_path, spacing):
    layout = _grid_layout(tmp_path / "dense.json", *spacing)
    code, errors, err = _run_limited("canopy", B, "--layout", str(layout))
    assert code == EXIT_FAIL and len(errors) == 1, err[-800:]
    assert "99,856 plants" in errors[0] and errors[0].endswith("(--layout)"), errors


def test_a_tiling_of_100000_plants_1_cm_apart_is_refused_naming_the_tiling():
    code, errors, err = _run_limited("canopy", B, "--tile", "105x105", "--row-spacing", "1",
                                     "--plant-spacing", "1")
    assert code == EXIT_FAIL and len(errors) == 1, err[-800:]
    assert errors[0].endswith("(--tile)")


# ------------------------------------------------------------------ one huge leaf
def _peak_rss_run(*argv):
    """``maizeviz argv`` in a child limited to LIMIT_BYTES of address space; returns (exit
    code, stderr, its peak resident memory in bytes)."""
    code = ("import resource, sys\nfrom maizeviz.cli import main\n"
            f"rc = main({list(argv)!r})\n"
            "print('PEAK', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024, "
            "file=sys.stderr)\nsys.exit(rc)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=600, preexec_fn=_limited)
    peak = [ln for ln in proc.stderr.splitlines() if ln.startswith("PEAK")]
    return proc.returncode, proc.stderr, int(peak[0].split()[1]) if peak else None


def _one_leaf(path, rows, cols=3):
    lines = ["plant,leaf,row,col,x,y,z"]
    lines += [f"1,1,{r},{c},{0.5 * c:.3f},{0.01 * r:.4f},{50 + 0.01 * r:.4f}"
              for r in range(rows) for c in range(cols)]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("command", [["leaf"], ["canopy", "--tile", "1x1"]])
def test_one_leaf_of_10000_cross_sections_stays_within_its_estimate(tmp_path, command):
    """Issue 25: one leaf of 10,000 rows x 3 points (a 1 MB file) passed the estimate, then
    took 45 s and 3.9 GB and ended in MemoryError for 6.7 GiB more: its fit and sampling made
    dense matrices of (rows x 5)^2 and compared every sample with every mesh line. Now they
    are banded and searched, and the work stays within what the estimate counts (1 million
    triangles) over the interpreter's own memory (the same command on a leaf of 10 rows)."""
    from maizeviz.cost import BYTES_PER_TRIANGLE, canopy_cost

    big = _one_leaf(tmp_path / "big.csv", 10_000)
    small = _one_leaf(tmp_path / "small.csv", 10)
    leaves = read_leaves(big).leaves
    if command[0] == "leaf":
        estimate = leaves_cost(leaves, Level(interp=4), "interp", batch=4096).bytes
    else:
        estimate = canopy_cost(leaves, {1: 1}, Level(interp=4)).bytes
    assert estimate >= 999_900 * min(BYTES_PER_LEAF_TRIANGLE, BYTES_PER_TRIANGLE)
    code, err, peak = _peak_rss_run(command[0], str(big), *command[1:])
    assert code == 0, err[-800:]
    _, _, base = _peak_rss_run(command[0], str(small), *command[1:])
    assert peak - base <= estimate, (peak, base, estimate)
