"""Below the standard mesh: inverse multi-line segment splitting under a triangle budget.

The paper's method (section 2.2) is Douglas-Peucker run top-down: start from the collar and the
tip cross-sections and the two margins, then repeatedly add the cross-section (grid row) or the
line across the blade (grid column) whose data point lies farthest from the current polylines,
as long as the triangle budget allows. The collar row, the tip row and both margins are always
kept, so the leaf keeps its length and span; the midrib column is added first whenever a mesh
with it and three cross-sections fits the budget.

Chords cut the curved midrib and the convex width profile, so a very coarse leaf loses area
(about -20% at 3 triangles). With ``preserve_area`` (the default) the kept cross-sections are
widened about their midrib point by one common factor, found by a few secant steps, so that the
coarse mesh has exactly the smooth surface's area (the width-rescaling trick of ADEL/OpenAlea);
the midrib line, the tip and the collar stay where they were digitized.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from maizeviz.mesh.tessellate import LeafMesh, grid_faces, mesh_grid, triangle_areas_normals


def count_triangles(n_rows: int, n_cols: int, tip_collapsed: bool) -> int:
    """Triangles of a grid of ``n_rows`` cross-sections x ``n_cols`` points, tip band halved."""
    return (n_cols - 1) * (2 * (n_rows - 1) - int(tip_collapsed))


def _segment_distance(p, a, b):
    """Distance of points p from segments a-b, all (..., 3) -> (...)."""
    ab = b - a
    ap = p - a
    denom = np.einsum("...k,...k->...", ab, ab)
    t = np.einsum("...k,...k->...", ap, ab) / np.where(denom > 0, denom, 1.0)
    t = np.minimum(np.maximum(t, 0.0), 1.0)
    d = ap - t[..., None] * ab
    return np.sqrt(np.einsum("...k,...k->...", d, d))


def _split_errors(grid: np.ndarray, kept: np.ndarray) -> np.ndarray:
    """For each index along axis 0 of ``grid`` (m, n, 3): the largest distance of its points
    from the chords between the kept indices around it (0 where kept)."""
    m = grid.shape[0]
    idx = np.arange(m)
    lo = np.maximum.accumulate(np.where(kept, idx, 0))
    hi = np.minimum.accumulate(np.where(kept, idx, m - 1)[::-1])[::-1]
    err = _segment_distance(grid, grid[lo], grid[hi]).max(axis=1)
    err[kept] = 0.0
    return err


@dataclass(frozen=True)
class Selection:
    """Rows and columns of the standard grid kept by the splitting."""

    rows: np.ndarray
    cols: np.ndarray


def _greedy(grid, rows, cols, budget, tip_collapsed):
    """Add the row or column farthest from the current chords while the budget allows.

    Returns the largest distance (cm) of a data point from the chords when it stops.
    """
    gridt = grid.transpose(1, 0, 2)
    row_all = _split_errors(grid, rows)
    col_all = _split_errors(gridt, cols)
    while True:
        row_fits = count_triangles(rows.sum() + 1, cols.sum(), tip_collapsed) <= budget
        col_fits = count_triangles(rows.sum(), cols.sum() + 1, tip_collapsed) <= budget
        residual = max(row_all.max(), col_all.max())
        row_err = row_all if row_fits else np.zeros_like(row_all)
        col_err = col_all if col_fits else np.zeros_like(col_all)
        i, j = int(np.argmax(row_err)), int(np.argmax(col_err))
        if max(row_err[i], col_err[j]) <= 1e-9:
            return residual
        if row_err[i] >= col_err[j]:
            rows[i] = True
            row_all = _split_errors(grid, rows)     # row errors depend on the kept rows only
        else:
            cols[j] = True
            col_all = _split_errors(gridt, cols)


def select_lines(grid: np.ndarray, budget: int, tip_collapsed: bool) -> Selection:
    """Choose rows and columns of a standard grid (m, n, 3) for at most ``budget`` triangles.

    The splitting is run twice, from the collar, tip and margins alone and with the midrib
    added first; the midrib run is kept unless it leaves a data point farther from the mesh.

    Raises
    ------
    ValueError
        If even collar + tip x two margins exceeds the budget.
    """
    m, n = grid.shape[:2]
    least = count_triangles(2, 2, tip_collapsed)
    if budget < least:
        raise ValueError(f"a budget of {budget} triangles is below the coarsest mesh of this leaf "
                         f"({least}: collar to tip, margin to margin)")
    best: tuple[float, np.ndarray, np.ndarray] | None = None
    seeds = [False]
    if n >= 3 and count_triangles(2, 3, tip_collapsed) <= budget:
        seeds.append(True)
    for midrib in seeds:
        rows = np.zeros(m, dtype=bool)
        cols = np.zeros(n, dtype=bool)
        rows[[0, -1]] = True
        cols[[0, -1]] = True
        cols[n // 2] |= midrib
        residual = _greedy(grid, rows, cols, budget, tip_collapsed)
        if best is None or residual <= best[0] + 1e-9:
            best = (residual, rows, cols)
    assert best is not None                          # seeds always holds False
    return Selection(np.flatnonzero(best[1]), np.flatnonzero(best[2]))


def _midrib(grid: np.ndarray) -> np.ndarray:
    """Midrib point of each cross-section: (m, n, 3) -> (m, 3)."""
    n = grid.shape[1]
    if n % 2:
        return grid[:, n // 2]
    return 0.5 * (grid[:, n // 2 - 1] + grid[:, n // 2])


def _area(vertices: np.ndarray) -> float:
    a, b = vertices.shape[:2]
    return float(triangle_areas_normals(vertices.reshape(-1, 3), grid_faces(a, b))[0].sum())


def widen_to_area(vertices: np.ndarray, centres: np.ndarray, target: float,
                  max_iter: int = 30) -> tuple[np.ndarray, float]:
    """Scale each row's offsets from its centre by one factor s so the mesh area is ``target``.

    Parameters
    ----------
    vertices : (a, b, 3) float64, cm
    centres : (a, 3) float64, cm
    target : float, cm2

    Returns
    -------
    scaled vertices (a, b, 3), the factor s
    """
    offsets = vertices - centres[:, None, :]

    def f(s):
        return _area(centres[:, None, :] + s * offsets) - target

    s0, s1 = 1.0, target / max(_area(vertices), 1e-300)
    f0, f1 = f(s0), f(s1)
    for _ in range(max_iter):
        if abs(f1) <= 1e-10 * target or f1 == f0:
            break
        s0, s1, f0 = s1, max(s1 - f1 * (s1 - s0) / (f1 - f0), 1e-6), f1
        f1 = f(s1)
    return centres[:, None, :] + s1 * offsets, s1


def simplify(grid: np.ndarray, u: np.ndarray, v: np.ndarray, budget: int, tip_collapsed: bool,
             target_area: float | None = None, plant: int = -1, leaf: int = -1) -> LeafMesh:
    """Mesh of at most ``budget`` triangles from the standard grid.

    Parameters
    ----------
    grid : (m, n, 3) float64, cm: the digitized points (standard mesh vertices)
    u : (m,), v : (n,) float64: their surface parameters
    budget : int, at least 1 (collapsed tip) or 2
    target_area : float, cm2, optional
        When given, widths are rescaled so the mesh has this area (see module docstring).
    """
    sel = select_lines(grid, budget, tip_collapsed)
    sub = grid[np.ix_(sel.rows, sel.cols)]
    label = f"{budget} triangles"
    if target_area is not None and (len(sel.rows) < grid.shape[0] or len(sel.cols) < grid.shape[1]):
        sub, _ = widen_to_area(sub, _midrib(grid)[sel.rows], target_area)
    return mesh_grid(sub, u[sel.rows], v[sel.cols], label, plant, leaf)
