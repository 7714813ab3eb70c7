"""Leaf optics per leaf rank (a table, as measured spectra of young and old leaves give):
each triangle takes its leaf's rank's values, a table of the base values changes nothing bit
for bit, and two plates of different ranks match the closed form of their own optics."""

import numpy as np
import pytest
from test_scatter import plates

from maizeviz.cli import main as cli_main
from maizeviz.errors import MaizevizError
from maizeviz.light.engine import LightEngine
from maizeviz.light.trace.optics import Optics, read_optics_table


def test_each_triangle_takes_its_ranks_values():
    o = Optics(0.1, 0.05, 0.1, "par", ranks=((2, 0.2, 0.1), (1, 0.3, 0.0)))
    assert o.ranks == ((1, 0.3, 0.0), (2, 0.2, 0.1))             # sorted, floats
    rho, tau = o.per_triangle(np.array([0, 1, 2, 3, 2]))
    np.testing.assert_array_equal(rho, [0.1, 0.3, 0.2, 0.1, 0.2])
    np.testing.assert_array_equal(tau, [0.05, 0.0, 0.1, 0.05, 0.1])


def test_a_table_of_the_base_values_changes_nothing():
    canopy = plates([40.0, 90.0])
    eng = LightEngine(canopy, periodic=True, density=1.0, heights_cm=(0.0,))
    base = Optics(0.2, 0.15, 0.1)
    same = Optics(0.2, 0.15, 0.1, ranks=((1, 0.2, 0.15), (2, 0.2, 0.15)))
    a = eng.absorbed(zenith=20, azimuth=90, optics=base, direct_w_m2=400.0, seed=3)
    b = eng.absorbed(zenith=20, azimuth=90, optics=same, direct_w_m2=400.0, seed=3)
    np.testing.assert_array_equal(a.triangle_absorbed_w, b.triangle_absorbed_w)
    assert a.balance == b.balance


def test_two_plates_of_different_ranks_follow_their_own_optics():
    """The top plate (rank 2) black, the bottom one (rank 1) transmitting half: the beam
    never reaches the bottom; swapped, the top plate passes tau to the bottom one."""
    canopy = plates([40.0, 90.0])             # leaf 1 at 40 cm, leaf 2 at 90 cm
    eng = LightEngine(canopy, periodic=True, density=1.0, heights_cm=(0.0,))
    top_black = Optics(0.0, 0.5, 0.0, ranks=((2, 0.0, 0.0),))
    got = eng.absorbed(zenith=0.0, azimuth=0.0, optics=top_black, direct_w_m2=100.0, depth=5)
    per_leaf = [got.triangle_absorbed_w[canopy.face_leaf == k].sum() for k in (1, 2)]
    assert per_leaf[0] == 0.0 and got.balance.absorbed_leaves == pytest.approx(100.0, rel=0.005)
    top_clear = Optics(0.0, 0.0, 0.0, ranks=((2, 0.0, 0.5),))
    got = eng.absorbed(zenith=0.0, azimuth=0.0, optics=top_clear, direct_w_m2=100.0, depth=5)
    b = got.balance
    # the top plate absorbs half, transmits half to the black bottom plate
    assert b.absorbed_leaves == pytest.approx(100.0, rel=0.005) and b.absorbed_ground == 0.0
    leaf_w = {k: got.triangle_absorbed_w[canopy.face_leaf == k].sum() for k in (1, 2)}
    area = 1.0                                   # the 100 x 100 cm plot is 1 m2
    assert leaf_w[2] / area == pytest.approx(50.0, rel=0.03)
    assert leaf_w[1] / area == pytest.approx(50.0, rel=0.03)


def test_a_spreadsheets_byte_order_mark_is_read(tmp_path):
    path = tmp_path / "excel.csv"
    path.write_bytes(b"\xef\xbb\xbfrank,reflectance,transmittance\r\n1,0.2,0.1\r\n")
    assert read_optics_table(path, "par") == ((1, 0.2, 0.1),)


@pytest.mark.parametrize("text, says", [
    ("rank,reflectance\n1,0.1\n", "no 'transmittance' column"),
    ("rank,reflectance,transmittance\n1,x,0.1\n", "line 2: rank, reflectance and"),
    ("rank,reflectance,transmittance\n1,0.1\n", "line 2: 2 values for 3 columns"),
    ("rank,reflectance,transmittance\n1,0.7,0.6\n", "line 2: a leaf cannot reflect"),
    ("rank,reflectance,transmittance\n0,0.1,0.1\n", "line 2: a leaf rank must be"),
    ("rank,reflectance,transmittance\n1,0.1,0.1\n1,0.2,0.1\n", "line 3: leaf rank 1 was given"),
    ("rank,reflectance,transmittance\n1,nan,0.1\n", "line 2: the reflectance must be"),
    ("rank,reflectance,transmittance,band\n1,0.1,0.1,nir\n", "no row for the PAR band"),
    ("", "empty"),
])
def test_a_bad_optics_table_is_one_line(tmp_path, capsys, text, says):
    path = tmp_path / "ranks.csv"
    path.write_text(text)
    with pytest.raises(MaizevizError, match=says):
        Optics(0.1, 0.05, 0.1, ranks=read_optics_table(path, "par"))
    points = tmp_path / "p.csv"
    assert cli_main(["synth", "--plants", "1x1", "--seed", "2", "--out", str(points)]) == 0
    capsys.readouterr()
    code = cli_main(["light", str(points), "--sun-zenith", "30", "--sun-azimuth", "180",
                     "--density", "0.2", "--optics-table", str(path)])
    err = capsys.readouterr().err
    assert code != 0 and says.split(":")[0].split("'")[0] in err and "Traceback" not in err
    assert len(err.strip().splitlines()) <= 3
