"""Leaf grids from a plant segmented by the Phenomenal pipeline (PhenoTrack3D).

The blade starts at the insertion (``pm_position_base``); it is cut into cross-sections along
the midrib, and each cross-section takes its margins from the voxels lying within half a
section of it (2nd and 98th percentiles of their offset across the blade), its height profile
from the voxels' median offset along the blade normal. The tip row collapses to the polyline's
end. Output grids follow the column convention of docs/method.md (col 0 = right margin seen from
above with the tip ahead) and are in centimetres.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.io.phenomenal import leaf_organs
from maizeviz.leaf.grid import LeafGrid, stalk_base


def _arc(points):
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(seg)])


def blade_grid(polyline: np.ndarray, voxels: np.ndarray, insertion: np.ndarray | None,
               cols: int = 5, section_cm: float = 7.0) -> np.ndarray:
    """A point grid (m, cols, 3) cm of one blade from its midrib (k, 3) and voxels (v, 3), mm."""
    poly = np.asarray(polyline, dtype=np.float64) / 10.0
    vox = np.asarray(voxels, dtype=np.float64).reshape(-1, 3) / 10.0
    if insertion is not None and np.all(np.isfinite(insertion)):
        start = int(np.argmin(np.linalg.norm(poly - np.asarray(insertion) / 10.0, axis=1)))
        poly = poly[start:]
    keep = np.concatenate([[True], np.linalg.norm(np.diff(poly, axis=0), axis=1) > 1e-9])
    poly = poly[keep]
    if len(poly) < 2:
        raise ValueError("midrib shorter than two points after the insertion")
    s = _arc(poly)
    length = s[-1]
    m = int(np.clip(round(length / section_cm) + 1, 4, 16))
    fine_s = np.linspace(0, length, 400)
    fine = np.column_stack([np.interp(fine_s, s, poly[:, k]) for k in range(3)])
    tangent = np.gradient(fine, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    right = np.cross(tangent, [0.0, 0.0, 1.0])
    rn = np.linalg.norm(right, axis=1, keepdims=True)
    right = np.where(rn > 1e-6, right / np.maximum(rn, 1e-12), [1.0, 0.0, 0.0])
    up = np.cross(right, tangent)
    stations = np.linspace(0, length, m)
    si = np.clip(np.searchsorted(fine_s, stations), 0, len(fine_s) - 1)

    from scipy.spatial import cKDTree  # ~0.5 s to import: only when importing

    near = cKDTree(fine).query(vox)[1] if len(vox) else np.empty(0, int)
    vs = fine_s[near]
    rel = vox - fine[near]
    lat = np.einsum("ij,ij->i", rel, right[near])
    nrm = np.einsum("ij,ij->i", rel, up[near])
    half = 0.5 * length / (m - 1)
    fractions = 1.0 - 2.0 * np.arange(cols) / (cols - 1)            # +1 right .. -1 left
    widths = np.full((m, 2), np.nan)                                 # right (>0), left (<0)
    heights = np.zeros((m, cols))
    for i in range(m - 1):
        sel = np.abs(vs - stations[i]) <= half
        if sel.sum() < 3:
            continue
        lr, nr = lat[sel], nrm[sel]
        widths[i] = [max(np.percentile(lr, 98), 0.2), min(np.percentile(lr, 2), -0.2)]
        for j, f in enumerate(fractions):
            target = f * (widths[i, 0] if f > 0 else -widths[i, 1])
            band = np.abs(lr - target) <= max(0.6, 0.25 * abs(target))
            heights[i, j] = np.median(nr[band]) if band.any() else 0.0
    ok = np.isfinite(widths[:, 0])
    ok[-1] = False
    if not ok.any():
        raise ValueError("no surface voxel near the midrib")
    for k in range(2):                                               # fill sections without voxels
        widths[:, k] = np.interp(stations, stations[ok], widths[ok, k])
    widths[-1] = 0.0
    grid = np.empty((m, cols, 3))
    for j, f in enumerate(fractions):
        off = np.where(f > 0, f * widths[:, 0], -f * widths[:, 1])
        grid[:, j] = (fine[si] + off[:, None] * right[si] + heights[:, j, None] * up[si])
    grid[-1] = fine[-1]
    return grid


def phenomenal_grids(data: dict, plant: int = 1, cols: int = 5) -> tuple[list[LeafGrid], list[str]]:
    """Leaf grids of every ranked leaf of a Phenomenal plant, plus warnings for skipped organs.

    Raises
    ------
    MaizevizError
        The structure is wrong (see :func:`maizeviz.io.phenomenal.leaf_organs`), or no leaf
        could be imported.
    """
    grids: list[LeafGrid] = []
    warnings: list[str] = []
    for organ in leaf_organs(data):
        longest = max(organ.polylines, key=len, default=np.empty((0, 3)))
        if organ.rank is None or not len(longest):
            warnings.append(f"a {organ.label} without rank or midrib skipped ({organ.where})")
            continue
        with np.errstate(all="ignore"):           # a degenerate blade is refused just below
            try:
                pts = blade_grid(longest, organ.voxels, organ.insertion, cols)
            except ValueError as exc:
                warnings.append(f"leaf {organ.rank}: skipped ({exc})")
                continue
        if not np.all(np.isfinite(pts)):
            warnings.append(f"leaf {organ.rank}: skipped (its midrib or voxels are degenerate)")
            continue
        if any(g.leaf == organ.rank for g in grids):
            warnings.append(f"leaf {organ.rank}: skipped (a leaf of that rank came first)")
            continue
        grids.append(LeafGrid(plant, organ.rank, pts, True, tuple(range(len(pts))), ()))
    if not grids:
        raise MaizevizError("no leaf could be imported from this Phenomenal plant")
    return sorted(grids, key=lambda g: g.leaf), warnings


def move_plant(grids: list[LeafGrid], x: float, y: float) -> list[LeafGrid]:
    """The plant's grids moved so its stalk base (median collar midrib point) stands at
    ``x, y`` cm."""
    if not (np.isfinite(x) and np.isfinite(y)) or max(abs(x), abs(y)) > 1e5:
        raise MaizevizError(f"the stalk position must be finite cm within 1 km, got {x}, {y}",
                            quantity="at")
    base = stalk_base(grids)
    return [replace(g, points=g.points + [x - base[0], y - base[1], 0.0]) for g in grids]
