"""Reading the K = 4 canopy as a mesh file: maizeviz's reader against a plain numpy read.

The bundled 3 x 3 block tiled 3 x 3 at K = 4 (2.68 million leaf triangles) is exported as a
binary PLY (``maizeviz canopy --export``) and read back, in the same run:

- **anchor**: a plain numpy read of the same file, knowing its layout in advance (the
  header's offsets and types): ``np.fromfile`` of the vertices and of the faces' records, then
  the same outputs the reader gives (float64 vertices, int64 faces, plant and leaf ids). No
  check at all: the least any reader can do;
- **read_mesh**: :func:`maizeviz.io.mesh_canopy.read_mesh`, plyfile with every guard (counts
  against the file size, list lengths, finite vertices, index range, whole ids in range);
- **read_mesh_canopy**: the same and the canopy made of it (what ``maizeviz light x.ply``
  does before the scene: repeated triangles, units, stalks, areas, plants and leaves);
- **trimesh**: ``trimesh.load(..., process=False)`` of the same file, where trimesh is
  installed (another library's parse, for the record);
- **old_read_mesh**: the hand-written parser before plyfile (from git, ``--old-rev``), for
  the record;

and the same canopy as OBJ (``read_mesh`` and the old parser). Each time is the shortest of
``--repeat`` calls, taken in turns; the targets are read_mesh / anchor <= 2 and
read_mesh_canopy / read_mesh <= 4 (a canopy as fast as its file is parsed), the latter in
wall time and in the process's CPU time (steadier on a shared machine).

    python benchmarks/bench_read_mesh.py [--json] [--repeat 5] [--old-rev e6c25db]
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from anchors import report  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def numpy_read(path: Path) -> tuple[np.ndarray, ...]:
    """The anchor: the file read with numpy alone, its layout known (maizeviz's export:
    float64 x y z, then uchar 3, int32 indices, int32 plant, int32 leaf per face)."""
    with path.open("rb") as fh:
        head = fh.read(4096)
        end = head.index(b"end_header\n") + len(b"end_header\n")
        words = head[:end].decode("ascii").split()
        nv = int(words[words.index("vertex") + 1])
        nf = int(words[words.index("face") + 1])
        fh.seek(end)
        v = np.fromfile(fh, "<f8", nv * 3).reshape(nv, 3)
        f = np.fromfile(fh, [("n", "u1"), ("v", "<i4", 3), ("plant", "<i4"), ("leaf", "<i4")],
                        nf)
    return v, f["v"].astype(np.int64), f["plant"].astype(np.int64), f["leaf"].astype(np.int64)


def old_reader(rev: str, folder: Path):
    """``read_mesh`` of maizeviz/io/mesh_canopy.py at ``rev`` (None without git)."""
    try:
        text = subprocess.run(["git", "show", f"{rev}:maizeviz/io/mesh_canopy.py"], cwd=ROOT,
                              capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return None
    path = folder / "old_mesh_canopy.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("old_mesh_canopy", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules["old_mesh_canopy"] = mod
    spec.loader.exec_module(mod)
    return mod.read_mesh


def timed(fns: dict, repeat: int, clock=time.perf_counter) -> dict[str, float]:
    """Shortest of ``repeat`` calls of each function, calls taken in turns."""
    best = dict.fromkeys(fns, float("inf"))
    for _ in range(repeat):
        for name, fn in fns.items():
            t0 = clock()
            fn()
            best[name] = min(best[name], clock() - t0)
    return best


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--repeat", type=int, default=5, help="calls of each reader (default 5)")
    ap.add_argument("--old-rev", default="e6c25db",
                    help="git revision of the hand-written parser (default: the last one)")
    ap.add_argument("--interp", type=int, default=4, help="mesh level K (default 4)")
    args = ap.parse_args(argv)

    from maizeviz.canopy.build import build_canopy
    from maizeviz.canopy.export import export_canopy
    from maizeviz.canopy.from_mesh import read_mesh_canopy
    from maizeviz.canopy.layout import layout_for
    from maizeviz.io.mesh_canopy import read_mesh
    from maizeviz.leaf.fit import read_leaves
    from maizeviz.mesh.levels import Level
    from maizeviz.resources import example_points

    found = read_leaves(example_points())
    canopy = build_canopy(found.leaves, layout_for(found.leaves, (3, 3)), Level(args.interp))
    out: dict = {"leaf_triangles": canopy.n_triangles}
    with tempfile.TemporaryDirectory(prefix="bench-read-mesh-") as tmp:
        tmp = Path(tmp)
        ply, obj = tmp / "canopy.ply", tmp / "canopy.obj"
        export_canopy(ply, canopy)
        export_canopy(obj, canopy)
        out.update(ply_bytes=ply.stat().st_size, obj_bytes=obj.stat().st_size)
        # the reader gives what the anchor gives
        mesh, (v, f, plant, leaf) = read_mesh(ply), numpy_read(ply)
        assert np.array_equal(mesh.vertices, v) and np.array_equal(mesh.faces, f)
        assert np.array_equal(mesh.plant, plant) and np.array_equal(mesh.leaf, leaf)
        old = old_reader(args.old_rev, tmp)
        fns = {"anchor_s": lambda: numpy_read(ply), "read_mesh_s": lambda: read_mesh(ply),
               "read_mesh_canopy_s": lambda: read_mesh_canopy(ply)}
        if old is not None:
            fns["old_read_mesh_s"] = lambda: old(ply)
        if importlib.util.find_spec("trimesh") is not None:
            import trimesh
            fns["trimesh_load_s"] = lambda: trimesh.load(ply, process=False)
        out.update(timed(fns, args.repeat))
        # the same in the process's CPU time, which other processes sharing the cores do not
        # lengthen as much as the wall clock
        cpu = timed({"read_mesh_cpu_s": fns["read_mesh_s"],
                     "read_mesh_canopy_cpu_s": fns["read_mesh_canopy_s"]}, args.repeat,
                    time.process_time)
        out.update(cpu)
        obj_fns = {"obj_read_mesh_s": lambda: read_mesh(obj)}
        if old is not None:
            obj_fns["obj_old_read_mesh_s"] = lambda: old(obj)
        out.update(timed(obj_fns, max(1, args.repeat // 2)))
    out["read_mesh_over_anchor"] = out["read_mesh_s"] / out["anchor_s"]
    out["target_read_mesh_over_anchor"] = 2.0
    out["canopy_over_read_mesh"] = out["read_mesh_canopy_s"] / out["read_mesh_s"]
    out["canopy_over_read_mesh_cpu"] = out["read_mesh_canopy_cpu_s"] / out["read_mesh_cpu_s"]
    out["target_canopy_over_read_mesh"] = 4.0
    if "trimesh_load_s" in out:
        out["canopy_over_trimesh"] = out["read_mesh_canopy_s"] / out["trimesh_load_s"]
    if "old_read_mesh_s" in out:
        out["old_over_anchor"] = out["old_read_mesh_s"] / out["anchor_s"]
        out["obj_old_over_new"] = out["obj_old_read_mesh_s"] / out["obj_read_mesh_s"]
    report(out, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
