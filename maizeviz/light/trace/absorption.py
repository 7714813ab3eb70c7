"""Light absorbed with scattering by the leaves and the ground: the sun's direct beam and the
directions of a sky, each followed through the canopy by :func:`~.scatter.scatter_beam`, summed
into an energy balance and the power each triangle absorbs (:func:`absorbed_light`); and over a
period (:func:`absorbed_period`), the sky traced once per W/m2 and scaled by each step's
diffuse irradiance (the transport is linear in the light put in), each step's sun traced with
its direct irradiance.

Every beam of an instant carries its irradiance over the sample rectangle's rays: a ray of a
beam of ``E`` W/m2 carries ``E x ray area`` W, and deposits ``1 - scattering`` of what it
carries at each leaf it reaches (:mod:`.scatter`).

References
----------
Bailey, B. N. (2018). A reverse ray-tracing method for modelling the net radiative flux in
leaf-resolving plant canopy simulations. Ecological Modelling 368, 233-245.
https://doi.org/10.1016/j.ecolmodel.2017.11.022
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.layout import stands_identity
from maizeviz.errors import check_range
from maizeviz.light.results.absorbed import AbsorbedLight, AbsorbedPeriod, Balance
from maizeviz.light.results.uncertainty import BATCHES, Batches
from maizeviz.light.sources.irradiance import Period
from maizeviz.light.sources.perez import PEREZ_MODELS, perez_split
from maizeviz.light.sources.sky import Sky
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.beam import Sampler
from maizeviz.light.trace.optics import Optics, band_share
from maizeviz.light.trace.scatter import scatter_beam, scatter_sky
from maizeviz.light.trace.sunlit import geometry, sunlit_share
from maizeviz.progress import ProgressCallback, report

if TYPE_CHECKING:
    from maizeviz.photosynthesis.split import LeafModel


#: Primary rays per grid cell of a sky traced with its directions drawn per ray.
SKY_PASSES = 4


def check_absorbed(direct_w_m2: float, diffuse_w_m2: float, depth: int,
                   threshold: float) -> None:
    """Refuse, naming the quantity, an irradiance outside 0-5000 W/m2, a depth that is not a
    whole number in 0-10,000 or a threshold outside [0, 1] (MaizevizError)."""
    check_range(direct_w_m2, "the direct irradiance (W/m2)", 0, 5000, "irradiance")
    check_range(diffuse_w_m2, "the diffuse irradiance (W/m2)", 0, 5000, "irradiance")
    check_range(depth, "the scattering depth", 0, 10_000, "depth", whole=True)
    check_range(threshold, "the scattering threshold", 0, 1, "threshold")


def absorbed_light(canopy: Canopy, smp: Sampler, normals: np.ndarray, optics: Optics,
                   sun: Sun | None, direct_w_m2: float, diffuse_w_m2: float, sky: Sky | None,
                   depth: int, threshold: float, seed: int, threads: int = 1,
                   progress: ProgressCallback | None = None,
                   build_s: float = 0.0, sky_passes: int = SKY_PASSES) -> AbsorbedLight:
    """Light absorbed in one band at one instant: the sun's beam and a sky's directions.

    Parameters
    ----------
    canopy : Canopy
        The canopy of the scene (its north, leaf ranks and mesh level).
    smp : Sampler
        The scene, sample rectangle, density and field (:func:`~.beam.sampler`).
    normals : (F, 3) float64
        Unit normals of the scene's leaf triangles, then its stalks' if traced.
    optics : Optics
        The band's leaf and soil optics.
    sun : Sun or None
        The sun's angles; None: no direct beam.
    direct_w_m2, diffuse_w_m2 : float
        The band's direct and diffuse irradiance on a horizontal plane above the canopy
        [W m-2]; the diffuse part is spread over ``sky`` (needed when it is > 0).
    sky : Sky or None
        The sky of the diffuse part.
    depth, threshold, seed : int, float, int
        Scatterings followed, share of the incident power left travelling where tracing stops,
        random seed (beam ``k`` uses ``seed + 7919 k``).
    threads : int
        Threads over chunks of rays.
    progress : callable, optional
        ``progress(done, total, what)`` after each beam.
    build_s : float
        Seconds spent building the scene for this call [s] (reported as ``seconds["build"]``).
    sky_passes : int
        With leaves or soil that scatter, in a periodic field, the diffuse light is traced as
        one beam whose rays each take a sky direction of their own
        (:func:`~.scatter.scatter_sky`), this many rays per grid cell (0: every sky direction
        traced over the whole grid, as black leaves are).

    Returns
    -------
    AbsorbedLight
        Its balance in W/m2 of sample ground, the W absorbed by each scene triangle (and the
        part the direct beam deposited), the per-batch shares the standard errors come from.
    """
    opt = optics
    beams: list[tuple[np.ndarray, float]] = []
    if sun is not None and direct_w_m2 > 0:
        beams.append((sun.direction(canopy.layout.north_deg), direct_w_m2))
    # leaves that scatter, in a periodic field: the sky's directions are drawn per ray
    # (one beam's rays, ``sky_passes`` per cell) instead of each traced over the grid
    sky_per_ray = diffuse_w_m2 > 0 and smp.periodic and sky_passes > 0 and (
        opt.scattering > 0 or opt.ground_reflectance > 0 or bool(opt.ranks))
    n_sky = 0
    if diffuse_w_m2 > 0:
        assert sky is not None
        n_sky = len(sky.weights)
        if not sky_per_ray:
            for toward, weight in zip(sky.directions, sky.weights):
                beams.append((np.asarray(toward, np.float64), diffuse_w_m2 * float(weight)))
    area_m2 = smp.ray_area_cm2 * 1e-4 * smp.n
    nf = len(normals)
    leaf_optics, kept = None, 1.0 - opt.scattering
    if opt.ranks:                                # leaves differ by rank (stalks: 0)
        rank = np.zeros(nf, np.int64)
        rank[:canopy.n_triangles] = canopy.face_leaf
        leaf_optics = opt.per_triangle(rank)
        kept = 1.0 - (leaf_optics[0] + leaf_optics[1])
    absorbed, sunlit, direct_t = np.zeros(nf), np.zeros(nf), np.zeros(nf)
    from scipy.sparse import csr_array  # 0.3 s to import, pulls numpy.f2py: when used

    empty = csr_array((BATCHES, nf))
    absorbed_b, direct_b, sunlit_b = empty, empty, empty
    sun_dir = None
    parts_b = np.zeros((4, BATCHES))
    parts = dict.fromkeys(("ground", "top", "sides", "unresolved"), 0.0)
    events, seconds = 0, {"build": build_s, "trace": 0.0, "scatter": 0.0}
    for k, (toward, irradiance) in enumerate(beams):
        tally, secs = scatter_beam(smp, toward, opt, normals, depth, threshold,
                                   seed + 7919 * k, threads,
                                   leaf_optics=leaf_optics)
        per_ray = irradiance * smp.ray_area_cm2 * 1e-4       # W carried by one ray
        absorbed += tally.per_triangle(nf, kept * per_ray)
        absorbed_b = absorbed_b + tally.per_batch(nf, kept * per_ray)
        if k == 0 and sun is not None and direct_w_m2 > 0:
            # the direct beam each triangle absorbs: its sampled sunlit share of what its
            # whole area intercepts at the beam's flux (bounded by construction, see
            # .sunlit), in place of the primary rays' deposits, which the scattering still
            # starts from
            hits = _first_hits(tally, nf)
            cos = np.abs(np.einsum("ij,j->i", normals, toward))     # no BLAS thread pool
            share = sunlit_share(smp, canopy, normals, toward, seed + 7919 * k, hits, cos)
            area = geometry(canopy, nf).area_cm2
            whole = (kept * irradiance / toward[2] * 1e-4) * cos * area
            rays_w = hits * (kept * per_ray)               # as Tally.per_triangle counts them
            rays_b = tally.per_batch(nf, kept * per_ray, first=True)
            direct_t, direct_b = _matched(share.fraction * whole, csr_array(
                share.batches * whole), whole, rays_w, rays_b, canopy.n_triangles)
            absorbed += direct_t - rays_w
            absorbed_b = absorbed_b - rays_b + direct_b
            fraction = np.divide(direct_t, whole, out=np.zeros(nf), where=whole > 0)
            sunlit = fraction * area
            # cm2 per W of each triangle, at the few columns the batches store
            sunlit_b = csr_array(direct_b, copy=True)
            col = sunlit_b.indices
            sunlit_b.data *= np.divide(area[col], whole[col], out=np.zeros(len(col)),
                                       where=whole[col] > 0)
            sunlit_b.eliminate_zeros()
            sun_dir = (float(toward[0]), float(toward[1]), float(toward[2]))
        for name in parts:
            parts[name] += getattr(tally, name) * per_ray
        parts_b += tally.parts_batch * per_ray
        events += tally.events
        seconds["trace"] += secs["trace"]
        seconds["scatter"] += secs["scatter"]
        report(progress, k + 1, len(beams) + sky_per_ray, "absorbed light")
    if sky_per_ray:
        assert sky is not None
        tally, secs = scatter_sky(smp, np.asarray(sky.directions, np.float64),
                                  np.asarray(sky.weights, np.float64), opt, normals, depth,
                                  threshold, seed + 7919 * len(beams), threads, sky_passes,
                                  leaf_optics=leaf_optics)
        per_ray = diffuse_w_m2 * smp.ray_area_cm2 * 1e-4 / sky_passes
        absorbed += tally.per_triangle(nf, kept * per_ray)
        absorbed_b = absorbed_b + tally.per_batch(nf, kept * per_ray)
        for name in parts:
            parts[name] += getattr(tally, name) * per_ray
        parts_b += tally.parts_batch * per_ray
        events += tally.events
        seconds["scatter"] += secs["scatter"]
        report(progress, len(beams) + 1, len(beams) + 1, "absorbed light")
    incident = direct_w_m2 * (sun is not None) + diffuse_w_m2
    leaves = canopy.n_triangles                  # the stalks' triangles follow, if traced
    balance = Balance(float(incident), float(absorbed[:leaves].sum()) / area_m2,
                      float(parts["ground"]) / area_m2, float(parts["top"]) / area_m2,
                      float(parts["sides"]) / area_m2, float(parts["unresolved"]) / area_m2,
                      float(absorbed[leaves:].sum()) / area_m2)
    return AbsorbedLight(opt.band, opt, incident, balance, absorbed, sunlit, smp.rect, smp.n,
                         len(beams) + (n_sky if sky_per_ray else 0), depth, threshold, seed,
                         events, smp.periodic, canopy.level, seconds,
                         triangle_direct_w=direct_t,
                         batches=Batches(absorbed_b, direct_b, sunlit_b, parts_b / area_m2),
                         sun_direction=sun_dir, stands=stands_identity(canopy.layout))


def _matched(direct: np.ndarray, direct_b, whole: np.ndarray, rays_w: np.ndarray, rays_b,
             n_leaf: int) -> tuple[np.ndarray, Any]:
    """The sampled direct beam of each triangle (F,) W and its batches (BATCHES, F), made to
    add up, over the leaves and over the stalks, to what the primary rays deposited there
    (``rays_w``, ``rays_b``), every triangle kept within ``[0, whole]``.

    The two totals estimate the same thing; the rays' is a regular grid's, less noisy, and
    keeps the energy balance closing as the rays trace it. A sampled total below the rays' is
    raised in proportion to each triangle's room below its whole area's beam, one above is
    lowered in proportion; the change is the two estimates' difference, noise."""
    from scipy.sparse import csr_array

    out = direct.copy()
    add = np.zeros_like(direct)
    scale = [1.0, 1.0]                              # of the leaves', the stalks' sampled beam
    for k, part in enumerate((slice(0, n_leaf), slice(n_leaf, len(direct)))):
        got, want = float(direct[part].sum()), float(rays_w[part].sum())
        if want > got:
            room = whole[part] - direct[part]
            total = float(room.sum())
            add[part] = room * min(1.0, (want - got) / total) if total > 0 else 0.0
        elif got > 0:
            scale[k] = want / got
            out[part] *= scale[k]
    # the batches: the sampled rows scaled as their triangles (their few stored values), the
    # raise dealt as the rays'
    rows = csr_array(direct_b, copy=True)
    rows.data *= np.where(rows.indices < n_leaf, scale[0], scale[1])
    rows.eliminate_zeros()
    per_batch = np.asarray(rays_b.sum(axis=1)).ravel()
    ids = np.flatnonzero(add)
    if len(ids) and per_batch.sum() > 0:
        # each triangle's raise in one batch, drawn as the rays' batches carry the beam
        pick = np.random.default_rng(len(ids)).choice(len(per_batch), len(ids),
                                                      p=per_batch / per_batch.sum())
        rows = rows + csr_array((add[ids], (pick, ids)), shape=rows.shape)
    return out + add, csr_array(rows)


def _first_hits(tally, nf: int) -> np.ndarray:
    """(F,) int64: how many primary rays hit each triangle first."""
    ids = np.concatenate(tally.first_hits) if tally.first_hits else np.empty(0, np.int64)
    return np.bincount(ids, minlength=nf)


def period_temperatures(period: Period, temperature_c) -> np.ndarray:
    """Air (leaf) temperature of each step of ``period``, C (n,): a weather file's own
    (``Period.temp_air``, where finite), else ``temperature_c`` (one, or one per step);
    MaizevizError naming the temperature when they do not fit."""
    from maizeviz.errors import MaizevizError

    steps = len(period.step_s)
    temps = np.asarray(temperature_c, np.float64)
    if temps.ndim > 1 or temps.size not in (1, steps) or not np.all(np.isfinite(temps)):
        raise MaizevizError(f"give one air temperature or one for each of the period's "
                            f"{steps} steps (finite, C), got {temps.size}",
                            quantity="temperature")
    temps = np.broadcast_to(temps.reshape(-1), (steps,)) if temps.size == 1 else temps
    given = getattr(period, "temp_air", None)          # a weather file's air temperature
    if given is not None and len(given) == steps:
        temps = np.where(np.isfinite(given), np.asarray(given, np.float64), temps)
    return np.array(temps, dtype=np.float64)


def band_irradiance(period: Period, band: str, share: float) -> tuple[np.ndarray, np.ndarray]:
    """The band's direct and diffuse irradiance on the horizontal at each step of ``period``.

    PAR is the PAR the intercepted period takes (:attr:`Period.step_direct_par_mol_m2` and
    :attr:`Period.step_diffuse_par_mol_m2`): a weather file's measured PAR where it has one
    (split as the shortwave is), else the shortwave times the PAR factor (split by the
    period's own PAR split where it has one), turned into watts of PAR at 4.57 umol per J
    (:data:`~maizeviz.light.sources.irradiance.PAR_UMOL_PER_J_PAR`). Another band is
    ``share`` of the shortwave.

    Parameters
    ----------
    period : Period
        Its steps' irradiance (and measured PAR, if any).
    band : {"par", "nir"}
        The waveband.
    share : float
        The band's share of the shortwave (:func:`~.optics.band_share`), for a band other than
        PAR.

    Returns
    -------
    direct_w, diffuse_w : (n,) float64, W/m2 of the band's energy on the horizontal
    """
    from maizeviz.light.sources.irradiance import PAR_UMOL_PER_J_PAR

    if band == "par":
        to_w = 1e6 / (np.asarray(period.step_s, np.float64) * PAR_UMOL_PER_J_PAR)
        return (np.asarray(period.step_direct_par_mol_m2, np.float64) * to_w,
                np.asarray(period.step_diffuse_par_mol_m2, np.float64) * to_w)
    ghi, dhi = np.asarray(period.ghi, np.float64), np.asarray(period.dhi, np.float64)
    return (ghi - dhi) * share, dhi * share


def absorbed_period(period: Period, optics: Optics, sky: Sky | str,
                    absorbed: Callable[..., AbsorbedLight],
                    progress: ProgressCallback | None = None, canopy: Canopy | None = None,
                    photosynthesis: LeafModel | None = None,
                    temperature_c=25.0) -> AbsorbedPeriod:
    """Light absorbed in one band over a period: the diffuse part traced once per W/m2 over
    ``sky`` and scaled by each step's diffuse irradiance, each step's sun with the band's share
    of its direct irradiance; with a leaf model, the leaves' gross CO2 assimilation at every
    step (each step's light through the model at that step's temperature).

    Parameters
    ----------
    period : Period
        Its steps, sun and irradiance; its PAR factor sets the band's share of shortwave
        (:func:`~.optics.band_share`); PAR is a weather file's measured PAR where it has one,
        as the intercepted period's (:func:`band_irradiance`).
    optics : Optics
        The band's leaf and soil optics.
    sky : Sky or str
        The diffuse light's sky (kind or Sky); "perez" (or "perez-driesse") splits each step's
        diffuse light by Perez's model (:mod:`maizeviz.light.sources.perez`): its circumsolar
        part added to that step's direct beam, the rest from a uniform sky.
    absorbed : callable
        ``absorbed(sun, direct_w_m2=..., diffuse_w_m2=..., sky=...)`` -> AbsorbedLight of one
        instant on the canopy (``LightEngine.absorbed`` with the band, optics, sampling and
        scattering settings bound).
    progress : callable, optional
        Called after the sky and after each step.
    canopy : Canopy
        The canopy traced (needed with ``photosynthesis``).
    photosynthesis : LeafModel, optional
        A leaf model (:mod:`maizeviz.photosynthesis`); PAR only.
    temperature_c : float or (n,) float64
        Air (leaf) temperature, C: one, or one per step (:func:`period_temperatures`).

    Returns
    -------
    AbsorbedPeriod
        Its balance in MJ/m2 of sample ground, the J absorbed by each scene triangle, the
        per-batch shares of those, and ``assimilation`` (a
        :class:`~maizeviz.light.results.assimilation.PeriodAssimilation`) with a leaf model.
    """
    share = band_share(optics.band, period.par_umol_per_j)
    steps = len(period.step_s)
    temps = period_temperatures(period, temperature_c) if photosynthesis is not None \
        else np.zeros(steps)
    model = str(sky).strip().lower() if isinstance(sky, str) else ""
    split = perez_split(period, model) if model in PEREZ_MODELS else None
    unit = absorbed(None, direct_w_m2=0.0, diffuse_w_m2=1.0,
                    sky="uoc" if split is not None else sky)
    report(progress, 1, steps + 1, "absorbed light: the sky")
    sun_w, diffuse_w = band_irradiance(period, optics.band, share)
    circumsolar_w = np.zeros(steps)
    if split is not None:                   # the circumsolar part comes with the sun
        dhi = np.asarray(period.dhi, np.float64)
        scale = np.divide(diffuse_w, dhi, out=np.zeros(steps), where=dhi > 0)
        circumsolar_w = np.asarray(split.circumsolar_w_m2, np.float64) * scale
        diffuse_w = np.where(dhi > 0, np.asarray(split.isotropic_w_m2, np.float64) * scale,
                             diffuse_w)
    step_s = np.asarray(period.step_s, np.float64)
    joules = unit.triangle_absorbed_w * float(np.sum(diffuse_w * step_s))
    ub_ = unit.batches
    assert ub_ is not None
    joules_b = ub_.absorbed * float(np.sum(diffuse_w * step_s))
    parts_b = (ub_.parts if ub_.parts is not None else np.zeros((4, BATCHES))) * float(
        np.sum(diffuse_w * step_s))
    carbon = _Carbon(canopy, photosynthesis, unit, diffuse_w, step_s, temps)
    ub = unit.balance
    parts = {k: getattr(ub, k) * float(np.sum(diffuse_w * step_s))
             for k in ("absorbed_leaves", "absorbed_ground", "reflected_top",
                       "escaped_sides", "unresolved", "absorbed_stalks")}
    leaves_w = ub.absorbed_leaves * diffuse_w
    seconds = dict(unit.seconds)
    direct_w = sun_w + circumsolar_w
    for k in range(steps):
        z = float(period.zenith_deg[k])
        if direct_w[k] > 0 and z < 90.0:
            light = absorbed(Sun(z, float(period.azimuth_deg[k])),
                             direct_w_m2=float(direct_w[k]))
            joules += light.triangle_absorbed_w * step_s[k]
            assert light.batches is not None
            joules_b = joules_b + light.batches.absorbed * step_s[k]
            if light.batches.parts is not None:
                parts_b = parts_b + light.batches.parts * step_s[k]
            carbon.add(k, light)
            for name in parts:
                parts[name] += getattr(light.balance, name) * step_s[k]
            leaves_w[k] += light.balance.absorbed_leaves
            for name in ("trace", "scatter"):
                seconds[name] = seconds.get(name, 0.0) + light.seconds.get(name, 0.0)
        elif diffuse_w[k] > 0:
            carbon.add(k, None)
        report(progress, k + 2, steps + 1, f"absorbed light: time step {k + 1} of {steps}")
    incident_w = diffuse_w + direct_w
    balance = Balance(float(np.sum(incident_w * step_s)) * 1e-6,
                      *(float(parts[k]) * 1e-6 for k in ("absorbed_leaves", "absorbed_ground",
                                                   "reflected_top", "escaped_sides",
                                                   "unresolved", "absorbed_stalks")))
    return AbsorbedPeriod(optics.band, optics, period, balance, joules, leaves_w, incident_w,
                          unit.rect, unit.rays, unit.depth, unit.seed, unit.periodic,
                          unit.level, seconds,
                          batches=Batches(joules_b, None, None, parts_b * 1e-6),
                          assimilation=carbon.result(), stands=unit.stands)


class _Carbon:
    """A period's gross assimilation, step by step: each step's light (its sun, if any, and
    the sky's unit light scaled by its diffuse irradiance) through the leaf model."""

    def __init__(self, canopy, model, unit: AbsorbedLight, diffuse_w, step_s, temps):
        self.canopy, self.model, self.unit = canopy, model, unit
        self.diffuse_w, self.step_s, self.temps = diffuse_w, step_s, temps
        self.step_gross = np.zeros(len(step_s))
        if model is not None:
            if canopy is None:
                raise TypeError("photosynthesis over a period needs the canopy")
            n = canopy.n_triangles
            self.mol, self.mol_b = np.zeros(n), np.zeros((BATCHES, n))
            self.bias, self.bias_se = 0.0, 0.0

    def add(self, k: int, light: AbsorbedLight | None) -> None:
        if self.model is None:
            return
        from maizeviz.light.results.assimilation import assimilate

        unit, dw = self.unit, float(self.diffuse_w[k])
        ub = unit.batches
        assert ub is not None
        if light is None:
            step = replace(unit, triangle_absorbed_w=unit.triangle_absorbed_w * dw,
                           batches=Batches(ub.absorbed * dw, ub.direct, ub.sunlit_cm2))
        else:
            lb = light.batches
            assert lb is not None
            step = replace(light, triangle_absorbed_w=light.triangle_absorbed_w
                           + unit.triangle_absorbed_w * dw,
                           batches=Batches(lb.absorbed + ub.absorbed * dw, lb.direct,
                                           lb.sunlit_cm2))
        a = assimilate(self.canopy, step, self.model, float(self.temps[k]))
        self.mol += a.triangle_gross_umol_s * self.step_s[k] * 1e-6
        if a.triangle_batches is not None:
            self.mol_b += a.triangle_batches * self.step_s[k] * 1e-6
        if a.bias_umol_s is not None:
            # the steps share the sky's rays: their biases' spreads add up, not in quadrature
            self.bias += a.bias_umol_s * self.step_s[k] * 1e-6
            self.bias_se += (a.bias_se_umol_s or 0.0) * self.step_s[k] * 1e-6
        self.step_gross[k] = a.canopy_gross_umol_m2_s

    def result(self):
        if self.model is None:
            return None
        from maizeviz.light.results.assimilation import PeriodAssimilation

        x0, y0, x1, y1 = self.unit.rect
        return PeriodAssimilation(self.model.as_dict(), self.temps.copy(), self.mol,
                                  self.mol_b, (x1 - x0) * (y1 - y0) * 1e-4, self.step_gross,
                                  self.unit.rect, self.unit.periodic, self.bias, self.bias_se)
