"""Diffuse light from the sky: radiance distributions and their discretisation into directions.

A sky is a set of directions toward the sky hemisphere, each standing for one cell of the
hemisphere (the cells do not overlap and together cover it). Each direction is traced like the
sun; its weight is its cell's share of the horizontal diffuse irradiance,

    w_i = integral over cell i of L(theta) cos(theta) dOmega
          / integral over the hemisphere of L(theta) cos(theta) dOmega,

so the weights sum to 1 and the diffuse transmission of a canopy is ``sum_i w_i T_i``.

Radiance distributions (theta = zenith angle of the sky element)

- ``"soc"``: standard overcast sky, L(theta) proportional to (1 + 2 cos theta) / 3
  (Moon & Spencer 1942; adopted by the CIE as its standard overcast sky).
- ``"uoc"``: uniform overcast sky, L constant.

Discretisations (``split``)

- ``"turtle"``: den Dulk's "turtle" of 6, 16 or 46 directions (den Dulk 1989), the sky used by
  Caribu, ADEL and RATP in OpenAlea. Its directions derive from an icosahedron with one vertex
  at the zenith: 6 = the icosahedron's vertices above the horizon, 16 = those plus its face
  centres, 46 = those plus the centres of a further (star) subdivision. The directions are the
  published table (elevations and azimuths rounded to 0.01 deg). The table gives no cell
  boundaries; here the cell of a direction is the part of the hemisphere closer to it than to
  any other direction (spherical Voronoi cell, cut at the horizon), which reproduces the
  published turtle-46 solid angles (Dauzat's table, shipped with Vegestar and
  openalea.astk) to within 0.0014 sr of about 0.136 sr, and den Dulk's published weights to
  within their rounding (0.0003).
- ``"tregenza"``: Tregenza's 145 patches (Tregenza 1987): bands 12 deg high centred on
  altitudes 6, 18, ..., 78 deg with 30, 30, 24, 24, 18, 12, 6 patches and a zenith cap above
  84 deg; the direction of a patch is its centre altitude and azimuth.
- ``"equal"``: any number n >= 1 of cells of exactly equal solid angle 2 pi / n: a zenith cap
  and bands of altitude whose edges are placed so that each band holds a whole number of
  equal cells (the zonal equal-area construction of Leopardi 2006, on the hemisphere); the
  direction of a cell is its centre in azimuth and zenith angle (the cap's is the zenith).

``make_sky(kind, directions)`` picks the turtle for 6, 16 and 46 directions, Tregenza for 145
and the equal split otherwise.

Angles are in degrees, zenith from the vertical, azimuth clockwise from north; vectors have
x = east, y = north, z = up, as :meth:`maizeviz.light.sources.sun.Sun.direction`.

References
----------
- den Dulk, J.A. (1989). The interpretation of remote sensing, a feasibility study. PhD thesis,
  Wageningen Agricultural University (the 46-direction "turtle" sky).
- Moon, P. & Spencer, D.E. (1942). Illumination from a non-uniform sky. Illuminating
  Engineering 37, 707-726.
- Tregenza, P.R. (1987). Subdivision of the sky hemisphere for luminance measurements.
  Lighting Research and Technology 19, 13-14.
- Leopardi, P. (2006). A partition of the unit sphere into regions of equal area and small
  diameter. Electronic Transactions on Numerical Analysis 25, 309-327.
- Van Oosterom, A. & Strackee, J. (1983). The solid angle of a plane triangle. IEEE
  Transactions on Biomedical Engineering 30, 125-126.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from maizeviz.errors import MaizevizError

#: Sky radiance distributions: name -> description.
SKY_KINDS = {
    "soc": "standard overcast sky, radiance (1 + 2 cos zenith) / 3 (Moon & Spencer 1942)",
    "uoc": "uniform overcast sky, constant radiance",
}
#: Ways to split the hemisphere into cells.
SKY_SPLITS = ("auto", "turtle", "tregenza", "equal")
#: More directions than this are refused (each direction is one full tracing pass).
MAX_SKY_DIRECTIONS = 10_000

# den Dulk's turtle (den Dulk 1989), in the hierarchical order of the published table: the
# first 6 directions are the 6-direction turtle, the first 16 the 16-direction turtle.
# (elevation deg, azimuths deg clockwise from north)
_TURTLE_BANDS = (
    (90.00, (180.0,)),
    (26.57, (0.0, 72.0, 144.0, 216.0, 288.0)),
    (52.62, (36.0, 108.0, 180.0, 252.0, 324.0)),
    (10.81, (36.0, 108.0, 180.0, 252.0, 324.0)),
    (69.16, (0.0, 72.0, 144.0, 216.0, 288.0)),
    (47.41, (0.0, 72.0, 144.0, 216.0, 288.0)),
    (31.08, (23.27, 48.73, 95.27, 120.73, 167.27, 192.73, 239.27, 264.73, 311.27, 336.73)),
    (9.23, (12.23, 59.77, 84.23, 131.77, 156.23, 203.77, 228.23, 275.77, 300.23, 347.77)),
)
TURTLE_SIZES = (6, 16, 46)

# Tregenza (1987): (lower altitude deg, upper altitude deg, patches); the last band is the cap.
_TREGENZA_BANDS = ((0, 12, 30), (12, 24, 30), (24, 36, 24), (36, 48, 24), (48, 60, 18),
                   (60, 72, 12), (72, 84, 6), (84, 90, 1))
TREGENZA_SIZE = 145

# Gauss-Legendre nodes on [0, 1] for the cell integrals of the turtle (Voronoi) cells.
_GL_ORDER = 8
_GL_LEVELS = 1  # each fan triangle of a cell is split in 4**levels before the quadrature


# --------------------------------------------------------------------------- radiance


def _check_kind(kind: str) -> str:
    key = str(kind).strip().lower()
    if key not in SKY_KINDS:
        raise MaizevizError(f"unknown sky kind '{kind}' (known: {', '.join(SKY_KINDS)})",
                            quantity="sky")
    return key


def relative_radiance(cos_zenith, kind: str) -> np.ndarray:
    """Sky radiance relative to the zenith's.

    Parameters
    ----------
    cos_zenith : (n,) float64, cosine of the zenith angle of sky elements, in [0, 1]
    kind : "soc" or "uoc"

    Returns
    -------
    (n,) float64, dimensionless, 1 at the zenith
    """
    kind = _check_kind(kind)
    c = np.asarray(cos_zenith, dtype=np.float64)
    if kind == "soc":
        return (1.0 + 2.0 * c) / 3.0
    return np.ones_like(c)


def hemisphere_horizontal_integral(kind: str) -> float:
    """Integral of L(theta) cos(theta) dOmega over the hemisphere, L relative to the zenith.

    Returns
    -------
    float, sr: pi for the uniform sky, 7 pi / 9 for the standard overcast sky
    """
    return 7.0 * math.pi / 9.0 if _check_kind(kind) == "soc" else math.pi


def _band_horizontal_integral(c_hi, c_lo, dphi, kind: str) -> np.ndarray:
    """Integral of L cos(theta) dOmega over zenith bands cut into azimuth sectors.

    Parameters
    ----------
    c_hi, c_lo : (n,) float64, cos of the band's smaller and larger zenith angle
    dphi : (n,) float64, rad, azimuth width of the cell
    """
    c_hi, c_lo, dphi = (np.asarray(a, dtype=np.float64) for a in (c_hi, c_lo, dphi))
    first = (c_hi ** 2 - c_lo ** 2) / 2.0          # integral of cos sin dtheta
    if kind == "uoc":
        return dphi * first
    second = (c_hi ** 3 - c_lo ** 3) / 3.0         # integral of cos^2 sin dtheta
    return dphi * (first + 2.0 * second) / 3.0


# --------------------------------------------------------------------------- the Sky


def _unit_vectors(zenith_deg: np.ndarray, azimuth_deg: np.ndarray) -> np.ndarray:
    z = np.radians(zenith_deg)
    a = np.radians(azimuth_deg)
    return np.column_stack([np.sin(z) * np.sin(a), np.sin(z) * np.cos(a), np.cos(z)])


def _frozen(a) -> np.ndarray:
    a = np.array(a, dtype=np.float64)
    a.setflags(write=False)
    return a


def _sum_to_one(w: np.ndarray) -> np.ndarray:
    """Normalise weights so that their exactly rounded sum (math.fsum) is 1.0."""
    w = w / math.fsum(w)
    big = int(np.argmax(w))
    for _ in range(8):
        rest = 1.0 - math.fsum(w)
        if rest == 0.0:
            break
        w[big] += rest
    return w


@dataclass(frozen=True, eq=False)
class Sky:
    """A sky discretised into n directions with their weights.

    Attributes
    ----------
    kind : str
        Radiance distribution, "soc" or "uoc".
    split : str
        How the hemisphere was cut: "turtle", "tregenza" or "equal".
    zenith_deg : (n,) float64, deg
        Zenith angle of each direction, in [0, 90).
    azimuth_deg : (n,) float64, deg
        Azimuth, clockwise from north, in [0, 360).
    solid_angle_sr : (n,) float64, sr
        Solid angle of each direction's cell; they sum to 2 pi.
    weights : (n,) float64
        Each direction's share of the horizontal diffuse irradiance; they sum to 1 (the exactly
        rounded sum ``math.fsum`` is 1.0).

    Directions are derived: :attr:`directions` (n, 3) unit vectors toward the sky.
    """

    kind: str
    split: str
    zenith_deg: np.ndarray
    azimuth_deg: np.ndarray
    solid_angle_sr: np.ndarray
    weights: np.ndarray
    #: (n, 3) float64, unit vectors toward the sky (x east, y north, z up); derived
    directions: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "kind", _check_kind(self.kind))
        if self.split not in SKY_SPLITS[1:]:
            raise MaizevizError(f"unknown sky split '{self.split}' (known: "
                                f"{', '.join(SKY_SPLITS[1:])})")
        n = len(self.weights)
        for name in ("zenith_deg", "azimuth_deg", "solid_angle_sr", "weights"):
            arr = _frozen(getattr(self, name))
            if arr.shape != (n,) or not np.all(np.isfinite(arr)):
                raise MaizevizError(f"sky {name} must be {n} finite numbers, got shape {arr.shape}")
            object.__setattr__(self, name, arr)
        if n < 1:
            raise MaizevizError(f"sky directions must be at least 1, got {n}")
        if np.any(self.zenith_deg < 0) or np.any(self.zenith_deg >= 90):
            raise MaizevizError("sky directions must point above the horizon (zenith in [0, 90) deg)")
        if np.any(self.weights < 0) or abs(math.fsum(self.weights) - 1.0) > 1e-12:
            raise MaizevizError(f"sky weights must be >= 0 and sum to 1, got sum "
                                f"{math.fsum(self.weights):.15g}")
        object.__setattr__(self, "directions", _frozen(_unit_vectors(self.zenith_deg,
                                                                     self.azimuth_deg)))

    @property
    def n(self) -> int:
        """Number of directions."""
        return len(self.weights)

    @property
    def name(self) -> str:
        """Short label such as ``"soc turtle 46"``."""
        return f"{self.kind} {self.split} {self.n}"

    @property
    def description(self) -> str:
        """One line naming the radiance distribution and the discretisation."""
        return f"{SKY_KINDS[self.kind]}; {self.split} split, {self.n} directions"

    def field_directions(self, north_deg: float = 0.0) -> np.ndarray:
        """Directions toward the sky in field coordinates, as ``Sun.direction(north_deg)``.

        Parameters
        ----------
        north_deg : float, deg, clockwise angle from north to the field's +y axis

        Returns
        -------
        (n, 3) float64, unit vectors toward the sky
        """
        return _unit_vectors(self.zenith_deg, self.azimuth_deg - float(north_deg))

    def transmission(self, per_direction) -> float:
        """Diffuse transmission from the transmission of each direction: ``sum_i w_i T_i``.

        Parameters
        ----------
        per_direction : (n,) float64 in [0, 1], transmission of the parallel beam of each
            direction, in the order of :attr:`directions`

        Returns
        -------
        float in [0, 1]
        """
        t = np.asarray(per_direction, dtype=np.float64)
        if t.shape != (self.n,):
            raise MaizevizError(f"the sky has {self.n} directions but {t.size} transmissions "
                                f"were given")
        if not np.all(np.isfinite(t)) or np.any(t < 0) or np.any(t > 1):
            raise MaizevizError("transmissions must be numbers between 0 and 1")
        return float(math.fsum(self.weights * t))

    def table(self) -> str:
        """Plain-text table of the directions and weights (for ``--verbose``)."""
        lines = [f"# sky: {self.description}",
                 "#  i  zenith_deg  azimuth_deg  solid_angle_sr  weight"]
        for i in range(self.n):
            lines.append(f"{i + 1:4d}  {self.zenith_deg[i]:10.2f}  {self.azimuth_deg[i]:11.2f}  "
                         f"{self.solid_angle_sr[i]:14.5f}  {self.weights[i]:.5f}")
        lines.append(f"# weights sum to {math.fsum(self.weights):.15f}, solid angles to "
                     f"{math.fsum(self.solid_angle_sr):.12f} sr (2 pi = {2 * math.pi:.12f})")
        return "\n".join(lines)


def _make(kind, split, zenith, azimuth, solid, integral) -> Sky:
    order = np.lexsort((np.round(np.mod(azimuth, 360.0), 9), np.round(zenith, 9)))
    return Sky(kind=kind, split=split, zenith_deg=np.asarray(zenith)[order],
               azimuth_deg=np.mod(np.asarray(azimuth), 360.0)[order],
               solid_angle_sr=np.asarray(solid)[order],
               weights=_sum_to_one(np.asarray(integral, dtype=np.float64)[order]))


# --------------------------------------------------------------------------- band splits


def _band_sky(kind, split, c_edges, counts, zenith_of_cell, centre_offset) -> Sky:
    """Sky whose cells are zenith bands cut into equal azimuth sectors.

    Parameters
    ----------
    c_edges : (b + 1,) float64, cos of the band edges from the zenith (1) down to the horizon (0)
    counts : (b,) int, cells per band
    zenith_of_cell : (b,) float64, deg, zenith of the directions of each band
    centre_offset : float, 0.5 puts the first sector's direction at half a sector from north,
        0.0 puts it on north (the sector then spans north +- half a sector)
    """
    zen, azi, solid, integ = [], [], [], []
    for b, m in enumerate(counts):
        dphi = 2.0 * math.pi / m
        k = np.arange(m)
        zen.append(np.full(m, zenith_of_cell[b]))
        azi.append(np.degrees((k + centre_offset) * dphi) if m > 1 else np.zeros(1))
        solid.append(np.full(m, dphi * (c_edges[b] - c_edges[b + 1])))
        integ.append(np.full(m, _band_horizontal_integral(c_edges[b], c_edges[b + 1], dphi,
                                                          kind)))
    return _make(kind, split, np.concatenate(zen), np.concatenate(azi), np.concatenate(solid),
                 np.concatenate(integ))


def equal_area_bands(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Zonal split of the hemisphere into n cells of solid angle 2 pi / n each.

    A zenith cap holds one cell; the remaining n - 1 cells fill bands whose number is chosen so
    that cells are about as tall as they are wide, and whose edges are then moved so that each
    band holds a whole number of cells of exactly 2 pi / n sr (Leopardi 2006).

    Returns
    -------
    c_edges : (b + 1,) float64, cos of the zenith of the band edges, 1 ... 0 (first band = cap)
    counts : (b,) int64, cells per band, counts[0] == 1, sum == n
    """
    if n == 1:
        return np.array([1.0, 0.0]), np.array([1], dtype=np.int64)
    cell = 2.0 * math.pi / n
    cap = math.acos(1.0 - 1.0 / n)                 # 2 pi (1 - cos cap) = cell
    bands = max(1, round((math.pi / 2 - cap) / math.sqrt(cell)))
    while True:
        theta = np.linspace(cap, math.pi / 2, bands + 1)
        ideal = n * (np.cos(theta[:-1]) - np.cos(theta[1:]))   # cells each band would hold
        counts, carry = [], 0.0
        for x in ideal:
            m = round(x + carry)
            carry += x - m
            counts.append(m)
        if min(counts) >= 1 or bands == 1:
            break
        bands -= 1
    per_band = np.array([1, *counts], dtype=np.int64)
    per_band[-1] += n - per_band.sum()             # absorbs rounding of the carry, if any
    c_edges = 1.0 - np.concatenate([[0], np.cumsum(per_band)]) / n
    c_edges[-1] = 0.0
    return c_edges, per_band


def _equal_sky(kind: str, n: int) -> Sky:
    c_edges, counts = equal_area_bands(n)
    theta = np.degrees(np.arccos(c_edges))
    # the band's middle zenith angle (as Tregenza's patch centres); the middle in solid angle
    # sits lower and makes every low band see too long a path (-3.6 % instead of +0.4 % on
    # the spherical-canopy transmission at LAI 5 with 46 directions)
    zen = (theta[:-1] + theta[1:]) / 2.0
    zen[0] = 0.0                                   # the cap's direction is the zenith
    return _band_sky(kind, "equal", c_edges, counts, zen, centre_offset=0.5)


def _tregenza_sky(kind: str) -> Sky:
    lo = np.array([b[0] for b in _TREGENZA_BANDS], dtype=np.float64)[::-1]   # zenith down
    hi = np.array([b[1] for b in _TREGENZA_BANDS], dtype=np.float64)[::-1]
    counts = [b[2] for b in _TREGENZA_BANDS][::-1]
    c_edges = np.sin(np.radians(np.concatenate([[90.0], lo])))   # cos(zenith) = sin(altitude)
    zen = 90.0 - (lo + hi) / 2.0
    zen[0] = 0.0                                   # the cap's direction is the zenith
    return _band_sky(kind, "tregenza", c_edges, counts, zen, centre_offset=0.0)


# --------------------------------------------------------------------------- turtle


def turtle_directions(n: int = 46) -> tuple[np.ndarray, np.ndarray]:
    """den Dulk's turtle as published (elevations and azimuths rounded to 0.01 deg).

    Parameters
    ----------
    n : 6, 16 or 46

    Returns
    -------
    zenith_deg : (n,) float64, azimuth_deg : (n,) float64 (clockwise from north), in the
    hierarchical order of the table (the first 6 and 16 form the smaller turtles)
    """
    if n not in TURTLE_SIZES:
        raise MaizevizError(f"the turtle sky has {', '.join(map(str, TURTLE_SIZES[:-1]))} or "
                            f"{TURTLE_SIZES[-1]} directions, got {n}", quantity="sky_directions")
    el = np.concatenate([np.full(len(az), e) for e, az in _TURTLE_BANDS])
    az = np.concatenate([np.array(a) for _, a in _TURTLE_BANDS])
    return 90.0 - el[:n], az[:n]


def _voronoi_cells(directions: np.ndarray) -> list[np.ndarray]:
    """Cells of the hemisphere nearest to each direction (spherical Voronoi, cut at z = 0).

    Mirroring the directions below the horizon makes the horizon the bisector between each
    direction and its mirror image, so the cells of the upper directions tile the hemisphere.

    Returns
    -------
    list of n (k_i, 3) float64 arrays: unit vertices of each cell, counter-clockwise
    """
    from scipy.spatial import SphericalVoronoi

    mirrored = np.vstack([directions, directions * np.array([1.0, 1.0, -1.0])])
    sv = SphericalVoronoi(mirrored, radius=1.0, center=np.zeros(3))
    sv.sort_vertices_of_regions()
    cells = []
    for i in range(len(directions)):
        verts = sv.vertices[sv.regions[i]]
        # where 4 cells meet on the horizon (a direction, its neighbour and their mirror
        # images), the vertex appears twice: keep one
        step = np.linalg.norm(verts - np.roll(verts, -1, axis=0), axis=1)
        cells.append(verts[step > 1e-12])
    return cells


def triangle_solid_angle(a, b, c) -> np.ndarray:
    """Solid angle of spherical triangles with unit vertices (Van Oosterom & Strackee 1983).

    Parameters
    ----------
    a, b, c : (m, 3) float64, unit vectors

    Returns
    -------
    (m,) float64, sr
    """
    num = np.abs(np.einsum("ij,ij->i", a, np.cross(b, c)))
    den = 1.0 + np.einsum("ij,ij->i", a, b) + np.einsum("ij,ij->i", b, c) + \
        np.einsum("ij,ij->i", c, a)
    return 2.0 * np.arctan2(num, den)


def _split4(a, b, c):
    ab = a + b
    bc = b + c
    ca = c + a
    ab /= np.linalg.norm(ab, axis=1, keepdims=True)
    bc /= np.linalg.norm(bc, axis=1, keepdims=True)
    ca /= np.linalg.norm(ca, axis=1, keepdims=True)
    return (np.concatenate([a, ab, ca, ab]), np.concatenate([ab, b, bc, bc]),
            np.concatenate([ca, bc, c, ca]))


def spherical_triangle_quadrature(a, b, c, levels: int = _GL_LEVELS, order: int = _GL_ORDER):
    """Nodes and solid-angle weights integrating over spherical triangles.

    Each triangle is split ``levels`` times into 4; each piece is integrated on its flat
    triangle with a collapsed (Duffy) Gauss-Legendre rule of ``order`` x ``order`` points and
    the solid-angle Jacobian h / |p|^3 of the central projection onto the sphere.

    Parameters
    ----------
    a, b, c : (m, 3) float64, unit vertices of m spherical triangles

    Returns
    -------
    nodes : (m, q, 3) float64, unit vectors; domega : (m, q) float64, sr, summing per triangle
    to its solid angle; q = 4**levels * order**2
    """
    m = len(a)
    a, b, c = (np.asarray(x, dtype=np.float64) for x in (a, b, c))
    for _ in range(levels):
        a, b, c = _split4(a, b, c)
    # pieces are ordered level by level: piece j of triangle i sits at index j * m + i
    x, w = np.polynomial.legendre.leggauss(order)
    x = (x + 1.0) / 2.0
    w = w / 2.0
    u, v = (g.ravel() for g in np.meshgrid(x, x, indexing="ij"))
    wuv = np.outer(w, w).ravel() * u
    e1 = b - a
    e2 = c - b
    normal = np.cross(e1, c - a)
    twice_area = np.linalg.norm(normal, axis=1)
    h = np.abs(np.einsum("ij,ij->i", normal, a)) / twice_area
    p = a[:, None, :] + u[None, :, None] * (e1[:, None, :] + v[None, :, None] * e2[:, None, :])
    r = np.linalg.norm(p, axis=2)
    dom = (twice_area * h)[:, None] * wuv[None, :] / r ** 3
    nodes = p / r[..., None]
    pieces = 4 ** levels
    nodes = nodes.reshape(pieces, m, -1, 3).transpose(1, 0, 2, 3).reshape(m, -1, 3)
    dom = dom.reshape(pieces, m, -1).transpose(1, 0, 2).reshape(m, -1)
    return nodes, dom


def _turtle_sky(kind: str, n: int) -> Sky:
    zen, azi = turtle_directions(n)
    dirs = _unit_vectors(zen, azi)
    cells = _voronoi_cells(dirs)
    owners, tas, tbs, tcs = [], [], [], []
    for i, verts in enumerate(cells):
        k = len(verts)
        owners.append(np.full(k, i))
        tas.append(np.repeat(dirs[i][None, :], k, axis=0))
        tbs.append(verts)
        tcs.append(np.roll(verts, -1, axis=0))
    owner = np.concatenate(owners)
    ta, tb, tc = np.concatenate(tas), np.concatenate(tbs), np.concatenate(tcs)
    solid = np.bincount(owner, weights=triangle_solid_angle(ta, tb, tc), minlength=n)
    nodes, dom = spherical_triangle_quadrature(ta, tb, tc)
    cz = np.clip(nodes[..., 2], 0.0, 1.0)
    per_tri = np.sum(relative_radiance(cz, kind) * cz * dom, axis=1)
    integral = np.bincount(owner, weights=per_tri, minlength=n)
    return _make(kind, "turtle", zen, azi, solid, integral)


# --------------------------------------------------------------------------- public entry


def _check_count(directions) -> int:
    if isinstance(directions, bool) or not isinstance(directions, (int, np.integer, float)):
        raise MaizevizError(f"sky directions must be a whole number, got {directions!r}",
                            quantity="sky_directions")
    if isinstance(directions, float) and (not math.isfinite(directions)
                                          or directions != int(directions)):
        raise MaizevizError(f"sky directions must be a whole number, got {directions}",
                            quantity="sky_directions")
    n = int(directions)
    if n < 1:
        raise MaizevizError(f"sky directions must be at least 1, got {n}",
                            quantity="sky_directions")
    if n > MAX_SKY_DIRECTIONS:
        raise MaizevizError(f"sky directions must be at most {MAX_SKY_DIRECTIONS}, got {n} "
                            f"(each direction is one full tracing pass)", quantity="sky_directions")
    return n


def make_sky(kind: str = "soc", directions: int = 46, split: str = "auto") -> Sky:
    """A sky of the given radiance distribution, discretised into ``directions`` directions.

    Parameters
    ----------
    kind : {"soc", "uoc"}
        Standard overcast (radiance rising toward the zenith) or uniform overcast.
    directions : int
        Directions, at least 1 (6, 16, 46: den Dulk's turtles; 145: Tregenza's patches).
    split : {"auto", "turtle", "tregenza", "equal"}
        How the hemisphere is cut: "auto" is the turtle for 6, 16 and 46, Tregenza's for 145,
        equal solid angles otherwise.

    Returns
    -------
    Sky
        ``zenith_deg``, ``azimuth_deg`` (n,) [deg], ``solid_angle_sr`` (n,) [sr] and
        ``weights`` (n,) summing to 1 (each direction's share of the horizontal diffuse
        irradiance).

    Raises
    ------
    MaizevizError
        Unknown kind or split, fewer than 1 direction, or a count the split does not offer.

    References
    ----------
    Moon, P. & Spencer, D. E. (1942). Illumination from a non-uniform sky. Illuminating
    Engineering 37, 707-726 (no DOI). den Dulk, J. A. (1989), the turtle; Tregenza, P. R.
    (1987), Lighting Research and Technology 19, 13-14 (see the module's references).
    Chelle, M. & Andrieu, B. (1998). The nested radiosity model for the distribution of
    light within plant canopies. Ecological Modelling 111(1), 75-91.
    https://doi.org/10.1016/S0304-3800(98)00100-8
    """
    kind = _check_kind(kind)
    n = _check_count(directions)
    key = str(split).strip().lower()
    if key not in SKY_SPLITS:
        raise MaizevizError(f"unknown sky split '{split}' (known: {', '.join(SKY_SPLITS)})",
                            quantity="sky")
    if key == "auto":
        key = "turtle" if n in TURTLE_SIZES else ("tregenza" if n == TREGENZA_SIZE else "equal")
    if key == "tregenza" and n != TREGENZA_SIZE:
        raise MaizevizError(f"the Tregenza sky has {TREGENZA_SIZE} directions, got {n}",
                            quantity="sky_directions")
    if key == "turtle" and n not in TURTLE_SIZES:
        turtle_directions(n)                        # raises with the sizes on offer
    return _cached_sky(kind, n, key)


@lru_cache(maxsize=64)
def _cached_sky(kind: str, n: int, split: str) -> Sky:
    if split == "turtle":
        return _turtle_sky(kind, n)
    if split == "tregenza":
        return _tregenza_sky(kind)
    return _equal_sky(kind, n)


# --------------------------------------------------------------------------- analytic cases


def analytic_diffuse_transmission(lai: float, sky_kind: str, G: float = 0.5) -> float:
    """Diffuse transmission of a turbid medium of leaf area index ``lai`` under a sky.

    Each direction at zenith t transmits exp(-G L / cos t); the sky weights it by its share of
    horizontal irradiance:

        T_d = integral_0^{pi/2} L(t) exp(-G lai / cos t) cos t sin t dt
              / integral_0^{pi/2} L(t) cos t sin t dt,

    i.e. 2 * integral exp(-G lai / cos t) cos t sin t dt under the uniform sky. G = 0.5 is the
    spherical leaf angle distribution.

    Parameters
    ----------
    lai : float >= 0, m2 leaf / m2 ground
    sky_kind : "soc" or "uoc"
    G : float in (0, 1], mean projection of unit leaf area on a plane normal to the beam

    Returns
    -------
    float in (0, 1]
    """
    from scipy.integrate import quad

    kind = _check_kind(sky_kind)
    if not (math.isfinite(lai) and lai >= 0):
        raise MaizevizError(f"leaf area index must be a number >= 0, got {lai}")
    if not (math.isfinite(G) and 0 < G <= 1):
        raise MaizevizError(f"G (mean leaf projection) must be in (0, 1], got {G}")

    def integrand(t):
        c = math.cos(t)
        if c <= 0.0:
            return 0.0
        lum = (1.0 + 2.0 * c) / 3.0 if kind == "soc" else 1.0
        return lum * math.exp(-G * lai / c) * c * math.sin(t)

    value, _ = quad(integrand, 0.0, math.pi / 2, epsabs=1e-14, epsrel=1e-12, limit=200)
    return value * 2.0 * math.pi / hemisphere_horizontal_integral(kind)
