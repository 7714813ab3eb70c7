"""Diffuse light from the sky and light over a day or a period, on one Embree scene.

Every direction, a sky element or the sun at a time step, is traced exactly like the sun of
:func:`~maizeviz.light.trace.beam.trace_light`: parallel rays landing on the ground rectangle
(first hits: light intercepted per triangle) and sensor planes at each height (transmission),
with the same periodic wrap. The scene is built once and shared by every direction; directions
run in parallel on ``threads`` threads (Embree releases the GIL), and ``progress(done, total)``
is called after each direction, in order (returning ``False`` cancels with InterruptedError).

Diffuse light (:func:`trace_sky`): a :class:`~maizeviz.light.sources.sky.Sky` of n directions with
weights w_i (each direction's share of the horizontal diffuse irradiance, summing to 1) gives

    T_diffuse(h) = sum_i w_i T_i(h),   share of triangle t = sum_i w_i hits_i(t) / N,

where N is the number of rays per direction: the share is the fraction of the rectangle's
horizontal diffuse light that the triangle intercepts (first hits; light scattered by leaves is
not followed).

A period (:func:`trace_period`, a :class:`~maizeviz.light.sources.irradiance.Period`): step j carries a
direct PAR dose D_j and a diffuse dose S_j (mol/m2 of ground, midpoint rule); the sun is traced
at each step, the sky once for the whole period. Per step,

    transmitted_j(h) = D_j T_sun_j(h) + S_j T_diffuse(h)
    intercepted_j    = D_j f_sun_j + S_j f_diffuse        (f: leaves' share of the beam)

and the period's totals are the exactly rounded sums (math.fsum) of its steps. Intercepted PAR
per triangle in mol is its share times the dose times the rectangle's area.

An anisotropic diffuse sky (``diffuse``, a :class:`~maizeviz.light.sources.perez.DiffuseSplit` from
Perez's model): the diffuse dose of step j is split into a circumsolar part C_j, traced with the
sun of that step, and an isotropic part I_j = S_j - C_j, spread over the directions of a uniform
sky traced once (the horizon band brings nothing through a horizontal plane). Sky direction i
then carries the weight (I_j / S_j) w_i of step j's diffuse light and the sun the weight
C_j / S_j: the weights change per step but the sky's directions keep their proportions, so the
uniform sky's sums (transmission, shares per triangle, maps) are reused and nothing is traced
beyond today's sky and suns. Per step,

    transmitted_j(h) = (D_j + C_j) T_sun_j(h) + I_j T_sky(h)
    intercepted_j    = (D_j + C_j) f_sun_j + I_j f_sky
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.layout import stands_identity
from maizeviz.errors import MaizevizError
from maizeviz.light.results.diffuse import PeriodLight, SkyLight
from maizeviz.light.results.maps import bin_edges, binned, binned_grid
from maizeviz.light.scene.request import (
    LightRequest,
    Sampling,
    canopy_top,
    check_sampling,
    edge_reach,
)
from maizeviz.light.sources.irradiance import Period
from maizeviz.light.sources.perez import DiffuseSplit
from maizeviz.light.sources.sky import Sky
from maizeviz.light.trace.beam import Sampler, sampler, scene_for, trace_direction
from maizeviz.mesh.raytrace import RayScene
from maizeviz.progress import ProgressCallback, ordered_map, report

# --------------------------------------------------------------------------- one beam


@dataclass(frozen=True)
class _Beam:
    """What is kept of one traced direction (the rays themselves are dropped)."""

    transmission: np.ndarray          # (H,)
    leaf_fraction: float              # leaves' first hits / N
    ids: np.ndarray                   # (k,) int64, triangles with first hits
    hits: np.ndarray                  # (k,) int64, their first-hit counts
    lit_bins: np.ndarray              # (H, a, b) float64, lit fraction per bin (NaN: no sensor)
    seconds: float


def _sparse_counts(prim: np.ndarray, n_triangles: int) -> tuple[np.ndarray, np.ndarray]:
    hit = prim[prim >= 0]
    if n_triangles <= 8 * len(prim):
        dense = np.bincount(hit, minlength=n_triangles)
        ids = np.flatnonzero(dense)
        return ids.astype(np.int64), dense[ids].astype(np.int64)
    ids, counts = np.unique(hit, return_counts=True)
    return ids.astype(np.int64), counts.astype(np.int64)


def _beam(smp: Sampler, toward: np.ndarray, edges: tuple[np.ndarray, np.ndarray],
          ground_xy: tuple[np.ndarray, np.ndarray], stop: threading.Event) -> _Beam:
    tr = trace_direction(smp, toward, ids=True, stop=stop)
    assert tr.first_prim is not None
    prim = tr.first_prim
    leaf = np.count_nonzero((prim >= 0) & (prim < smp.n_leaf_triangles)) / smp.n
    ids, hits = _sparse_counts(prim, smp.n_triangles)
    xe, ye = edges
    bins = np.empty((len(smp.heights_cm), len(xe) - 1, len(ye) - 1))
    xs, ys = ground_xy
    for k in range(len(smp.heights_cm)):
        lit = np.unpackbits(tr.sensor_lit[k], count=smp.n).view(bool)
        off = tr.sensor_offset_cm[k]
        counts, lit_counts = binned_grid(xs + off[0], ys + off[1], lit, xe, ye)
        with np.errstate(invalid="ignore", divide="ignore"):
            bins[k] = np.where(counts > 0, lit_counts / counts, np.nan)
    return _Beam(tr.transmission, float(leaf), ids, hits, bins, tr.seconds["trace"])


def _beams(smp: Sampler, towards: Sequence[np.ndarray], threads: int,
           progress: ProgressCallback | None, edges: tuple[np.ndarray, np.ndarray],
           what: str) -> Iterator[_Beam]:
    """Trace ``towards`` (each (3,), toward the light) on ``threads`` threads; yields the beams
    in order, calling ``progress(done, total)`` after each."""
    from maizeviz.light.scene.rays import grid_shape, ray_grid

    grid = ray_grid(smp.rect, smp.density)[0]
    nx, ny = grid_shape(smp.rect, smp.density)
    ground_xy = (grid[::ny, 0].copy(), grid[:ny, 1].copy())     # the grid's columns and rows
    stop = threading.Event()
    return ordered_map(lambda s: _beam(smp, s, edges, ground_xy, stop), towards, threads,
                       lambda k: report(progress, k, len(towards), what), stop)


# --------------------------------------------------------------------------- entry points


@dataclass(frozen=True)
class _Bins:
    edges: tuple[np.ndarray, np.ndarray]
    rays: np.ndarray                  # (a, b) int64, ground-grid sensors per bin


def _prepare(canopy: Canopy, sampling: Sampling | LightRequest, with_stalks: bool,
             scene: RayScene | None, bin_cm: float) -> tuple[Sampler, list[str], float, _Bins]:
    from maizeviz.light.scene.rays import ray_grid

    if isinstance(sampling, LightRequest):
        sampling = sampling.sampling
    rect, warnings = check_sampling(canopy, sampling)
    xe, ye = bin_edges(rect, bin_cm)
    xy = ray_grid(rect, sampling.density)[0]
    counts, _ = binned(xy, np.ones(len(xy)), xe, ye)
    bins = _Bins((xe, ye), counts.astype(np.int64))
    t0 = time.perf_counter()
    scene, said = scene_for(canopy, sampling.periodic, scene, with_stalks)
    warnings += said
    build_s = time.perf_counter() - t0
    smp = sampler(canopy, scene, rect, sampling.density, sampling.heights_cm, sampling.periodic,
                  with_stalks)
    return smp, warnings, build_s, bins


def _edge_warning(canopy: Canopy, smp: Sampler, zenith: np.ndarray, towards: np.ndarray,
                  what: str) -> str | None:
    """One warning for all directions whose paths cross the plot edge (non-periodic field)."""
    if smp.periodic or not len(zenith):
        return None
    top = canopy_top(canopy)
    crossing = [z for z, s in zip(zenith, towards) if edge_reach(canopy, smp.rect, float(z), s,
                                                                 top) is not None]
    if not crossing:
        return None
    return (f"{len(crossing)} of {len(zenith)} {what} (zenith {min(crossing):.0f} deg and lower) "
            "reach the sample rectangle across the plot edge, where nothing stops them; "
            "transmission is overestimated (trace a periodic field)")


def _sky_light(sky: Sky, smp: Sampler, beams: list[_Beam], bins: _Bins, level: str,
               warnings: list[str], seconds: dict[str, float], stands: dict) -> SkyLight:
    edges = bins.edges
    w = np.asarray(sky.weights, dtype=np.float64)
    per_dir = np.array([b.transmission for b in beams]).reshape(sky.n, len(smp.heights_cm))
    per_int = np.array([b.leaf_fraction for b in beams])
    share = np.zeros(smp.n_triangles)
    maps = np.zeros((len(smp.heights_cm), len(edges[0]) - 1, len(edges[1]) - 1))
    for wi, b in zip(w, beams):
        np.add.at(share, b.ids, wi * b.hits / smp.n)
        maps += wi * b.lit_bins
    trans = np.array([math.fsum(w * per_dir[:, k]) for k in range(per_dir.shape[1])])
    return SkyLight(sky=sky, heights_cm=smp.heights_cm, transmission=np.clip(trans, 0.0, 1.0),
                    per_direction=per_dir, intercepted_fraction=math.fsum(w * per_int),
                    per_direction_intercepted=per_int, triangle_share=share, rect=smp.rect,
                    rays=smp.n, density=smp.density, maps=maps, map_edges=edges,
                    map_rays=bins.rays, level=level, warnings=tuple(warnings), seconds=seconds,
                    periodic=smp.periodic, stands=stands)


def trace_sky(canopy: Canopy, sky: Sky, sampling: Sampling | LightRequest,
              progress: ProgressCallback | None = None, with_stalks: bool = False,
              scene: RayScene | None = None, bin_cm: float = 5.0) -> SkyLight:
    """Diffuse light: every direction of ``sky`` traced like the sun on one scene.

    Parameters
    ----------
    canopy : Canopy
    sky : Sky from :func:`maizeviz.light.sources.sky.make_sky`
    sampling : heights, density, rectangle, periodic field and threads (a :class:`Sampling`, or
        a :class:`LightRequest` whose sun is ignored)
    progress : ``progress(done, total)`` after each direction; returning ``False`` cancels
        with InterruptedError
    scene : the canopy's scene from :func:`~maizeviz.light.scene.embree_scenes.light_scene` (same
        ``with_stalks`` and ``periodic``); built here when not given
    bin_cm : bin edge of the maps, cm

    Raises
    ------
    MaizevizError
        A bad request (as :func:`maizeviz.light.scene.request.check_sampling`), naming the quantity.
    """
    smp, warnings, build_s, bins = _prepare(canopy, sampling, with_stalks, scene, bin_cm)
    towards = sky.field_directions(canopy.layout.north_deg)
    w = _edge_warning(canopy, smp, sky.zenith_deg, towards, "sky directions")
    if w:
        warnings.append(w)
    t0 = time.perf_counter()
    beams = list(_beams(smp, list(towards), sampling.threads, progress, bins.edges,
                        "sky tracing"))
    seconds = {"build": build_s, "trace": time.perf_counter() - t0}
    return _sky_light(sky, smp, beams, bins, canopy.level, warnings, seconds,
                      stands_identity(canopy.layout))


def trace_period(canopy: Canopy, period: Period, sampling: Sampling | LightRequest,
                 sky: Sky | SkyLight | None = None, progress: ProgressCallback | None = None,
                 with_stalks: bool = False, scene: RayScene | None = None,
                 bin_cm: float = 5.0, diffuse: DiffuseSplit | None = None) -> PeriodLight:
    """Light over a period: the sun traced at every step, the sky once; see the module docstring.

    Parameters
    ----------
    canopy : Canopy
    period : Period from :func:`maizeviz.light.sources.irradiance.clear_sky_period` or
        :func:`~maizeviz.light.sources.irradiance.weather_period`
    sampling : heights, density, rectangle, periodic field and threads
    sky : the Sky for the diffuse part (traced here, its directions and the sun steps sharing
        the threads), or a SkyLight already traced on this canopy with the same sampling
        (reused: a sweep over days traces its sky once); None for the standard overcast
        turtle of 46 directions
    progress : ``progress(done, total)`` after each direction (sky directions first, then the
        time steps); returning ``False`` cancels with InterruptedError
    scene : the canopy's scene (same ``with_stalks`` and ``periodic``); built here when not given
    bin_cm : bin edge of the maps, cm
    diffuse : each step's diffuse light split by Perez's model
        (:func:`maizeviz.light.sources.perez.perez_split` of ``period``): its circumsolar part is traced
        with the sun of the step, the rest spread over ``sky``, which must then be a uniform
        sky ("uoc"; default: the uniform turtle of 46 directions); None spreads the whole
        diffuse part over ``sky``

    Returns
    -------
    PeriodLight; a period without sun (polar night) traces nothing and gives zeros (its
    ``period.notes`` say so).
    """
    from maizeviz.light.sources.sky import make_sky

    if diffuse is not None and (diffuse.n_steps != period.n_steps or not np.allclose(
            diffuse.dhi_w_m2, period.dhi, rtol=1e-9, atol=1e-9)):
        raise MaizevizError("the diffuse split is not this period's: its steps or its diffuse "
                            "irradiance differ (split the period itself)", quantity="sky")
    smp, warnings, build_s, bins = _prepare(canopy, sampling, with_stalks, scene, bin_cm)
    stands = stands_identity(canopy.layout)
    edges = bins.edges
    warnings += list(period.notes)
    n_h = len(smp.heights_cm)
    shape = (n_h, len(edges[0]) - 1, len(edges[1]) - 1)
    zeros = np.zeros(smp.n_triangles)
    if period.n_steps == 0:
        return PeriodLight(period=period, sky=None, heights_cm=smp.heights_cm,
                           step_transmission=np.zeros((0, n_h)),
                           step_intercepted_fraction=np.zeros(0), triangle_direct_mol=zeros,
                           triangle_diffuse_mol=zeros.copy(), rect=smp.rect, rays=smp.n,
                           maps=np.full(shape, np.nan), map_edges=edges, map_rays=bins.rays,
                           level=canopy.level, warnings=tuple(warnings),
                           seconds={"build": build_s, "trace": 0.0}, periodic=smp.periodic,
                           diffuse=diffuse, stands=stands)
    sky_light = sky if isinstance(sky, SkyLight) else None
    if sky_light is not None:
        if not (np.array_equal(sky_light.heights_cm, smp.heights_cm)
                and sky_light.rect == smp.rect and sky_light.rays == smp.n):
            raise MaizevizError("the sky light was traced with other heights, rectangle or "
                                "density than this period", quantity="sky")
        if sky_light.stands is not None and sky_light.stands != stands:
            raise MaizevizError("the sky light was traced on other stands than this canopy's "
                                f"({sky_light.stands.get('n')} plants, this canopy "
                                f"{stands['n']}): trace the sky on this canopy", quantity="sky")
    sky_obj = sky_light.sky if sky_light is not None else \
        (sky if isinstance(sky, Sky) else make_sky("soc" if diffuse is None else "uoc", 46))
    if diffuse is not None and sky_obj.kind != "uoc":
        raise MaizevizError(f"Perez's isotropic part is spread over a uniform sky, not a "
                            f"{sky_obj.kind} sky: trace the period with a uoc sky",
                            quantity="sky")
    north = canopy.layout.north_deg
    suns = period.suns()
    sun_dirs = [s.direction(north) for s in suns]
    sky_dirs = [] if sky_light is not None else list(sky_obj.field_directions(north))
    for zen, dirs, what in ((np.array([s.zenith_deg for s in suns]), np.array(sun_dirs),
                             "time steps' suns"),
                            (sky_obj.zenith_deg, sky_obj.field_directions(north),
                             "sky directions")):
        w = _edge_warning(canopy, smp, zen, dirs, what)
        if w and w not in warnings:
            warnings.append(w)
    t0 = time.perf_counter()
    beams = list(_beams(smp, sky_dirs + sun_dirs, sampling.threads, progress, edges,
                        "period tracing"))
    trace_s = time.perf_counter() - t0
    if sky_light is None:
        sky_light = _sky_light(sky_obj, smp, beams[:len(sky_dirs)], bins, canopy.level, [],
                               {"build": 0.0, "trace": trace_s}, stands)
    steps = beams[len(sky_dirs):]
    direct_mol = np.asarray(period.step_direct_par_mol_m2, dtype=np.float64)
    step_diffuse = np.asarray(period.step_diffuse_par_mol_m2, dtype=np.float64)
    circ_mol = step_diffuse * diffuse.circumsolar_share if diffuse is not None else \
        np.zeros(len(steps))
    diffuse_mol = math.fsum(step_diffuse - circ_mol)        # spread over the sky
    area_m2 = (smp.rect[2] - smp.rect[0]) * (smp.rect[3] - smp.rect[1]) * 1e-4
    tri_direct = np.zeros(smp.n_triangles)
    for dose, b in zip(direct_mol, steps):
        np.add.at(tri_direct, b.ids, dose * area_m2 * b.hits / smp.n)
    tri_diffuse = sky_light.triangle_share * diffuse_mol * area_m2
    for dose, b in zip(circ_mol, steps):
        if dose > 0:
            np.add.at(tri_diffuse, b.ids, dose * area_m2 * b.hits / smp.n)
    incident = math.fsum(period.step_par_mol_m2)
    maps = sky_light.maps * diffuse_mol
    for dose, b in zip(direct_mol + circ_mol, steps):
        maps = maps + dose * b.lit_bins
    maps = maps / incident if incident > 0 else np.full(shape, np.nan)
    return PeriodLight(
        period=period, sky=sky_light, heights_cm=smp.heights_cm,
        step_transmission=np.array([b.transmission for b in steps]).reshape(len(steps), n_h),
        step_intercepted_fraction=np.array([b.leaf_fraction for b in steps]),
        triangle_direct_mol=tri_direct, triangle_diffuse_mol=tri_diffuse, rect=smp.rect,
        rays=smp.n, maps=maps, map_edges=edges, map_rays=bins.rays, level=canopy.level,
        warnings=tuple(warnings), seconds={"build": build_s, "trace": trace_s},
        periodic=smp.periodic, diffuse=diffuse, stands=stands)
