"""The Beer-Lambert check of a light result, with G and the leaf area index from the mesh.

T_BL(h) = exp(-G L(h) / cos(theta)): G = sum A |n . s| / sum A over all leaf triangles (the
mean projection of unit leaf area toward the sun), L(h) = leaf area above h per ground area.
Row crops clump their leaves, so a traced T usually sits a little above T_BL; the effective
clumping index ln T / ln T_BL says by how much (1: random foliage; below 1: clumped, 0.7-1 for
most row crops; above 1: more regular than random).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.light.sources.sky import Sky
from maizeviz.light.sources.sun import Sun
from maizeviz.mesh.tessellate import triangle_areas_normals


@dataclass(frozen=True)
class BeerLambert:
    """Beer-Lambert transmission (H,) at the requested heights, G, and L(h) (H,) m2/m2."""

    transmission: np.ndarray
    G: float
    lai_above: np.ndarray


def beer_lambert(canopy: Canopy, sun: Sun, heights_cm: np.ndarray | tuple[float, ...]) -> BeerLambert:
    """Beer-Lambert transmission with G and L(h) (by triangle centroid) from the mesh."""
    area, normals = triangle_areas_normals(canopy.vertices, canopy.faces)
    s = sun.direction(canopy.layout.north_deg)
    g = float((area * np.abs(normals @ s)).sum() / area.sum())
    cz = canopy.vertices[canopy.faces].mean(axis=1)[:, 2]
    order = np.argsort(cz)
    cum_above = area[order][::-1].cumsum()[::-1]
    zs = cz[order]
    h = np.asarray(heights_cm, dtype=np.float64)
    idx = np.searchsorted(zs, h, side="right")
    above = np.where(idx < len(zs), cum_above[np.minimum(idx, len(zs) - 1)], 0.0)
    lai = above / canopy.layout.ground_area_cm2
    return BeerLambert(np.exp(-g * lai / s[2]), g, lai)


def clumping(traced: float, beer_lambert_t: float) -> float:
    """Effective clumping index ln T / ln T_BL; NaN where either is 0 or 1 (undefined)."""
    if 0 < traced < 1 and 0 < beer_lambert_t < 1:
        return math.log(traced) / math.log(beer_lambert_t)
    return float("nan")


def beer_lambert_sky(canopy: Canopy, sky: Sky,
                     heights_cm: np.ndarray | tuple[float, ...]) -> BeerLambert:
    """Beer-Lambert diffuse transmission under a sky: sum_i w_i exp(-G_i L(h) / cos(theta_i)),
    with G_i and L(h) from the mesh as in :func:`beer_lambert`.

    Returns
    -------
    BeerLambert with transmission (H,), G the weight-averaged G_i, lai_above (H,) m2/m2
    """
    area, normals = triangle_areas_normals(canopy.vertices, canopy.faces)
    dirs = sky.field_directions(canopy.layout.north_deg)
    g = (area[:, None] * np.abs(normals @ dirs.T)).sum(axis=0) / area.sum()      # (n,)
    lai = beer_lambert(canopy, Sun(0.0, 0.0), heights_cm).lai_above
    t = np.exp(-np.outer(lai, g / dirs[:, 2])) @ sky.weights
    return BeerLambert(t, float(g @ sky.weights), lai)
