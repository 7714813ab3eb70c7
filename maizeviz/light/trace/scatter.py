"""Absorbed light with scattering: Monte Carlo ray tracing of a parallel beam (the sun, or one
direction of a sky) through the canopy, leaves and ground reflecting and transmitting as
:class:`~maizeviz.light.trace.optics.Optics` say.

The beam's rays are the ground rays of the direct-light computation
(:func:`~maizeviz.light.trace.beam.trace_direction`): a regular grid over the sample
rectangle, each ray carrying the beam's power over its footprint. Each ray is followed:

- at a leaf it deposits the share ``1 - reflectance - transmittance`` of what it carries on
  that triangle; it goes on, with probability ``reflectance + transmittance`` (Russian
  roulette: its expected power is what the leaf scatters), reflected (to the side it came
  from) or transmitted (to the other side) in proportion, in a cosine-distributed direction
  about the leaf's normal;
- on the ground (z = 0) it deposits ``1 - ground_reflectance`` of it and goes on upward with
  probability ``ground_reflectance``;
- above the canopy top going up, it is reflected out of the canopy; in an open field, leaving
  the plot sideways, it escapes; in a periodic field it re-enters on the opposite side;
- after ``depth`` scatterings, or once the power still travelling is below ``threshold`` of
  the incident power, what remains is reported as unresolved.

Deposits are exact expectations; only the choice to go on is random, so with every optical
value 0 nothing goes on and the leaves absorb exactly what the direct-light computation
intercepts, ray for ray. The energy balance (incident = absorbed by leaves + absorbed by the
ground + reflected out of the top + escaped sideways + unresolved) holds in expectation; its
closure is within Monte Carlo noise (about ``sqrt(k)/N`` of the incident for ``k`` scattering
events and ``N`` rays).

References
----------
Dutre, P., Bekaert, P. & Bala, K. (2006). Advanced Global Illumination, 2nd ed., A K Peters
(Russian roulette, cosine-weighted sampling of a Lambertian surface).
Chelle, M. & Andrieu, B. (1998). The nested radiosity model for the distribution of light
within plant canopies. Ecological Modelling 111, 75-91 (Caribu: Lambertian leaves, periodic
canopy).
Bailey, B. N. (2018). A reverse ray-tracing method for modelling the net radiative flux in
leaf-resolving plant canopy simulations. Ecological Modelling 368, 233-245 (Helios).
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

import numpy as np

from maizeviz.light.results.uncertainty import BATCHES
from maizeviz.light.scene.rays import ray_grid
from maizeviz.light.trace.beam import Sampler, trace_direction
from maizeviz.light.trace.optics import Optics
from maizeviz.progress import ProgressCallback, ordered_map, report

#: Default largest number of scatterings followed per ray.
DEFAULT_DEPTH = 20
#: Default share of the incident power still travelling below which tracing stops.
DEFAULT_THRESHOLD = 1e-4
#: Distance (cm) a scattered ray starts off its surface (Embree starts at t = 0).
EPS_CM = 1e-3
#: Primary rays followed together (bounded memory: a few arrays of this length).
CHUNK_RAYS = 1 << 19


@dataclass
class Tally:
    """What one beam's rays deposited, in units of one primary ray's power.

    Attributes
    ----------
    leaf_hits : list of int64 arrays, the triangle of every ray's arrival at a leaf (each
        deposits ``1 - scattering`` there)
    first_hits : list of int64 arrays, the triangles the primary rays hit (sunlit area)
    ground, top, sides, unresolved : float, absorbed by the ground, reflected out of the
        canopy top, escaped sideways (open field), still travelling when tracing stopped
    rays : primary rays; events : scatterings followed
    leaf_batch, first_batch : int8 arrays beside ``leaf_hits`` and ``first_hits``: the batch
        of the primary ray each arrival descends from
    """

    leaf_hits: list = field(default_factory=list)
    first_hits: list = field(default_factory=list)
    leaf_batch: list = field(default_factory=list)
    first_batch: list = field(default_factory=list)
    #: ground, top, sides, unresolved by batch: (4, BATCHES) float64
    parts_batch: np.ndarray = field(default_factory=lambda: np.zeros((4, BATCHES)))
    ground: float = 0.0
    top: float = 0.0
    sides: float = 0.0
    unresolved: float = 0.0
    rays: int = 0
    events: int = 0

    def add(self, other: Tally) -> None:
        self.leaf_hits += other.leaf_hits
        self.first_hits += other.first_hits
        self.leaf_batch += other.leaf_batch
        self.first_batch += other.first_batch
        self.parts_batch = self.parts_batch + other.parts_batch
        for name in ("ground", "top", "sides", "unresolved", "rays", "events"):
            setattr(self, name, getattr(self, name) + getattr(other, name))

    def per_triangle(self, n_triangles: int, absorbed_share: float) -> np.ndarray:
        """(F,) float64: what each triangle absorbed (``absorbed_share`` of each arrival)."""
        ids = np.concatenate(self.leaf_hits) if self.leaf_hits else np.empty(0, np.int64)
        return np.bincount(ids, minlength=n_triangles) * absorbed_share

    def per_batch(self, n_triangles: int, weight: float | np.ndarray, first: bool = False):
        """(BATCHES, F) scipy.sparse CSR array: what each batch's rays deposited on each
        triangle, ``weight`` per arrival (a number, or (F,) per triangle); ``first``: the
        primary hits only. Rows sum to :meth:`per_triangle`'s (for the same weight)."""
        from scipy.sparse import csr_array

        hits, batch = (self.first_hits, self.first_batch) if first else \
            (self.leaf_hits, self.leaf_batch)
        ids = np.concatenate(hits) if hits else np.empty(0, np.int64)
        bat = np.concatenate(batch).astype(np.int64) if batch else np.empty(0, np.int64)
        w = np.broadcast_to(np.asarray(weight, np.float64), (n_triangles,))[ids] \
            if np.ndim(weight) else np.full(len(ids), float(weight))
        out = csr_array((w, (bat, ids)), shape=(BATCHES, n_triangles))
        out.sum_duplicates()
        return out

    def sunlit(self, n_triangles: int, area_factor: np.ndarray) -> np.ndarray:
        """(F,) float64 cm2 in the direct beam: primary hits times each triangle's
        ``area_factor`` (cm2 of leaf per ray)."""
        ids = np.concatenate(self.first_hits) if self.first_hits else np.empty(0, np.int64)
        return np.bincount(ids, minlength=n_triangles) * area_factor


def lambertian(normals: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Directions (M, 3) drawn with a cosine distribution about unit ``normals`` (M, 3)."""
    m = len(normals)
    u1, u2 = rng.random(m), rng.random(m)
    r, phi = np.sqrt(u1), 2.0 * np.pi * u2
    helper = np.where(np.abs(normals[:, :1]) > 0.9, [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]])
    t1 = np.cross(normals, helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(normals, t1)
    return (r * np.cos(phi))[:, None] * t1 + (r * np.sin(phi))[:, None] * t2 + \
        np.sqrt(1.0 - u1)[:, None] * normals


@dataclass
class _Rays:
    """Rays travelling: origins (k, 3) cm, unit directions (k, 3), the batch (k,) int8 of
    the primary ray each descends from."""

    org: np.ndarray
    dirs: np.ndarray
    batch: np.ndarray


LEAF, GROUND, TOP, SIDES, LOST = range(5)


def follow(smp: Sampler, rays: _Rays, max_crossings: int = 1000
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where each ray ends: what it met (LEAF, GROUND, TOP, SIDES, LOST), the triangle (leaf
    and stalk ids, -1 unless LEAF) and the end point (k, 3) cm. In a periodic field rays are
    wrapped across the plot (:func:`~maizeviz.light.scene.periodic.trace_wrapped`, as the
    direct-light rays are); one that has not met anything after ``max_crossings`` plot widths
    sideways is LOST."""
    k = len(rays.org)
    kind = np.full(k, LOST, dtype=np.int8)
    prim = np.full(k, -1, dtype=np.int64)
    o = rays.org.astype(np.float64)
    d = rays.dirs.astype(np.float64)
    end = o.copy()
    with np.errstate(divide="ignore", invalid="ignore"):
        t_vert = np.where(d[:, 2] < 0, -o[:, 2] / d[:, 2],
                          np.where(d[:, 2] > 0, (smp.top - o[:, 2]) / d[:, 2], np.inf))
    t_vert = np.maximum(t_vert, 0.0)
    x0, y0, x1, y1 = smp.bounds
    if smp.periodic:
        from maizeviz.light.scene.periodic import Wrap, trace_wrapped

        scene = smp.scene
        wrap = getattr(scene, "wrap", None) or Wrap.of(smp.bounds)
        horiz = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-300)
        cap = max_crossings * max(x1 - x0, y1 - y0) / horiz      # distance of that many plots
        length = np.minimum(t_vert, cap)
        ids, cell, t = trace_wrapped(scene, wrap, o, d, length)
        hit = np.isfinite(t)
        resolve = getattr(scene, "resolve", None)
        assert ids is not None
        prim[hit] = ids[hit] if resolve is None else resolve(ids[hit], cell[hit])
        t_side = np.where(t_vert <= cap, np.inf, 0.0)          # LOST unless it ends vertically
    else:
        lo, hi = np.array([x0, y0]), np.array([x1, y1])
        with np.errstate(divide="ignore", invalid="ignore"):
            t_side = np.full(k, np.inf)
            for a in (0, 1):
                edge = np.where(d[:, a] > 0, hi[a], lo[a])
                ta = np.where(d[:, a] != 0, (edge - o[:, a]) / d[:, a], np.inf)
                t_side = np.minimum(t_side, ta)
        t_side = np.maximum(t_side, 0.0)
        seg = np.minimum(t_vert, t_side)
        ids32, t32 = smp.scene.first_hit(o, d, seg)
        hit = ids32 >= 0
        source = getattr(smp.scene, "source", None)
        prim[hit] = ids32[hit] if source is None else source[ids32[hit]]
        t = np.where(hit, t32.astype(np.float64), np.inf)
    kind[hit] = LEAF
    end[hit] = o[hit] + t[hit, None] * d[hit]
    vertical = ~hit & (t_vert <= t_side) & np.isfinite(t_vert)
    kind[vertical] = np.where(d[vertical, 2] < 0, GROUND, TOP)
    end[vertical] = o[vertical] + t_vert[vertical, None] * d[vertical]
    side = ~hit & ~vertical & np.isfinite(t_side) & (not smp.periodic)
    kind[side] = SIDES
    end[side] = o[side] + t_side[side, None] * d[side]
    return kind, prim, end


def _bounce(smp: Sampler, optics: Optics, normals: np.ndarray, tally: Tally, rng,
            kind: np.ndarray, prim: np.ndarray, end: np.ndarray, dirs: np.ndarray,
            batch: np.ndarray, leaf_optics: tuple | None = None) -> _Rays:
    """Deposit what rays ending at leaves and the ground absorb, count those leaving, and draw
    the rays that go on (Russian roulette on the scattering coefficient); ``leaf_optics``:
    (reflectance, transmittance) per triangle (F,) when leaves differ by rank."""
    leaf = kind == LEAF
    sc = optics.scattering
    if leaf_optics is not None or sc < 1.0:
        tally.leaf_hits.append(prim[leaf])
        tally.leaf_batch.append(batch[leaf])
    ground = kind == GROUND
    tally.ground += np.count_nonzero(ground) * (1.0 - optics.ground_reflectance)
    tally.top += np.count_nonzero(kind == TOP)
    tally.sides += np.count_nonzero(kind == SIDES)
    tally.unresolved += np.count_nonzero(kind == LOST)
    for row, (what, share) in enumerate(((ground, 1.0 - optics.ground_reflectance),
                                         (kind == TOP, 1.0), (kind == SIDES, 1.0),
                                         (kind == LOST, 1.0))):
        if what.any():
            tally.parts_batch[row] += np.bincount(batch[what], minlength=BATCHES) * share
    parts_o, parts_d, parts_b = [], [], []
    go = np.flatnonzero(leaf)
    if leaf_optics is not None:
        rho_t, tau_t = leaf_optics[0][prim[go]], leaf_optics[1][prim[go]]
        sc_t = rho_t + tau_t
        keep = rng.random(len(go)) < sc_t
        go, rho_go = go[keep], rho_t[keep] / np.where(sc_t[keep] > 0, sc_t[keep], 1.0)
    else:
        go = go[rng.random(len(go)) < sc] if sc > 0 else go[:0]
        rho_go = optics.reflectance / sc if sc > 0 else 0.0
    if len(go):
        n = normals[prim[go]]
        facing = np.einsum("ij,ij->i", n, dirs[go])             # < 0: hit the front side
        back = np.where(facing < 0, 1.0, -1.0)[:, None] * n     # the side the ray came from
        reflect = rng.random(len(go)) < rho_go
        side = np.where(reflect[:, None], back, -back)
        parts_o.append(end[go] + EPS_CM * side)
        parts_d.append(lambertian(side, rng))
        parts_b.append(batch[go])
    up = np.flatnonzero(ground)
    rg = optics.ground_reflectance
    up = up[rng.random(len(up)) < rg] if rg > 0 else up[:0]
    if len(up):
        zplus = np.tile([0.0, 0.0, 1.0], (len(up), 1))
        o = end[up].copy()
        o[:, 2] = EPS_CM
        parts_o.append(o)
        parts_d.append(lambertian(zplus, rng))
        parts_b.append(batch[up])
    if not parts_o:
        return _Rays(np.empty((0, 3)), np.empty((0, 3)), np.empty(0, np.int8))
    return _Rays(np.vstack(parts_o), np.vstack(parts_d), np.concatenate(parts_b))


def _scatter_on(smp: Sampler, optics: Optics, normals: np.ndarray, tally: Tally, rng,
                rays: _Rays, depth: int, least: float, leaf_optics: tuple | None) -> None:
    """Follow scattered ``rays`` for up to ``depth`` more scatterings, or until no more than
    ``least`` are still travelling; what is left is unresolved."""
    for _ in range(depth):
        if len(rays.org) <= least:
            break
        tally.events += len(rays.org)
        kind, prim, end = follow(smp, rays)
        rays = _bounce(smp, optics, normals, tally, rng, kind, prim, end, rays.dirs,
                       rays.batch, leaf_optics)
    tally.unresolved += len(rays.org)
    if len(rays.org):
        tally.parts_batch[3] += np.bincount(rays.batch, minlength=BATCHES)


def scatter_beam(smp: Sampler, toward: np.ndarray, optics: Optics, normals: np.ndarray,
                 depth: int = DEFAULT_DEPTH, threshold: float = DEFAULT_THRESHOLD,
                 seed: int = 0, threads: int = 1, progress: ProgressCallback | None = None,
                 stop: threading.Event | None = None,
                 leaf_optics: tuple | None = None) -> tuple[Tally, dict[str, float]]:
    """Follow one parallel beam through the canopy (see the module docstring).

    Parameters
    ----------
    smp : Sampler of the canopy (scene, sample rectangle and density, plot, periodic field)
    toward : (3,) unit vector toward the light, z > 0
    optics : Optics of the band
    normals : (F, 3) unit normals of the scene's leaf and stalk triangles (their ids)
    depth : most scatterings followed per ray; threshold : share of the incident power still
        travelling below which tracing stops (the rest is unresolved)
    seed : of the random generator (one stream per chunk of rays: the same numbers whatever
        ``threads``)
    leaf_optics : (reflectance, transmittance) of every triangle, (F,) each, when leaves
        differ by rank (:meth:`~maizeviz.light.trace.optics.Optics.per_triangle`); None: ``optics``

    Returns
    -------
    Tally in units of one primary ray's power, and seconds spent ("trace": the primary beam,
    "scatter": the rest).
    """
    t0 = time.perf_counter()
    s = np.asarray(toward, dtype=np.float64)
    primary = trace_direction(smp, s, ids=True, threads=threads, stop=stop)
    t1 = time.perf_counter()
    n = smp.n
    chunks = [(a, min(a + CHUNK_RAYS, n)) for a in range(0, n, CHUNK_RAYS)]
    first_prim = primary.first_prim
    assert first_prim is not None
    # primary rays dealt into equal batches at random (the same whatever ``threads``)
    batches = (np.random.default_rng([seed, 0xBA7C]).permutation(n) % BATCHES).astype(np.int8)

    def chunk(k_ab: tuple[int, tuple[int, int]]) -> Tally:
        k, (a, b) = k_ab
        rng = np.random.default_rng([seed, k])
        tally = Tally(rays=b - a)
        prim = first_prim[a:b].astype(np.int64)
        z = primary.first_z[a:b].astype(np.float64)
        g = ray_grid(smp.rect, smp.density, a, b)[0]
        hit = prim >= 0
        kind = np.where(hit, LEAF, GROUND).astype(np.int8)
        end = np.empty((b - a, 3))
        height = np.where(hit, z, 0.0)
        end[:, :2] = g + s[:2] * (height / s[2])[:, None]
        end[:, 2] = height
        tally.first_hits.append(prim[hit])
        batch = batches[a:b]
        tally.first_batch.append(batch[hit])
        dirs = np.broadcast_to(-s, (b - a, 3))
        rays = _bounce(smp, optics, normals, tally, rng, kind, prim, end, dirs, batch,
                       leaf_optics)
        _scatter_on(smp, optics, normals, tally, rng, rays, depth, threshold * (b - a),
                    leaf_optics)
        return tally

    total = Tally()

    def done(k: int) -> None:
        report(progress, k, len(chunks), "scattering")

    for part in ordered_map(chunk, list(enumerate(chunks)), threads, done, stop):
        total.add(part)
    return total, {"trace": t1 - t0, "scatter": time.perf_counter() - t1}


def scatter_sky(smp: Sampler, directions: np.ndarray, weights: np.ndarray, optics: Optics,
                normals: np.ndarray, depth: int = DEFAULT_DEPTH,
                threshold: float = DEFAULT_THRESHOLD, seed: int = 0, threads: int = 1,
                passes: int = 1, stop: threading.Event | None = None,
                leaf_optics: tuple | None = None) -> tuple[Tally, dict[str, float]]:
    """Follow a whole sky's diffuse light through a periodic canopy, each primary ray in a
    sky direction of its own: ``passes`` rays per cell of the sample grid, their directions
    dealt in proportion to the sky's ``weights`` (stratified, then shuffled over the cells).

    Each ray carries the same power (the sky's horizontal irradiance over its footprint, over
    ``passes``): drawing a direction with probability ``weight`` makes that unbiased. Tracing
    every direction over the whole grid (:func:`scatter_beam` per direction) costs as many
    times more primary rays as the sky has directions; this costs one beam's, for a Monte Carlo
    error the batches report.

    Parameters
    ----------
    smp : Sampler of a periodic field; directions : (K, 3) unit vectors toward the sky
    weights : (K,) shares of the horizontal diffuse irradiance (sum 1)
    optics, normals, depth, threshold, seed, threads, stop, leaf_optics : as
        :func:`scatter_beam`
    passes : primary rays per grid cell

    Returns
    -------
    Tally in units of one primary ray's power, and seconds ("trace": 0, "scatter": all).
    """
    if not smp.periodic:
        raise ValueError("a sky sampled per ray needs a periodic field")
    t0 = time.perf_counter()
    dirs_k = np.asarray(directions, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    n_cells = smp.n
    n = n_cells * passes
    rng0 = np.random.default_rng([seed, 0x5C1])
    # stratified: each direction gets its share of the rays (largest remainders), shuffled
    want = w / w.sum() * n
    counts = np.floor(want).astype(np.int64)
    rest = n - int(counts.sum())
    if rest:
        counts[np.argsort(want - counts)[::-1][:rest]] += 1
    which = rng0.permutation(np.repeat(np.arange(len(w)), counts))
    batches = (rng0.permutation(n) % BATCHES).astype(np.int8)
    chunks = [(a, min(a + CHUNK_RAYS, n)) for a in range(0, n, CHUNK_RAYS)]
    grid = ray_grid(smp.rect, smp.density)[0]

    def chunk(k_ab: tuple[int, tuple[int, int]]) -> Tally:
        k, (a, b) = k_ab
        rng = np.random.default_rng([seed, k, 0x5C1])
        tally = Tally(rays=b - a)
        g = grid[np.arange(a, b) % n_cells]
        s = dirs_k[which[a:b]]
        # start on the plane above the canopy, on the line through the grid point toward the
        # sky direction, going down along it
        org = np.empty((b - a, 3))
        org[:, :2] = g + s[:, :2] * (smp.top / s[:, 2])[:, None]
        org[:, 2] = smp.top
        batch = batches[a:b]
        kind, prim, end = follow(smp, _Rays(org, -s, batch))
        hit = kind == LEAF
        tally.first_hits.append(prim[hit])
        tally.first_batch.append(batch[hit])
        rays = _bounce(smp, optics, normals, tally, rng, kind, prim, end, -s, batch,
                       leaf_optics)
        _scatter_on(smp, optics, normals, tally, rng, rays, depth, threshold * (b - a),
                    leaf_optics)
        return tally

    total = Tally()
    for part in ordered_map(chunk, list(enumerate(chunks)), threads, None, stop):
        total.add(part)
    return total, {"trace": 0.0, "scatter": time.perf_counter() - t0}
