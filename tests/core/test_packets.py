"""Embree's ray packets (maizeviz.mesh.packets, the C kernel _packets.c) against embreex's
single rays, through real Embree, under every instruction set Embree accepts on this CPU
(maizeviz.mesh.embree_isa): the same triangle for every ray and float32 distances within
maizeviz.mesh.precision's bound, coherent or not, in order or in tiles; whole light
computations with the same hits either way, heights within the bound;
the kernel is the extension built at install (nothing compiled or written at run time), the
Embree library is found in every embreex wheel layout, and every fallback says why, once."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from embree_contract import assert_same_blocked, assert_same_hits

import maizeviz.mesh.raytrace as raytrace
from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.leaf.fit import read_leaves
from maizeviz.light.scene.embree_scenes import light_scene
from maizeviz.light.scene.request import LightRequest, Sampling, canopy_top
from maizeviz.light.sources.sky import make_sky
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace import beam
from maizeviz.light.trace.beam import trace_direction, trace_light
from maizeviz.light.trace.directions import trace_sky
from maizeviz.mesh import packets
from maizeviz.mesh.embree_isa import supported
from maizeviz.mesh.levels import parse_level
from maizeviz.mesh.precision import U32, distance_bound
from maizeviz.mesh.raytrace import RayScene
from maizeviz.resources import example_points

needs_kernel = pytest.mark.skipif(packets.kernel() is None,
                                  reason="no C compiler or Embree library for the packets")


@pytest.fixture(scope="module")
def canopy():
    leaves = read_leaves(example_points()).leaves
    return build_canopy(leaves, layout_for(leaves, (3, 3)), parse_level("36"))


#: The instruction sets Embree accepts here (each a run of the contract's tests).
ISAS = supported() or (None,)


@pytest.fixture(scope="module", params=ISAS)
def scenes(canopy, request):
    both = (RayScene(canopy.vertices, canopy.faces, packets=False, isa=request.param),
            RayScene(canopy.vertices, canopy.faces, isa=request.param))
    return both


def grid_rays(canopy, toward, nx=300, ny=200, z=None):
    """A grid of parallel rays laid out row by row (ny a row) over the central tile."""
    x0, y0, x1, y1 = canopy.layout.centre_bounds
    i, j = np.divmod(np.arange(nx * ny), ny)
    org = np.empty((nx * ny, 3))
    org[:, 0] = x0 + (i + 0.5) * (x1 - x0) / nx
    org[:, 1] = y0 + (j + 0.5) * (y1 - y0) / ny
    org[:, 2] = 0.0 if z is None else z
    top = float(canopy.vertices[:, 2].max()) + 1.0
    return org, np.full(len(org), (top - org[0, 2]) / toward[2])


@needs_kernel
def test_packets_give_embreex_hits_ray_for_ray(canopy, scenes):
    single, packed = scenes
    assert packed.packets and not single.packets
    rng = np.random.default_rng(5)
    s = Sun(35, 140).direction()
    org, length = grid_rays(canopy, s)
    down_org = org + length[:, None] * s                    # from above, toward the ground
    n = len(org)
    rand_org = np.column_stack([rng.uniform(-150, 330, n), rng.uniform(-80, 170, n),
                                rng.uniform(0, 260, n)])
    rand_dir = rng.normal(size=(n, 3))
    rand_dir /= np.linalg.norm(rand_dir, axis=1, keepdims=True)
    cases = [(down_org, np.tile(-s, (n, 1)), length, 200),      # sunlight, a grid
             (org, np.tile(s, (n, 1)), length, 200),            # sensors toward the sun
             (rand_org, rand_dir, rng.uniform(0, 400, n), 0)]   # scattered light
    v, f = canopy.vertices, canopy.faces
    for o, d, t, row in cases:
        p1, t1 = single.first_hit(o, d, t)
        assert 0.05 < np.mean(p1 >= 0) < 0.98
        u1 = single.first_hit(o, d)                              # unbounded rays
        for kwargs in ({}, {"row": row}):
            p2, t2 = packed.first_hit(o, d, t, **kwargs)
            assert_same_hits(v, f, o, d, t, (p1, t1), (p2, t2))
            assert_same_hits(v, f, o, d, t, (p1, single.distance(o, d, t)),
                             (p2, packed.distance(o, d, t, **kwargs)))
            assert_same_blocked(v, f, o, d, t, single.occluded(o, d, t),
                                packed.occluded(o, d, t, **kwargs), u1)
        assert_same_hits(v, f, o, d, None, u1, packed.first_hit(o, d))
    k = packets.kernel()
    sun, sensors = cases[0][:3], cases[1][:3]
    sun_hits, sensor_hits = single.first_hit(*sun), single.first_hit(sensors[0], sensors[1])
    for width in (4, 8, 16):                                     # every packet width
        for coherent in (False, True):
            got = packets.intersect(k, packed._handle, sun[0], -s[None], sun[2],
                                    coherent=coherent, width=width, row=200)
            assert_same_hits(v, f, *sun, sun_hits, got)
            b = packets.occluded(k, packed._handle, sensors[0], s[None], sensors[2],
                                 coherent=coherent, width=width, row=7)
            assert_same_blocked(v, f, *sensors, b, single.occluded(*sensors), sensor_hits)


@needs_kernel
@pytest.mark.parametrize("isa", ISAS)
@pytest.mark.parametrize("periodic", [False, True])
def test_light_is_the_same_through_packets_or_single_rays(canopy, monkeypatch, periodic, isa):
    """The same hits, first and second, the same lit sensors and sky shares; each first hit's
    height within the distance bound times the sun's vertical, plus its float32 rounding."""
    if isa is not None:
        monkeypatch.setenv("MAIZEVIZ_EMBREE_ISA", isa)
    req = LightRequest(Sun(28, 200), Sampling(density=2.0, periodic=periodic, threads=2))
    sky = make_sky("soc", 6)
    beams = []                                  # each path's sun beam, ray by ray

    def keep(*args, **kwargs):
        beams.append(trace_direction(*args, **kwargs))
        return beams[-1]

    monkeypatch.setattr(beam, "trace_direction", keep)
    fast = trace_light(canopy, req), trace_sky(canopy, sky, req.sampling)
    monkeypatch.setattr(raytrace._packets, "kernel", lambda: None)
    scene = light_scene(canopy, periodic=periodic)
    assert not scene.packets
    slow = trace_light(canopy, req, scene=scene), trace_sky(canopy, sky, req.sampling,
                                                            scene=scene)
    np.testing.assert_array_equal(fast[0].first_hits, slow[0].first_hits)
    np.testing.assert_array_equal(fast[0].second_hits, slow[0].second_hits)
    np.testing.assert_array_equal(fast[0].sensor_lit, slow[0].sensor_lit)
    np.testing.assert_array_equal(fast[1].triangle_share, slow[1].triangle_share)
    np.testing.assert_array_equal(fast[1].maps, slow[1].maps)
    one, other = beams
    np.testing.assert_array_equal(one.first_prim, other.first_prim)
    hit = one.first_prim >= 0
    np.testing.assert_array_equal(one.first_z[~hit], other.first_z[~hit])     # -inf
    z = one.first_z[hit].astype(np.float64)
    down = -np.asarray(one.toward, np.float64)
    t = (canopy_top(canopy) + 1.0 - z) / -down[2]       # from the rays' start plane
    tri = canopy.vertices[canopy.faces[one.first_prim[hit]]]
    edge = np.linalg.norm(tri[:, 1] - tri[:, 0], axis=1) + \
        np.linalg.norm(tri[:, 2] - tri[:, 0], axis=1)
    origins = tri[:, 0] - (t + edge)[:, None] * down    # as far as a start can be from v0
    bound = distance_bound(origins, np.broadcast_to(down, origins.shape), t, tri) * \
        -down[2] + 2 * U32 * np.abs(z)                  # and z's own float32 rounding
    gap = np.abs(z - other.first_z[hit])
    assert np.all(gap <= bound), f"worst gap {np.max(gap / bound):.2f} of the bound"


def test_the_kernel_is_the_extension_built_at_install(tmp_path):
    """The kernel in use is the extension module built from this _packets.c when maizeviz was
    installed; a light computation with no compiler on PATH and an empty home folder uses it
    and writes nothing there."""
    import importlib.machinery

    st = packets.status()
    assert (st.name, st.why) == ("packets", "")
    assert st.path is not None and st.path.parent == Path(packets.__file__).parent
    assert st.path.name.endswith(tuple(importlib.machinery.EXTENSION_SUFFIXES))
    home = tmp_path / "home"
    home.mkdir()
    code = ("import maizeviz as mv, warnings; warnings.simplefilter('error'); "
            "c = mv.build_canopy(mv.read_points(mv.example_points()), tile=(1, 1), "
            "level='8'); e = mv.LightEngine(c, density=0.2); r = e.sun(zenith=30, azimuth=0); "
            "print(e.scene().packets, r.transmission[0])")
    env = {k: v for k, v in os.environ.items() if k not in ("XDG_CACHE_HOME", "CC")}
    env.update(HOME=str(home), PATH=str(tmp_path / "no-compiler"), MPLCONFIGDIR=str(tmp_path))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[0] == "True"
    assert list(home.rglob("*")) == []


def _fallback(code: str, env: dict | None = None) -> subprocess.CompletedProcess:
    """Run ``code`` after tracing two scenes, warnings recorded: prints the kernel in use and
    every warning's text, one a line."""
    prog = ("import warnings, numpy as np\n" + code + "\n"
            "from maizeviz.mesh.raytrace import RayScene\n"
            "from maizeviz.mesh import packets\n"
            "v = np.array([[0, 0, 1.0], [1, 0, 1], [0, 1, 1]]); f = np.array([[0, 1, 2]])\n"
            "with warnings.catch_warnings(record=True) as said:\n"
            "    warnings.simplefilter('always')\n"
            "    scenes = [RayScene(v, f), RayScene(v, f)]\n"
            "    hit = scenes[1].first_hit(np.array([[0.2, 0.2, 0.0]]), np.array([[0, 0, 1.0]]))\n"
            "print(packets.status().name, scenes[0].packets, int(hit[0][0]))\n"
            "for w in said: print(w.category.__name__, w.message)\n")
    base = {k: v for k, v in os.environ.items() if k != "MAIZEVIZ_EMBREE_ISA"}
    return subprocess.run([sys.executable, "-c", prog], capture_output=True, text=True,
                          timeout=300, env={**base, **(env or {})})


def test_without_the_built_kernel_rays_fall_back_and_say_why_once():
    out = _fallback("import sys; sys.modules['maizeviz.mesh._packets'] = None")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == "embreex False 0"                  # the same hit through single rays
    assert len(lines) == 2 and lines[1].startswith("RuntimeWarning maizeviz: tracing with "
                                                   "embreex's single rays")
    assert "was not built when maizeviz was installed" in lines[1]


def test_a_kernel_built_from_another_source_is_not_used(tmp_path, monkeypatch):
    other = tmp_path / "_packets.c"
    other.write_bytes(packets.SOURCE.read_bytes() + b"\n/* edited */\n")
    monkeypatch.setattr(packets, "SOURCE", other)
    k, st = packets._load()
    assert k is None and st.name == "embreex"
    assert "was built from another _packets.c" in st.why and "pip install -e ." in st.why


def test_turning_the_packets_off_is_not_warned_about():
    out = _fallback("", {"MAIZEVIZ_PACKETS": "0"})
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines() == ["embreex False 0"]


def test_an_unknown_embreex_keeps_its_scenes_private_and_says_so():
    """embreex releases whose scene layout maizeviz does not know: neither the copy fill nor
    the packets read its private scene handle; each fallback is said once."""
    out = _fallback("import maizeviz.mesh.embree_fill as ef; ef.KNOWN_EMBREEX = ((4, 3),)")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == "embreex False 0"
    assert len(lines) == 3
    assert all("is not a release whose scene layout maizeviz knows (4.3.x)" in w
               for w in lines[1:])
    assert "filling Embree's scenes through embreex" in lines[1]
    assert "tracing with embreex's single rays" in lines[2]


#: The Embree library in each embreex 4.4.0.post1 wheel, with the files beside it (from
#: ``pip download embreex --platform ... --only-binary=:all:``, unpacked).
WHEEL_FILES = {
    "manylinux_2_17_x86_64": ("embreex.libs/libembree4-4aef3270.so.4",
                              ["embreex.libs/libtbb-dcf63f8c.so.12",
                               "embreex/rtcore.cpython-311-x86_64-linux-gnu.so"]),
    "macosx_13_0_arm64": ("embreex/.dylibs/libembree4.4.dylib",
                          ["embreex/.dylibs/libtbb.12.11.dylib",
                           "embreex/rtcore.cpython-311-darwin.so"]),
    "macosx_13_0_x86_64": ("embreex/.dylibs/libembree4.4.dylib",
                           ["embreex/.dylibs/libtbb.12.11.dylib",
                            "embreex/rtcore_scene.cpython-311-darwin.so"]),
    "win_amd64": ("embreex.libs/embree4.dll",
                  ["embreex.libs/tbb12.dll",
                   "embreex.libs/msvcp140-a4c2229bdc2a2a630acdc095b4d86008.dll",
                   "embreex/rtcore.cp311-win_amd64.pyd"]),
}


@pytest.mark.parametrize("wheel", sorted(WHEEL_FILES))
def test_embree_is_found_in_every_wheel_layout(tmp_path, wheel):
    from maizeviz.mesh.embree_fill import wheel_library

    library, others = WHEEL_FILES[wheel]
    for name in (library, *others):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_bytes(b"")
    assert wheel_library(tmp_path) == tmp_path / library
    assert wheel_library(tmp_path / "elsewhere") is None


def test_the_library_found_is_the_one_embreex_loaded():
    import embreex

    from maizeviz.mesh.embree_fill import embree, loaded_library, wheel_library

    e = embree()
    assert e.scene_field and e.why == "" and e.version.startswith("4.")
    assert e.path == loaded_library()
    site = Path(embreex.__file__).resolve().parent.parent
    if (site / "embreex.libs").is_dir() or (site / "embreex" / ".dylibs").is_dir():
        assert wheel_library(site).resolve() == e.path.resolve()     # embreex's own wheel


def test_without_embreex_light_is_refused_in_one_line_naming_the_platform():
    """Where embreex has no wheel (pyproject's marker leaves it out), maizeviz installs and
    light is refused in one line naming the platform and where embreex has wheels."""
    import platform

    code = ("import sys; sys.modules['embreex'] = None\n"
            "from maizeviz.cli import main\n"
            "from maizeviz.resources import example_points\n"
            "sys.exit(main(['light', str(example_points()), '--triangles', '8', '--density', "
            "'0.2', '--sun-zenith', '30', '--sun-azimuth', '150']))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 1
    errors = [line for line in out.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "Traceback" not in out.stderr
    assert "embreex has wheels for Linux x86-64, Windows x86-64 and macOS 13" in errors[0]
    assert f"this is {sys.platform} {platform.machine()}" in errors[0]
