"""Each time step's diffuse light split by Perez's anisotropic sky model (through pvlib).

Perez's model (Perez et al. 1987, 1990) describes the diffuse sky of a time step as three
sources, whose strengths follow from the step's diffuse and direct irradiance and the sun's
zenith through two coefficients F1 (circumsolar brightening) and F2 (horizon brightening),
read from the published tables by ``pvlib.irradiance.perez``:

- an isotropic background of uniform radiance,
- a circumsolar source, treated as a point at the sun's position,
- a horizon band, a line source of zero width lying on the horizon.

On a plane of tilt beta the model gives the diffuse irradiance
``dhi [(1 - F1)(1 + cos beta)/2 + F1 a/b + F2 sin beta]`` with ``a`` the cosine of the sun's
angle of incidence and ``b = max(cos z, cos 85 deg)``. On the horizontal plane (beta = 0),
which is how the light of a sky enters a canopy traced here (every direction carries its share
of the *horizontal* diffuse irradiance), the three parts are

    isotropic   = dhi (1 - F1)
    circumsolar = dhi F1 cos z / max(cos z, cos 85 deg)
    horizon     = dhi F2 sin 0 = 0

so for the sun above 5 deg of elevation the isotropic and circumsolar parts add to dhi. A
line source on the horizon sends its light parallel to the ground: it crosses no horizontal
plane and brings nothing to a canopy lit from above. Its strength is kept
(:attr:`DiffuseSplit.horizon_vertical_w_m2`, F2 dhi, what it gives a vertical plane) but
nothing of it is traced; widening it into the lowest band of sky directions would invent
horizontal irradiance the model does not have (and F2 < 0, horizon darkening, for overcast
skies would give that band negative light).

Two adjustments keep the parts physical and make them add up to dhi exactly:

- the circumsolar part is cut to [0, dhi] (F1 > 1 would leave a negative isotropic
  background; F1 is already >= 0 in pvlib);
- with the sun below 5 deg of elevation, ``b = cos 85 deg`` makes the two parts add to less
  than dhi (the circumsolar region is partly below the horizon): the isotropic part is taken as
  ``dhi - circumsolar`` there, i.e. it takes what the model leaves out.

Models: ``"perez"``, the 1990 all-sites composite coefficients (Perez et al. 1990) in
``pvlib.irradiance.perez``; ``"perez-driesse"``, the continuous reformulation of the same model
(Driesse et al. 2024) in ``pvlib.irradiance.perez_driesse``, without the jumps of the 1990
model at the edges of its eight sky-clearness bins. Inputs: the step's dhi and dni, the sun's
apparent zenith and azimuth, the extraterrestrial irradiance of the day
(``pvlib.irradiance.get_extra_radiation``) and the relative air mass of Kasten & Young 1989
(``pvlib.atmosphere.get_relative_airmass``). F1 and F2 are not re-typed here: they are read back
from pvlib's own components (F1 = 1 - isotropic / dhi on the horizontal, F2 = horizon / dhi on
a vertical plane).

References
----------
- Perez, R., Ineichen, P., Seals, R., Michalsky, J. & Stewart, R. (1990). Modeling daylight
  availability and irradiance components from direct and global irradiance. Solar Energy
  44(5), 271-289.
- Perez, R., Seals, R., Ineichen, P., Stewart, R. & Menicucci, D. (1987). A new simplified
  version of the Perez diffuse irradiance model for tilted surfaces. Solar Energy 39(3),
  221-231.
- Driesse, A., Jensen, A. R. & Perez, R. (2024). A continuous form of the Perez diffuse sky
  model for forward and reverse transposition. Solar Energy 267, 112093.
- Kasten, F. & Young, A. T. (1989). Revised optical air mass tables and approximation formula.
  Applied Optics 28, 4735-4738.
- pvlib python: ``pvlib.irradiance.perez``, ``pvlib.irradiance.perez_driesse``
  (https://pvlib-python.readthedocs.io); Holmgren, W. F., Hansen, C. W. & Mikofski, M. A.
  (2018). pvlib python: a python package for modeling solar energy systems. Journal of Open
  Source Software 3(29), 884.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.light.sources.irradiance import Period

#: Diffuse models that split each step's diffuse light: name -> description.
PEREZ_MODELS = {
    "perez": "Perez et al. 1990 anisotropic sky (all-sites composite coefficients, pvlib)",
    "perez-driesse": "Perez-Driesse continuous form of the Perez 1990 sky (Driesse et al. "
                     "2024, pvlib)",
}
#: The arrays of a :class:`DiffuseSplit`, in its constructor's order after ``model``.
SPLIT_ARRAYS = ("isotropic_w_m2", "circumsolar_w_m2", "horizon_w_m2", "horizon_vertical_w_m2",
                "f1", "f2", "clearness", "brightness")
#: Below this solar elevation (deg) Perez's horizontal parts add to less than dhi.
LOW_SUN_ELEVATION_DEG = 5.0


def _frozen(a) -> np.ndarray:
    a = np.array(a, dtype=np.float64)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class DiffuseSplit:
    """The diffuse horizontal irradiance of each step of a period in Perez's three parts.

    Attributes
    ----------
    model : "perez" or "perez-driesse"
    isotropic_w_m2 : (n,) float64 W/m2 on the horizontal: spread as a uniform sky
    circumsolar_w_m2 : (n,) float64 W/m2 on the horizontal: from the sun's direction
    horizon_w_m2 : (n,) float64 W/m2 on the horizontal: 0 (a line source on the horizon)
    horizon_vertical_w_m2 : (n,) float64 W/m2: what the horizon band gives a vertical plane,
        F2 dhi (negative: horizon darkening); not traced
    f1, f2 : (n,) float64: Perez's circumsolar and horizon coefficients of each step
    clearness : (n,) float64: Perez's sky clearness epsilon (1: overcast; above 6.2: clear;
        NaN where dhi is 0)
    brightness : (n,) float64: Perez's sky brightness delta = dhi m / I0

    For every step ``isotropic + circumsolar + horizon == dhi`` (to rounding) and each part is
    >= 0.
    """

    model: str
    isotropic_w_m2: np.ndarray
    circumsolar_w_m2: np.ndarray
    horizon_w_m2: np.ndarray
    horizon_vertical_w_m2: np.ndarray
    f1: np.ndarray
    f2: np.ndarray
    clearness: np.ndarray
    brightness: np.ndarray

    def __post_init__(self):
        if self.model not in PEREZ_MODELS:
            raise MaizevizError(f"unknown diffuse model '{self.model}' (known: "
                                f"{', '.join(PEREZ_MODELS)})", quantity="sky")
        n = len(self.isotropic_w_m2)
        for name in SPLIT_ARRAYS:
            arr = _frozen(getattr(self, name))
            if arr.shape != (n,):
                raise MaizevizError(f"diffuse split {name} must hold {n} numbers, got shape "
                                    f"{arr.shape}")
            object.__setattr__(self, name, arr)
        for name in ("isotropic_w_m2", "circumsolar_w_m2", "horizon_w_m2"):
            arr = getattr(self, name)
            if not np.all(np.isfinite(arr)) or np.any(arr < 0):
                raise MaizevizError(f"diffuse split {name} must be finite numbers >= 0")

    @property
    def n_steps(self) -> int:
        return len(self.isotropic_w_m2)

    @property
    def dhi_w_m2(self) -> np.ndarray:
        """(n,) float64 W/m2: the three parts added (the period's dhi)."""
        return self.isotropic_w_m2 + self.circumsolar_w_m2 + self.horizon_w_m2

    @property
    def circumsolar_share(self) -> np.ndarray:
        """(n,) float64 in [0, 1]: circumsolar / dhi of each step (0 where dhi is 0)."""
        dhi = self.dhi_w_m2
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(dhi > 0, np.clip(self.circumsolar_w_m2 / dhi, 0.0, 1.0), 0.0)

    @property
    def description(self) -> str:
        return PEREZ_MODELS[self.model]


def perez_split(period: Period, model: str = "perez") -> DiffuseSplit:
    """Split each step's diffuse horizontal irradiance into Perez's three parts (pvlib).

    Parameters
    ----------
    period : Period (its dhi, dni, apparent zenith, azimuth and times)
    model : "perez" (1990 all-sites composite coefficients) or "perez-driesse" (continuous)

    Returns
    -------
    DiffuseSplit, one entry per step of ``period``; see the module docstring for the parts and
    the two adjustments that make them add to dhi.

    References
    ----------
    Perez, R. et al. (1990). Solar Energy 44(5), 271-289; pvlib's ``irradiance.perez``.
    """
    import pvlib

    key = str(model).strip().lower()
    if key not in PEREZ_MODELS:
        raise MaizevizError(f"unknown diffuse model '{model}' (known: "
                            f"{', '.join(PEREZ_MODELS)})", quantity="sky")
    n = period.n_steps
    dhi = np.asarray(period.dhi, dtype=np.float64)
    if n == 0:
        z = np.zeros(0)
        return DiffuseSplit(key, z, z, z, z, z, z, z, z)
    zen = np.asarray(period.zenith_deg, dtype=np.float64)
    azi = np.asarray(period.azimuth_deg, dtype=np.float64)
    dni = np.asarray(period.dni, dtype=np.float64)
    extra = np.asarray(pvlib.irradiance.get_extra_radiation(period.times), dtype=np.float64)
    airmass = np.asarray(pvlib.atmosphere.get_relative_airmass(zen, "kastenyoung1989"),
                         dtype=np.float64)
    fn = pvlib.irradiance.perez if key == "perez" else pvlib.irradiance.perez_driesse
    lit = dhi > 0
    f1 = np.zeros(n)
    f2 = np.zeros(n)
    circ = np.zeros(n)
    if lit.any():
        args = (dhi[lit], dni[lit], extra[lit], zen[lit], azi[lit], airmass[lit])
        flat = fn(0.0, 180.0, *args, return_components=True)
        upright = fn(90.0, 180.0, *args, return_components=True)
        iso_h = np.asarray(flat["poa_isotropic"], dtype=np.float64)
        f1[lit] = 1.0 - iso_h / dhi[lit]
        f2[lit] = np.asarray(upright["poa_horizon"], dtype=np.float64) / dhi[lit]
        circ[lit] = np.asarray(flat["poa_circumsolar"], dtype=np.float64)
        if not (np.all(np.isfinite(f1)) and np.all(np.isfinite(f2))
                and np.all(np.isfinite(circ))):
            raise MaizevizError("pvlib's Perez model gave no coefficients for some time steps "
                                "(check the period's irradiance)", quantity="sky")
    circ = np.clip(circ, 0.0, dhi)
    iso = np.maximum(dhi - circ, 0.0)
    kappa = 1.041
    zr = np.radians(zen)
    with np.errstate(invalid="ignore", divide="ignore"):
        eps = np.where(lit, ((dhi + dni) / np.where(lit, dhi, 1.0) + kappa * zr ** 3)
                       / (1.0 + kappa * zr ** 3), np.nan)
    delta = dhi * airmass / extra
    return DiffuseSplit(key, iso, circ, np.zeros(n), f2 * dhi, f1, f2, eps, delta)


def split_summary(split: DiffuseSplit, period: Period) -> str:
    """One line: the period's diffuse light in the three parts, MJ/m2 and shares."""
    s = np.asarray(period.step_s, dtype=np.float64)
    total = math.fsum(split.dhi_w_m2 * s) * 1e-6
    circ = math.fsum(split.circumsolar_w_m2 * s) * 1e-6
    iso = math.fsum(split.isotropic_w_m2 * s) * 1e-6
    share = circ / total if total > 0 else 0.0
    return (f"diffuse split by the {split.description}: isotropic {iso:.2f} MJ/m2, "
            f"circumsolar (traced with the sun) {circ:.2f} MJ/m2 ({share:.0%}), horizon band "
            "0 on the horizontal (not traced)")
