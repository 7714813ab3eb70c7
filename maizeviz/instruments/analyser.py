"""A virtual plant canopy analyser (LAI-2200 style): gap fractions in five zenith rings.

The LAI-2200's fisheye optic sends the sky light of five concentric zenith rings to five
detectors; their ring edges are 0-12.3, 16.7-28.6, 32.4-43.4, 47.3-58.1 and 62.3-74.1 deg
(centres near 7, 23, 38, 53 and 68 deg). A reading above the canopy and readings below it give
each ring's transmission T_i (the mean of the readings below over the reading above), the
contact numbers K_i = -ln(T_i) cos(theta_i) and the leaf area index by Miller's integral,

    LAI = 2 sum_i K_i W_i,

with the instrument's ring weights W = (0.034, 0.104, 0.160, 0.218, 0.484) (the integral's
sin(theta) d(theta), the last ring taking the rest of the hemisphere). A view cap (45, 90, 180
or 270 deg of azimuth, or 360: none) keeps the operator, a row or the sun out of view: only
that sector of each ring is read.

Here each ring's sector is sampled by lines of sight uniform in solid angle, each weighted by
the sky's radiance in its direction (a uniform sky by default, so that T_i is the ring's gap
fraction); the reading is the radiance reaching the sensor through the gaps. The mean tilt
angle (MTA) is the mean leaf inclination of the ellipsoidal distribution (Campbell 1990) whose
contact numbers G(theta_i) L fit the measured ones best (least squares over the five rings).

References
----------
LI-COR (2013). LAI-2200C Plant Canopy Analyzer, Instruction Manual, ch. 11 (theory: ring
geometry, Miller's integral and its weights, mean tilt angle). LI-COR Biosciences, Lincoln, NE.
Miller, J. B. (1967). A formula for average foliage density. Australian Journal of Botany
15, 141-144. https://doi.org/10.1071/BT9670141
Welles, J. M. & Norman, J. M. (1991). Instrument for indirect measurement of canopy
architecture. Agronomy Journal 83, 818-825.
https://doi.org/10.2134/agronj1991.00021962008300050009x
Campbell, G. S. (1990). Derivation of an angle density function for canopies with ellipsoidal
leaf angle distributions. Agricultural and Forest Meteorology 49, 173-176.
https://doi.org/10.1016/0168-1923(90)90030-A
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.instruments.ceptometer import extinction_ellipsoidal
from maizeviz.instruments.sight import Sight
from maizeviz.light.sources.sky import relative_radiance

#: The five rings' zenith edges [deg] (LAI-2200 manual).
RING_EDGES_DEG = ((0.0, 12.3), (16.7, 28.6), (32.4, 43.4), (47.3, 58.1), (62.3, 74.1))
#: The rings' nominal centres [deg], the angles of Miller's sum.
RING_CENTRES_DEG = (7.0, 23.0, 38.0, 53.0, 68.0)
#: Miller's integral's weights for the five rings (LAI-2200 manual).
RING_WEIGHTS = (0.034, 0.104, 0.160, 0.218, 0.484)
#: The view caps the instrument is sold with, deg of azimuth seen.
VIEW_CAPS_DEG = (45.0, 90.0, 180.0, 270.0, 360.0)


def miller_lai(transmission: Sequence[float], rings: Sequence[int] = (0, 1, 2, 3, 4)) -> float:
    """LAI by Miller's integral from ring transmissions (the instrument's own sum).

    Parameters
    ----------
    transmission : (5,) float in (0, 1], T_i of each ring
    rings : the rings used (the instrument can mask rings); their weights are taken as they
        are, as the LAI-2200 does

    Returns
    -------
    float, m2 m-2; inf when a ring used sees no gap
    """
    t = np.asarray(transmission, dtype=np.float64)
    if t.shape != (5,) or np.any(t < 0) or np.any(t > 1) or not np.all(np.isfinite(t)):
        raise MaizevizError(f"give five ring transmissions between 0 and 1, got {t.tolist()}",
                            quantity="transmission")
    idx = np.asarray(rings, dtype=int)
    if np.any(t[idx] == 0):
        return math.inf
    k = -np.log(t[idx]) * np.cos(np.radians(np.asarray(RING_CENTRES_DEG)[idx]))
    return float(2.0 * np.sum(k * np.asarray(RING_WEIGHTS)[idx]))


def _ellipsoidal_g(theta_deg: np.ndarray, x: float) -> np.ndarray:
    """G(theta) = K(theta) cos(theta) of an ellipsoidal distribution of parameter x."""
    return np.array([extinction_ellipsoidal(t, x) for t in theta_deg]) * \
        np.cos(np.radians(theta_deg))


def mean_tilt_deg(x: float) -> float:
    """Mean leaf inclination [deg] of the ellipsoidal distribution of parameter ``x``
    (Campbell 1990's density, integrated numerically: 57.3 deg for x = 1, spherical)."""
    from scipy.integrate import quad

    def density(t):
        return 2.0 * x ** 3 * math.sin(t) / (math.cos(t) ** 2 + x * x * math.sin(t) ** 2) ** 2

    norm = quad(density, 0.0, math.pi / 2, limit=200)[0]
    return math.degrees(quad(lambda t: t * density(t), 0.0, math.pi / 2, limit=200)[0] / norm)


def fit_ellipsoidal(contact: Sequence[float] | np.ndarray) -> tuple[float, float]:
    """The ellipsoidal parameter x and the LAI whose G(theta_i) LAI fit the contact numbers
    (5,) best in least squares: (x, lai)."""
    from scipy.optimize import minimize_scalar

    k = np.asarray(contact, dtype=np.float64)
    theta = np.asarray(RING_CENTRES_DEG)

    def fit(log_x):
        g = _ellipsoidal_g(theta, math.exp(log_x))
        lai = float(k @ g / (g @ g))
        return float(np.sum((k - lai * g) ** 2)), lai

    best = minimize_scalar(lambda v: fit(v)[0], bounds=(math.log(0.05), math.log(20.0)),
                           method="bounded", options={"xatol": 1e-4})
    return math.exp(best.x), fit(best.x)[1]


@dataclass(frozen=True)
class AnalyserPosition:
    """Where the analyser's optic is held below (or in) the canopy.

    Parameters
    ----------
    x, y : float
        The optic's place in field coordinates (x across the rows, y along them) [cm].
    height_cm : float
        The optic's height above the ground [cm].
    heading_deg : float
        The azimuth the view cap is centred on, clockwise from the field's +y axis (the
        rows' direction) [deg].
    """

    x: float
    y: float
    height_cm: float = 0.0
    heading_deg: float = 0.0

    def __post_init__(self):
        for name in ("x", "y", "height_cm", "heading_deg"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float, np.floating, np.integer)) and math.isfinite(v)):
                raise MaizevizError(f"the analyser's {name} must be a finite number, got {v!r}",
                                    quantity=name)
        if self.height_cm < 0:
            raise MaizevizError(f"the analyser's height must be >= 0 cm, got {self.height_cm}",
                                quantity="height_cm")


def check_view_cap(cap_deg: float) -> float:
    """The view cap [deg of azimuth seen] if it is one the instrument has."""
    cap = float(cap_deg)
    if not any(abs(cap - c) < 1e-9 for c in VIEW_CAPS_DEG):
        raise MaizevizError(f"the view cap must be one of "
                            f"{', '.join(f'{c:g}' for c in VIEW_CAPS_DEG)} deg, got {cap_deg}",
                            quantity="view_cap")
    return cap


def ring_directions(ring: int, n: int, heading_deg: float, cap_deg: float,
                    rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``n`` lines of sight uniform in solid angle over a ring's sector, stratified (a jittered
    grid in cos(zenith) and azimuth): unit vectors (n, 3) toward the sky in field coordinates
    and their zenith angles (n,) deg."""
    lo, hi = RING_EDGES_DEG[ring]
    m_a = max(int(round(math.sqrt(n * cap_deg / 90.0))), 1)
    m_z = max(n // m_a, 1)
    i, j = np.divmod(np.arange(m_z * m_a), m_a)
    u = (i + rng.random(len(i))) / m_z
    v = (j + rng.random(len(j))) / m_a
    c_hi, c_lo = math.cos(math.radians(lo)), math.cos(math.radians(hi))
    cz = c_lo + u * (c_hi - c_lo)
    sz = np.sqrt(1.0 - cz * cz)
    az = np.radians(heading_deg + (v - 0.5) * cap_deg)
    return np.column_stack([sz * np.sin(az), sz * np.cos(az), cz]), np.degrees(np.arccos(cz))


@dataclass(frozen=True)
class AnalyserReadings:
    """What the analyser read: the reading above and those below, ring by ring.

    Parameters
    ----------
    positions : tuple of AnalyserPosition
        Where the readings below were taken.
    above : numpy.ndarray
        (5,) float64 each ring's reading above the canopy: sky radiance relative to the
        zenith's, times the solid angle of the ring's sector.
    below : numpy.ndarray
        (P, 5) float64 the same at each position below.
    view_cap_deg : float
        Azimuth seen, centred on each position's heading [deg].
    sky : str
        Sky radiance weighting the lines of sight: "uoc" or "soc".
    rays_per_ring : int
        Lines of sight per ring and position.
    notes : list of str
        What the user should know about these readings.
    """

    positions: tuple[AnalyserPosition, ...]
    above: np.ndarray
    below: np.ndarray
    view_cap_deg: float
    sky: str
    rays_per_ring: int
    notes: list[str] = field(default_factory=list)

    @property
    def gap_fraction(self) -> np.ndarray:
        """(P, 5) below over above at each position."""
        return self.below / self.above

    @property
    def transmission(self) -> np.ndarray:
        """(5,) T_i: the mean reading below over the reading above."""
        return self.below.mean(axis=0) / self.above

    @property
    def contact(self) -> np.ndarray:
        """(5,) contact numbers K_i = -ln(T_i) cos(theta_i) (inf where T_i = 0)."""
        with np.errstate(divide="ignore"):
            return -np.log(self.transmission) * np.cos(np.radians(RING_CENTRES_DEG))

    @property
    def lai(self) -> float:
        """LAI by Miller's integral (:func:`miller_lai`), m2 m-2."""
        return miller_lai(np.clip(self.transmission, 0.0, 1.0))

    @property
    def mta_deg(self) -> float:
        """Mean tilt angle of the ellipsoidal distribution fitting the contact numbers [deg].

        NaN when a ring sees no gap.
        """
        k = self.contact
        if not np.all(np.isfinite(k)) or np.all(k == 0):
            return math.nan
        return mean_tilt_deg(fit_ellipsoidal(k)[0])

    def rings(self) -> list[dict]:
        """The readings ring by ring.

        Returns
        -------
        list of dict
            One record a ring: its edges and centre [deg], weight, reading above, mean
            reading below, transmission T and contact number K.
        """
        t, k = self.transmission, self.contact
        return [{"ring": i + 1, "from_deg": RING_EDGES_DEG[i][0], "to_deg": RING_EDGES_DEG[i][1],
                 "centre_deg": RING_CENTRES_DEG[i], "weight": RING_WEIGHTS[i],
                 "above": float(self.above[i]), "below": float(self.below[:, i].mean()),
                 "transmission": float(t[i]),
                 "contact": float(k[i]) if math.isfinite(k[i]) else None}
                for i in range(5)]

    def as_dict(self) -> dict:
        """A JSON-ready record of the readings.

        Returns
        -------
        dict
            The settings, the rings, LAI and mean tilt angle, and each position's gap
            fractions.
        """
        lai, mta = self.lai, self.mta_deg
        return {"instrument": "analyser", "view_cap_deg": self.view_cap_deg, "sky": self.sky,
                "rays_per_ring": self.rays_per_ring,
                "lai": lai if math.isfinite(lai) else None,
                "mta_deg": mta if math.isfinite(mta) else None,
                "rings": self.rings(),
                "positions": [{"x_cm": p.x, "y_cm": p.y, "height_cm": p.height_cm,
                               "heading_deg": p.heading_deg,
                               "gap_fraction": [float(g) for g in gaps]}
                              for p, gaps in zip(self.positions, self.gap_fraction)],
                "notes": list(self.notes)}

    def table(self):
        """The readings as a table.

        Returns
        -------
        pandas.DataFrame
            One row a ring, as :meth:`rings`.
        """
        import pandas as pd

        return pd.DataFrame(self.rings())


def read_analyser(sight: Sight, positions: Sequence[AnalyserPosition], *,
                  view_cap_deg: float = 360.0, sky: str = "uoc", rays_per_ring: int = 2000,
                  seed: int = 0) -> AnalyserReadings:
    """Read a virtual canopy analyser below the canopy at each of ``positions``.

    Parameters
    ----------
    sight : Sight
        The canopy's lines of sight (:meth:`Sight.of`).
    positions : sequence of AnalyserPosition
        Where the readings below are taken (their mean makes T_i, as the instrument's).
    view_cap_deg : float
        Azimuth seen: 45, 90, 180, 270 or 360 (no cap), centred on each position's heading
        [deg].
    sky : {"uoc", "soc"}
        Sky radiance weighting the lines of sight (uniform: T_i is the ring's gap fraction).
    rays_per_ring : int
        Lines of sight per ring and position (a jittered grid, so the sampling error falls
        faster than 1 / sqrt(n)).
    seed : int
        Seed of the jitter.

    Returns
    -------
    AnalyserReadings
        Each ring's reading above and below, its transmission and contact number, the LAI
        by Miller's integral and the mean tilt angle.
    """
    positions = tuple(positions)
    if not positions:
        raise MaizevizError("give at least one analyser position", quantity="positions")
    cap = check_view_cap(view_cap_deg)
    if not (isinstance(rays_per_ring, (int, np.integer)) and 1 <= rays_per_ring <= 10_000_000):
        raise MaizevizError(f"rays per ring must be a whole number from 1 to 10,000,000, got "
                            f"{rays_per_ring}", quantity="rays")
    rng = np.random.default_rng(seed)
    above = np.zeros(5)
    below = np.zeros((len(positions), 5))
    notes = []
    for p_i, pos in enumerate(positions):
        origin = np.array([pos.x, pos.y, pos.height_cm])
        for ring in range(5):
            dirs, zen = ring_directions(ring, rays_per_ring, pos.heading_deg, cap, rng)
            lo, hi = RING_EDGES_DEG[ring]
            # each line of sight stands for an equal solid angle of the ring's sector
            solid = (math.cos(math.radians(lo)) - math.cos(math.radians(hi))) * \
                math.radians(cap) / len(dirs)
            radiance = relative_radiance(dirs[:, 2], sky) * solid
            gap = sight.open(np.broadcast_to(origin, dirs.shape), dirs)
            below[p_i, ring] = float(radiance[gap].sum())
            # the sky above read through the same lines of sight: T_i has no sampling error
            # of the sky's own
            above[ring] += float(radiance.sum()) / len(positions)
        if pos.height_cm >= sight.top:
            notes.append(f"position {p_i + 1} is above the canopy")
        if sight.outside(pos.x, pos.y):
            notes.append(sight.outside_note(f"position {p_i + 1}", pos.x, pos.y))
    notes += _closed_rings(below.mean(axis=0) / above)
    return AnalyserReadings(positions, above, below, cap, sky, int(rays_per_ring), notes)


def _closed_rings(transmission: np.ndarray) -> list[str]:
    """Notes for rings that saw no sky at any position: their contact number is infinite and
    so is Miller's LAI."""
    closed = [i for i in range(5) if transmission[i] == 0]
    if not closed:
        return []
    names = ", ".join(f"{i + 1} ({RING_EDGES_DEG[i][0]:g}-{RING_EDGES_DEG[i][1]:g} deg)"
                      for i in closed)
    return [f"ring{'s' if len(closed) > 1 else ''} {names} saw no sky at any position: the "
            "contact number is infinite and so is the LAI; add positions or lines of sight, "
            "or widen the view cap"]
