"""The instruction set Embree traces with (maizeviz.mesh.embree_isa): MAIZEVIZ_EMBREE_ISA and
RayScene's ``isa`` checked as an option is, refused in one line; a scene under each instruction
set Embree accepts here gives the same hits as under the CPU's best, within the distance bound
(maizeviz.mesh.precision)."""

import numpy as np
import pytest

from maizeviz.errors import MaizevizError
from maizeviz.mesh import embree_isa
from maizeviz.mesh.embree_isa import ISAS, check_isa, supported
from maizeviz.mesh.precision import distance_bound
from maizeviz.mesh.raytrace import RayScene


def test_the_names_embree_knows_are_read_and_others_refused_in_one_line():
    assert check_isa(None) is None and check_isa(" ") is None
    assert check_isa("AVX2") == "avx2" and check_isa("sse42") == "sse4.2"
    for bad in ("avx9", "sse4", "isa=avx2", "avx2,threads=1"):
        with pytest.raises(MaizevizError) as err:
            check_isa(bad)
        msg = str(err.value)
        assert msg.startswith("MAIZEVIZ_EMBREE_ISA: ") and repr(bad) in msg
        assert len(msg.splitlines()) == 1 and ", ".join(ISAS) in msg


def test_the_variable_is_checked_when_a_scene_is_made(monkeypatch):
    v = np.array([[0, 0, 1.0], [1, 0, 1], [0, 1, 1]])
    f = np.array([[0, 1, 2]])
    monkeypatch.setenv("MAIZEVIZ_EMBREE_ISA", "pentium")
    with pytest.raises(MaizevizError, match="MAIZEVIZ_EMBREE_ISA='pentium' in the environment"):
        RayScene(v, f)
    monkeypatch.setenv("MAIZEVIZ_EMBREE_ISA", supported()[0])
    assert RayScene(v, f).isa == supported()[0]


def test_an_instruction_set_the_cpu_lacks_is_refused_naming_those_it_has(monkeypatch):
    monkeypatch.setattr(embree_isa, "_new", lambda lib, isa: 0)   # Embree refusing the device
    with pytest.raises(MaizevizError) as err:
        RayScene(np.array([[0, 0, 1.0], [1, 0, 1], [0, 1, 1]]), np.array([[0, 1, 2]]),
                 isa="avx512")
    assert "Embree refuses it on this CPU (it accepts sse2" in str(err.value)


def test_sse2_is_always_there():
    """Every x86-64 CPU has SSE2, the lowest kernels of Embree's release builds."""
    assert supported()[0] == "sse2"


@pytest.mark.parametrize("isa", supported())
def test_each_instruction_set_gives_the_hits_of_the_cpus_best(isa):
    rng = np.random.default_rng(3)
    verts = rng.uniform(0, 100, (3000, 3))
    faces = rng.integers(0, len(verts), (1000, 3))
    o = rng.uniform(-20, 120, (20_000, 3))
    d = rng.normal(size=(20_000, 3))
    best = RayScene(verts, faces, packets=False).first_hit(o, d)
    for packets in (False, True):
        p, t = RayScene(verts, faces, packets=packets, isa=isa).first_hit(o, d)
        np.testing.assert_array_equal(p, best[0])
        h = p >= 0
        assert 0.2 < h.mean() < 0.99
        bound = distance_bound(o[h], d[h], best[1][h], verts[faces[p[h]]])
        assert np.all(np.abs(t[h].astype(np.float64) - best[1][h]) <= bound)
