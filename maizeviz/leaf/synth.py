"""Parametric maize leaves and plants that look digitized (docs/method.md, "A synthetic maize plant").

Used to make realistic test grids, benchmarks and the bundled example. A leaf is a midrib
curve with a two-part curvature law, the Prevot width profile, a V-shaped cross-section, margin
waves in opposite phase growing toward the tip, and FASTRAK noise (0.08 cm RMS). Grids follow
the column convention of docs/method.md: col 0 is the right margin seen from above with the tip
ahead, so dS/du x dS/dv points out of the upper face; the tip row collapses to one point.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from maizeviz.errors import check_range
from maizeviz.leaf.grid import LeafGrid

DIGITIZER_NOISE_CM = 0.08

#: Plants a synthetic block may hold: a hectare at 7 plants per m2 (70,000 plants, 72 million
#: points, about 18 minutes to make); written plant by plant, memory follows one row group.
MAX_SYNTH_PLANTS = 100_000


def prevot_width(s: np.ndarray, a: float = -2.3) -> np.ndarray:
    """Relative leaf width r(s) at relative distance s from the collar (Prevot et al. 1991).

    r(0) = 0.733, r(1) = 0, peak 1 near s = 0.34, integral 0.75 for a = -2.3.
    """
    b = -2.0 * (a + np.sqrt(-a))
    c = 2.0 * np.sqrt(-a) + a
    return np.clip(a * s**2 + b * s + c, 0.0, None)


@dataclass(frozen=True)
class LeafShape:
    """Parameters of one synthetic leaf.

    Lengths in cm, angles in degrees. ``azimuth_deg`` is the horizontal direction the blade
    points to, counter-clockwise from +x; ``insertion_deg`` the angle of the blade base from the
    vertical; ``curvature_deg`` the extra declination reached at the tip.
    """

    length: float = 90.0
    width: float = 9.0
    base: tuple[float, float, float] = (0.0, 0.0, 100.0)
    azimuth_deg: float = 0.0
    insertion_deg: float = 35.0
    curvature_deg: float = 70.0
    fold_deg: float = 15.0
    wave_amplitude: float = 0.6
    wave_length: float = 9.0
    twist_deg: float = 0.0


def midrib(shape: LeafShape, s: np.ndarray, samples: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """Midrib points (k, 3) cm and unit tangents (k, 3) at relative arc lengths s (k,).

    Declination from the vertical: theta(s) = theta0 + g(s) Delta with the two-section law
    g(s) = (1 + c) s^2 / (1 + c s^2), c = -0.2 up to 2/3 of the curvature and c = 5 after.
    """
    fine = np.linspace(0.0, 1.0, samples)
    g = 0.8 * fine**2 / (1.0 - 0.2 * fine**2)                      # c = -0.2
    s_break = np.sqrt((2 / 3) / (0.8 + 0.2 * 2 / 3))               # g reaches 2/3 here
    x = np.clip((fine - s_break) / (1.0 - s_break), 0.0, 1.0)
    g = np.where(fine <= s_break, g, 2 / 3 + (1 / 3) * 6.0 * x**2 / (1.0 + 5.0 * x**2))  # c = 5
    theta = np.radians(shape.insertion_deg + g * shape.curvature_deg)
    phi = np.radians(shape.azimuth_deg)
    tangent = np.column_stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                               np.cos(theta)])
    step = shape.length / (samples - 1)
    pos = np.concatenate([[[0.0, 0.0, 0.0]],
                          np.cumsum(0.5 * (tangent[1:] + tangent[:-1]) * step, axis=0)])
    pos += np.asarray(shape.base, dtype=np.float64)
    pts = np.column_stack([np.interp(s, fine, pos[:, k]) for k in range(3)])
    tan = np.column_stack([np.interp(s, fine, tangent[:, k]) for k in range(3)])
    return pts, tan / np.linalg.norm(tan, axis=1, keepdims=True)


def leaf_points(shape: LeafShape, rows: int = 13, cols: int = 5, noise: float = DIGITIZER_NOISE_CM,
                rng: np.random.Generator | None = None) -> np.ndarray:
    """A digitized-looking grid (rows, cols, 3) cm; the tip row is one point repeated.

    Cross-sections are denser toward the tip, as technicians digitize the narrowing part more
    finely.
    """
    if rows < 2 or cols < 2:
        raise ValueError("a leaf needs at least 2 rows and 2 cols")
    rng = rng or np.random.default_rng()
    s = 1.0 - (1.0 - np.linspace(0.0, 1.0, rows)) ** 1.15
    centre, tangent = midrib(shape, s)
    phi = np.radians(shape.azimuth_deg)
    right = np.array([np.sin(phi), -np.cos(phi), 0.0])
    twist = np.radians(shape.twist_deg) * s
    up = np.cross(right, tangent)
    up /= np.linalg.norm(up, axis=1, keepdims=True)
    side = np.cos(twist)[:, None] * right + np.sin(twist)[:, None] * up
    up = np.cross(side, tangent)
    half = 0.5 * shape.width * prevot_width(s)
    lateral = 1.0 - 2.0 * np.arange(cols) / (cols - 1)             # +1 right margin .. -1 left
    off = half[:, None] * lateral[None, :]                          # (rows, cols) cm
    fold = -np.tan(np.radians(shape.fold_deg)) * np.abs(off)
    wave = (shape.wave_amplitude * s[:, None] ** 1.5 * np.abs(lateral)[None, :]
            * np.sin(2 * np.pi * s[:, None] * shape.length / shape.wave_length
                     + np.where(lateral >= 0, 0.0, np.pi)[None, :]))
    pts = (centre[:, None, :] + off[..., None] * side[:, None, :]
           + (fold + wave)[..., None] * up[:, None, :])
    pts[-1] = centre[-1]
    if noise > 0:
        jitter = rng.normal(0.0, noise, pts.shape)
        jitter[-1] = jitter[-1, 0]
        pts = pts + jitter
    return pts


@dataclass(frozen=True)
class PlantShape:
    """A maize plant at silking: leaf size by rank on a skewed bell curve, ~180 deg phyllotaxy.

    The defaults give about 245 cm height (tassel included), 16 leaves and 0.94 m2 of leaf
    area, the plant of the paper's canopy.
    """

    leaves: int = 16
    height: float = 245.0
    top_insertion: float = 200.0
    max_length: float = 100.0
    max_width: float = 12.5
    max_rank: float = 11.0
    azimuth_deg: float = 90.0
    phyllotaxy_sd_deg: float = 30.0


def plant_leaf_shapes(plant: PlantShape, base=(0.0, 0.0, 0.0),
                      rng: np.random.Generator | None = None) -> list[LeafShape]:
    """One :class:`LeafShape` per rank (1 = lowest) for a plant standing at ``base`` (cm)."""
    rng = rng or np.random.default_rng()
    n = plant.leaves
    r = np.arange(1, n + 1)
    rel = (r - 0.5) / n
    height = 3.0 + (plant.top_insertion - 3.0) * rel**1.6
    sd = np.where(r < plant.max_rank, 6.0, 5.0)
    bell = np.exp(-0.5 * ((r - plant.max_rank) / sd) ** 2)
    length = plant.max_length * bell * rng.normal(1.0, 0.04, n)
    wsd = np.where(r < plant.max_rank, 4.5, 7.0)
    width = plant.max_width * (0.3 + 0.7 * np.exp(-0.5 * ((r - plant.max_rank) / wsd) ** 2))
    width = width * rng.normal(1.0, 0.04, n)
    insertion = 40.0 - 20.0 * rel + rng.normal(0, 4, n)
    curvature = 20.0 + 30.0 * (1 - rel) + rng.normal(0, 8, n)
    azimuth = (plant.azimuth_deg + 180.0 * (r % 2) + rng.normal(0, plant.phyllotaxy_sd_deg, n))
    bx, by, bz = base
    return [LeafShape(length=float(length[i]), width=float(width[i]),
                      base=(bx, by, bz + float(height[i])), azimuth_deg=float(azimuth[i]),
                      insertion_deg=float(insertion[i]), curvature_deg=float(curvature[i]),
                      wave_length=float(rng.uniform(7, 11)),
                      wave_amplitude=float(rng.uniform(0.3, 0.9)))
            for i in range(n)]


def plant_grids(plant_id: int, plant: PlantShape = PlantShape(), base=(0.0, 0.0, 0.0),
                rows: int = 13, cols: int = 5, noise: float = DIGITIZER_NOISE_CM,
                rng: np.random.Generator | None = None) -> list[LeafGrid]:
    """Digitized-looking grids of every leaf of one plant (leaf ids = rank from the base).

    Short lower leaves get fewer cross-sections, as a technician would digitize them.
    """
    rng = rng or np.random.default_rng()
    out = []
    for rank, shape in enumerate(plant_leaf_shapes(plant, base, rng), start=1):
        m = int(np.clip(round(rows * min(1.0, shape.length / 60.0)), 5, rows))
        pts = leaf_points(shape, m, cols, noise, rng)
        out.append(LeafGrid(plant_id, rank, pts, True, tuple(range(m)), ()))
    return out


def example_leaf(rows: int = 13, cols: int = 5, seed: int = 0, **kwargs) -> np.ndarray:
    """A realistic 90 cm ear-leaf grid (rows, cols, 3) for tests and benchmarks."""
    shape = replace(LeafShape(), **kwargs)
    return leaf_points(shape, rows, cols, rng=np.random.default_rng(seed))


def block_grids(rows: int = 3, plants_per_row: int = 3, row_spacing: float = 60.0,
                plant_spacing: float = 30.0, seed: int = 0, plant: PlantShape = PlantShape(),
                grid_rows: int = 13, grid_cols: int = 5) -> list[LeafGrid]:
    """A digitized block: rows along y at x = (i + 1/2) row_spacing, plants at
    y = (j + 1/2) plant_spacing, stalks off their nominal place by about 1 cm, each plant's
    leaf plane turned at random (field maize shows no strong preference at 60 x 30 cm), plant
    ids 1.. row by row as a technician walks them.
    """
    return [g for plant_leaves in iter_block_grids(rows, plants_per_row, row_spacing,
                                                   plant_spacing, seed, plant, grid_rows,
                                                   grid_cols)
            for g in plant_leaves]


def iter_block_grids(rows: int = 3, plants_per_row: int = 3, row_spacing: float = 60.0,
                     plant_spacing: float = 30.0, seed: int = 0, plant: PlantShape = PlantShape(),
                     grid_rows: int = 13, grid_cols: int = 5):
    """:func:`block_grids` plant by plant: yields each plant's list of leaf grids, so that a
    field is written without holding it."""
    check_range(rows * plants_per_row, "a synthetic block's plants", 1, MAX_SYNTH_PLANTS,
                "plants", whole=True)
    check_range(row_spacing, "the row spacing", 1, 1e4, "row_spacing", unit="cm")
    check_range(plant_spacing, "the plant spacing", 1, 1e4, "plant_spacing", unit="cm")
    check_range(seed, "the random seed", 0, 2**32 - 1, "seed", whole=True)
    check_range(grid_rows, "cross-sections of a long leaf", 2, 200, "sections", whole=True)
    check_range(grid_cols, "points per cross-section", 2, 51, "points_across", whole=True)
    rng = np.random.default_rng(seed)
    pid = 1
    for i in range(rows):
        for j in range(plants_per_row):
            base = ((i + 0.5) * row_spacing + rng.normal(0, 1.0),
                    (j + 0.5) * plant_spacing + rng.normal(0, 1.0), 0.0)
            shape = replace(plant, azimuth_deg=float(rng.uniform(0.0, 360.0)),
                            leaves=int(plant.leaves + rng.integers(-1, 2)),
                            max_length=float(plant.max_length * rng.normal(1.0, 0.03)))
            yield plant_grids(pid, shape, base, grid_rows, grid_cols, rng=rng)
            pid += 1
