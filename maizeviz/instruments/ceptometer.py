"""A virtual line ceptometer (AccuPAR LP-80 style): a probe of PAR sensors held in the canopy.

The probe is a straight bar of ``length_cm / spacing_cm`` sensors (80 cm and 1 cm: 80 sensors)
held level at a height, along any azimuth (along the rows, across them, or between). Each
sensor reads the PAR reaching it from the sun (when its line of sight to the sun is open) and
from the sky (the share of the sky's diffuse light whose lines of sight are open, each sky
direction weighted by its share of the horizontal diffuse irradiance, as the light engine's
skies are: :func:`~maizeviz.light.sources.sky.make_sky`). Light scattered by the leaves is not
in the readings: they are the uncollided PAR, the light engine's transmission on sensor
planes, sensor by sensor.

The instrument's LAI inverts the fraction transmitted, tau (the mean reading below over the
reading above), by the LP-80 manual's equation, from Campbell's ellipsoidal model of the leaf
angles (Campbell & Norman 1998, ch. 15):

    LAI = ((1 - 1 / (2 K)) fb - 1) ln(tau) / (A (1 - 0.47 fb)),
    A = 0.283 + 0.785 a - 0.159 a^2,
    K = sqrt(x^2 + tan^2(zenith)) / (x + 1.774 (x + 1.182)^-0.733),

with ``fb`` the beam fraction of the PAR above, ``a`` the leaves' PAR absorptivity (0.9 in the
manual) and ``x`` the ellipsoidal leaf angle distribution parameter (1: spherical).

References
----------
Decagon Devices (2016). AccuPAR PAR/LAI Ceptometer Model LP-80, Operator's Manual, ch. 9
(theory: the LAI inversion, the extinction coefficient, the beam fraction). Decagon Devices /
METER Group, Pullman, WA.
Campbell, G. S. & Norman, J. M. (1998). An Introduction to Environmental Biophysics, 2nd ed.,
ch. 15 (eq. 15.4, the ellipsoidal extinction coefficient). Springer, New York.
https://doi.org/10.1007/978-1-4612-1626-1
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.instruments.sight import Sight
from maizeviz.light.sources.sky import make_sky
from maizeviz.light.sources.sun import Sun

#: The LP-80's probe: 80 cm long, a sensor every centimetre.
PROBE_LENGTH_CM = 80.0
SENSOR_SPACING_CM = 1.0
#: Leaf PAR absorptivity the LP-80 manual assumes.
DEFAULT_ABSORPTIVITY = 0.9
#: Probe azimuths (clockwise from the field's +y axis, the rows' direction) named by word.
ORIENTATIONS = {"along": 0.0, "across": 90.0}


def probe_azimuth(orientation: str | float) -> float:
    """The probe's azimuth [deg, clockwise from the rows' direction, the field's +y axis] from
    "along" (0), "across" (90) or a number of degrees."""
    if isinstance(orientation, str):
        key = orientation.strip().lower()
        if key in ORIENTATIONS:
            return ORIENTATIONS[key]
        try:
            orientation = float(key)
        except ValueError:
            raise MaizevizError(f"the probe's orientation must be 'along', 'across' or an "
                                f"azimuth in degrees, got '{orientation}'",
                                quantity="orientation") from None
    value = float(orientation)
    if not math.isfinite(value):
        raise MaizevizError(f"the probe's azimuth must be a finite number of degrees, got "
                            f"{orientation}", quantity="orientation")
    return value % 360.0


@dataclass(frozen=True)
class Probe:
    """Where a ceptometer's probe is held.

    Parameters
    ----------
    x, y : float
        The probe's middle, in field coordinates (x across the rows, y along them) [cm].
    height_cm : float
        Height of the sensors above the ground [cm].
    azimuth_deg : float
        The bar's direction, clockwise from the rows' direction (+y): 0 along the rows, 90
        across them (:func:`probe_azimuth` reads "along" and "across") [deg].
    length_cm : float
        Length of the sensor bar (80 for the LP-80) [cm].
    spacing_cm : float
        Distance between neighbouring sensors (1 for the LP-80) [cm].
    """

    x: float
    y: float
    height_cm: float = 0.0
    azimuth_deg: float = 0.0
    length_cm: float = PROBE_LENGTH_CM
    spacing_cm: float = SENSOR_SPACING_CM

    def __post_init__(self):
        for name in ("x", "y", "height_cm", "azimuth_deg", "length_cm", "spacing_cm"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float, np.floating, np.integer)) and math.isfinite(v)):
                raise MaizevizError(f"the probe's {name} must be a finite number, got {v!r}",
                                    quantity=name)
        if self.height_cm < 0:
            raise MaizevizError(f"the probe's height must be >= 0 cm, got {self.height_cm}",
                                quantity="height_cm")
        if not (0 < self.spacing_cm <= self.length_cm):
            raise MaizevizError(f"the sensor spacing must be > 0 and at most the probe's length "
                                f"({self.length_cm:g} cm), got {self.spacing_cm}",
                                quantity="spacing_cm")
        if self.n_sensors > 100_000:
            raise MaizevizError(f"a probe of {self.length_cm:g} cm with a sensor every "
                                f"{self.spacing_cm:g} cm has {self.n_sensors:,} sensors: at "
                                "most 100,000", quantity="spacing_cm")

    @property
    def n_sensors(self) -> int:
        """Sensors on the bar: ``round(length / spacing)`` (80 for the LP-80)."""
        return max(int(round(self.length_cm / self.spacing_cm)), 1)

    @property
    def direction(self) -> np.ndarray:
        """(2,) unit vector along the bar, field x and y."""
        a = math.radians(self.azimuth_deg)
        return np.array([math.sin(a), math.cos(a)])

    def sensors(self) -> np.ndarray:
        """The sensors' centres: evenly spaced along the bar, centred on (x, y).

        Returns
        -------
        numpy.ndarray
            (n, 3) float sensor centres at ``height_cm`` [cm].
        """
        n = self.n_sensors
        s = (np.arange(n) - (n - 1) / 2.0) * self.spacing_cm
        out = np.empty((n, 3))
        out[:, :2] = np.array([self.x, self.y]) + s[:, None] * self.direction
        out[:, 2] = self.height_cm
        return out


def extinction_ellipsoidal(zenith_deg: float, x: float = 1.0) -> float:
    """Campbell's extinction coefficient of an ellipsoidal leaf angle distribution.

    Parameters
    ----------
    zenith_deg : float, deg, the beam's zenith angle, in [0, 90)
    x : float, the distribution's parameter (> 0; 1: spherical, larger: flatter leaves)

    Returns
    -------
    float, K (dimensionless): 1 / (2 cos(zenith)) for x = 1, within 0.1 %

    References
    ----------
    Campbell & Norman (1998), eq. 15.4.
    """
    if not x > 0:
        raise MaizevizError(f"the leaf angle distribution parameter x must be > 0, got {x}",
                            quantity="x")
    t = math.tan(math.radians(zenith_deg))
    return math.sqrt(x * x + t * t) / (x + 1.774 * (x + 1.182) ** -0.733)


def lp80_lai(tau: float, zenith_deg: float, beam_fraction: float, x: float = 1.0,
             absorptivity: float = DEFAULT_ABSORPTIVITY) -> float:
    """The LP-80's leaf area index from the fraction of PAR transmitted.

    Parameters
    ----------
    tau : float, mean PAR below over PAR above, in (0, 1]
    zenith_deg : float, deg, the sun's zenith angle
    beam_fraction : float, the beam's share of the PAR above, in [0, 1]
    x : float, ellipsoidal leaf angle distribution parameter (1: spherical)
    absorptivity : float, leaf PAR absorptivity a (0.9)

    Returns
    -------
    float, m2 leaf per m2 ground; inf where nothing is transmitted (tau = 0)
    """
    if not 0.0 <= tau <= 1.0:
        raise MaizevizError(f"tau must be between 0 and 1, got {tau}", quantity="tau")
    if not 0.0 <= beam_fraction <= 1.0:
        raise MaizevizError(f"the beam fraction must be between 0 and 1, got {beam_fraction}",
                            quantity="beam_fraction")
    if not 0.0 < absorptivity <= 1.0:
        raise MaizevizError(f"the leaf absorptivity must be in (0, 1], got {absorptivity}",
                            quantity="absorptivity")
    if tau == 0.0:
        return math.inf
    k = extinction_ellipsoidal(zenith_deg, x)
    a = 0.283 + 0.785 * absorptivity - 0.159 * absorptivity ** 2
    return ((1.0 - 1.0 / (2.0 * k)) * beam_fraction - 1.0) * math.log(tau) / \
        (a * (1.0 - 0.47 * beam_fraction)) + 0.0


@dataclass(frozen=True)
class CeptometerReadings:
    """What a ceptometer read at a set of probe positions under one sun and sky.

    Parameters
    ----------
    probes : tuple of Probe
        The probe positions read.
    sensors_cm : numpy.ndarray
        (P, n, 3) float64 every probe's sensor centres [cm].
    par_umol : numpy.ndarray
        (P, n) float64 PAR read by each sensor [umol m-2 s-1].
    sunlit : numpy.ndarray
        (P, n) bool, the sensor sees the sun.
    sky_seen : numpy.ndarray
        (P, n) float64 in [0, 1], the share of the sky's diffuse PAR the sensor sees.
    above_umol : float
        PAR above the canopy, beam and diffuse on a horizontal surface [umol m-2 s-1].
    beam_fraction : float
        The beam's share of ``above_umol``.
    sun : Sun
        The sun read under.
    x : float
        Ellipsoidal leaf angle distribution parameter of the LAI inversion.
    absorptivity : float
        Leaf PAR absorptivity of the LAI inversion.
    sky : str
        The sky's description.
    notes : list of str
        What the user should know about these readings.
    """

    probes: tuple[Probe, ...]
    sensors_cm: np.ndarray
    par_umol: np.ndarray
    sunlit: np.ndarray
    sky_seen: np.ndarray
    above_umol: float
    beam_fraction: float
    sun: Sun
    x: float
    absorptivity: float
    sky: str
    notes: list[str] = field(default_factory=list)

    @property
    def tau(self) -> float:
        """Mean PAR below over PAR above, every sensor of every probe."""
        return float(self.par_umol.mean() / self.above_umol)

    @property
    def tau_per_probe(self) -> np.ndarray:
        """(P,) mean PAR below over PAR above, probe by probe."""
        return self.par_umol.mean(axis=1) / self.above_umol

    @property
    def intercepted(self) -> float:
        """Fraction of the PAR above that the canopy intercepts before the sensors: 1 - tau."""
        return 1.0 - self.tau

    @property
    def lai(self) -> float:
        """The instrument's LAI from :attr:`tau` (:func:`lp80_lai`), m2 m-2."""
        return lp80_lai(min(max(self.tau, 0.0), 1.0), self.sun.zenith_deg,
                        self.beam_fraction, self.x, self.absorptivity)

    def as_dict(self) -> dict:
        """A JSON-ready record of the readings.

        Returns
        -------
        dict
            The settings, the summary (tau, intercepted fraction, LAI) and every sensor's
            reading, probe by probe.
        """
        lai = self.lai
        return {
            "instrument": "ceptometer",
            "sun_zenith_deg": self.sun.zenith_deg, "sun_azimuth_deg": self.sun.azimuth_deg,
            "sky": self.sky, "above_umol_m2_s": self.above_umol,
            "beam_fraction": self.beam_fraction, "x": self.x,
            "absorptivity": self.absorptivity,
            "tau": self.tau, "intercepted": self.intercepted,
            "lai": lai if math.isfinite(lai) else None,
            "probes": [{"x_cm": p.x, "y_cm": p.y, "height_cm": p.height_cm,
                        "azimuth_deg": p.azimuth_deg, "length_cm": p.length_cm,
                        "spacing_cm": p.spacing_cm, "sensors": p.n_sensors,
                        "tau": float(t), "intercepted": float(1.0 - t),
                        "par_umol_m2_s": [round(float(v), 4) for v in par],
                        "sunlit": [bool(v) for v in lit]}
                       for p, t, par, lit in zip(self.probes, self.tau_per_probe,
                                                 self.par_umol, self.sunlit)],
            "notes": list(self.notes),
        }

    def table(self):
        """The readings as a table.

        Returns
        -------
        pandas.DataFrame
            One row per sensor: probe, sensor, x, y, z [cm], PAR [umol m-2 s-1], sunlit and
            the share of the sky seen.
        """
        import pandas as pd

        p, n = self.par_umol.shape
        pts = self.sensors_cm.reshape(-1, 3)
        return pd.DataFrame({"probe": np.repeat(np.arange(1, p + 1), n),
                             "sensor": np.tile(np.arange(1, n + 1), p),
                             "x_cm": pts[:, 0], "y_cm": pts[:, 1], "z_cm": pts[:, 2],
                             "par_umol_m2_s": self.par_umol.ravel(),
                             "sunlit": self.sunlit.ravel(),
                             "sky_seen": self.sky_seen.ravel()})


def read_ceptometer(sight: Sight, probes: Sequence[Probe], sun: Sun, *,
                    par_umol: float = 2000.0, beam_fraction: float = 0.8, sky: str = "soc",
                    directions: int = 46, north_deg: float = 0.0, x: float = 1.0,
                    absorptivity: float = DEFAULT_ABSORPTIVITY) -> CeptometerReadings:
    """Read a virtual ceptometer held at each of ``probes``.

    Parameters
    ----------
    sight : Sight
        The canopy's lines of sight (:meth:`Sight.of`).
    probes : sequence of Probe
        The probe positions; the readings of all are averaged into tau, as the instrument
        averages its below-canopy readings.
    sun : Sun
        The sun's angles.
    par_umol : float
        PAR on a horizontal surface above the canopy (the reading above) [umol m-2 s-1].
    beam_fraction : float
        The beam's share of ``par_umol`` (the rest comes from the sky), in [0, 1].
    sky : {"soc", "uoc"}
        Radiance distribution of the diffuse part (:func:`~maizeviz.light.sources.sky.make_sky`).
    directions : int
        Sky directions traced (46: den Dulk's turtle).
    north_deg : float
        Angle from north to the field's +y axis, clockwise (the layout's) [deg].
    x : float
        Ellipsoidal leaf angle distribution parameter of the LAI inversion (1: spherical).
    absorptivity : float
        Leaf PAR absorptivity of the LAI inversion.

    Returns
    -------
    CeptometerReadings
        PAR per sensor, tau, the intercepted fraction and the instrument's LAI.
    """
    probes = tuple(probes)
    if not probes:
        raise MaizevizError("give at least one probe position", quantity="probes")
    if not (math.isfinite(par_umol) and par_umol > 0):
        raise MaizevizError(f"the PAR above must be > 0 umol/m2/s, got {par_umol}",
                            quantity="par")
    if not 0.0 <= beam_fraction <= 1.0:
        raise MaizevizError(f"the beam fraction must be between 0 and 1, got {beam_fraction}",
                            quantity="beam_fraction")
    lp80_lai(1.0, sun.zenith_deg, beam_fraction, x, absorptivity)   # the settings, checked
    sizes = {p.n_sensors for p in probes}
    if len(sizes) != 1:
        raise MaizevizError(f"every probe must carry as many sensors, got {sorted(sizes)}",
                            quantity="probes")
    pts = np.stack([p.sensors() for p in probes])                  # (P, n, 3)
    flat = pts.reshape(-1, 3)
    notes = []
    if np.all(flat[:, 2] >= sight.top):
        notes.append("every sensor is above the canopy: nothing is intercepted")
    notes += [sight.outside_note(f"probe {i + 1}", p.x, p.y)
              for i, p in enumerate(probes) if sight.outside(p.x, p.y)]
    sunlit = np.ones(len(flat), dtype=bool)
    seen = np.ones(len(flat))
    if beam_fraction > 0:
        sunlit = sight.open(flat, sun.direction(north_deg)[None, :])
    made = make_sky(sky, directions)
    if beam_fraction < 1:
        seen = np.zeros(len(flat))
        for w, d in zip(made.weights, made.field_directions(north_deg)):
            seen += w * sight.open(flat, d[None, :])
    beam_h = par_umol * beam_fraction
    diffuse_h = par_umol - beam_h
    par = beam_h * sunlit + diffuse_h * seen
    shape = pts.shape[:2]
    return CeptometerReadings(probes, pts, par.reshape(shape), sunlit.reshape(shape),
                              seen.reshape(shape), float(par_umol), float(beam_fraction), sun,
                              float(x), float(absorptivity), made.description, notes)
