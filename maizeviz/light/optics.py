"""Leaf and soil optics per waveband: how much light a leaf reflects and transmits, and the
ground reflects, in PAR (400-700 nm) and near infrared (700-3000 nm).

Leaves and soil are Lambertian here: what they reflect or transmit leaves in a cosine
distribution about the surface normal, whatever the direction it came from. A leaf reflects
to the side the light came from and transmits to the other side; both sides alike.

Defaults (maize, from measured spectra; the same values scatter models of crops use):

========  ===========  =============  ==================  ============================
band      reflectance  transmittance  ground reflectance  share of shortwave (global)
========  ===========  =============  ==================  ============================
``par``   0.10         0.05           0.10                0.48 (``PAR_FRACTION``)
``nir``   0.45         0.40           0.25                0.52 (the rest)
========  ===========  =============  ==================  ============================

A leaf's scattering coefficient (reflectance + transmittance) is then 0.15 in PAR, the value
de Pury & Farquhar (1997) use, and 0.85 in NIR (Goudriaan 1977: about 0.8).

References
----------
Walter-Shea, E. A., Norman, J. M. & Blad, B. L. (1989). Leaf bidirectional reflectance and
transmittance in corn and soybean. Remote Sensing of Environment 29, 161-174.
Goudriaan, J. (1977). Crop Micrometeorology: a Simulation Study. Pudoc, Wageningen.
de Pury, D. G. G. & Farquhar, G. D. (1997). Simple scaling of photosynthesis from leaves to
canopies without the errors of big-leaf models. Plant, Cell & Environment 20, 537-557.
Jacquemoud, S. & Baret, F. (1990). PROSPECT: a model of leaf optical properties spectra.
Remote Sensing of Environment 34, 75-91.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from maizeviz.errors import MaizevizError
from maizeviz.light.irradiance import PAR_FRACTION

#: Wavebands traced: photosynthetically active radiation and near infrared.
BANDS = ("par", "nir")
#: Share of global shortwave irradiance in each band.
SHORTWAVE_SHARE = {"par": PAR_FRACTION, "nir": 1.0 - PAR_FRACTION}


@dataclass(frozen=True)
class Optics:
    """Lambertian optics of the leaves and the ground in one band.

    Attributes
    ----------
    reflectance, transmittance : leaf, fractions in [0, 1] with a sum <= 1
    ground_reflectance : soil, fraction in [0, 1]
    band : ``"par"`` or ``"nir"`` (names the results' units)
    """

    reflectance: float
    transmittance: float
    ground_reflectance: float
    band: str = "par"

    def __post_init__(self) -> None:
        for name in ("reflectance", "transmittance", "ground_reflectance"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                    not math.isfinite(value) or not 0.0 <= value <= 1.0:
                raise MaizevizError(f"the {name.replace('_', ' ')} must be a number from 0 to "
                                    f"1, got {value!r}", quantity=name)
            object.__setattr__(self, name, float(value))
        if self.reflectance + self.transmittance > 1.0 + 1e-12:
            raise MaizevizError(f"a leaf cannot reflect and transmit more than it receives: "
                                f"reflectance {self.reflectance:g} + transmittance "
                                f"{self.transmittance:g} > 1", quantity="transmittance")
        if self.band not in BANDS:
            raise MaizevizError(f"unknown band '{self.band}' (known: {', '.join(BANDS)})",
                                quantity="band")

    @property
    def scattering(self) -> float:
        """Leaf scattering coefficient: reflectance + transmittance."""
        return self.reflectance + self.transmittance

    @property
    def black(self) -> bool:
        """Nothing is scattered: leaves and ground absorb all they intercept."""
        return self.scattering == 0.0 and self.ground_reflectance == 0.0


#: Maize defaults per band (module docstring).
DEFAULT_OPTICS = {"par": Optics(0.10, 0.05, 0.10, "par"),
                  "nir": Optics(0.45, 0.40, 0.25, "nir")}


def optics_for(band: str = "par", reflectance: float | None = None,
               transmittance: float | None = None,
               ground_reflectance: float | None = None) -> Optics:
    """The band's default optics with any value given replacing its default.

    Raises
    ------
    MaizevizError
        An unknown band, a value outside [0, 1] or a leaf scattering more than 1.
    """
    if band not in DEFAULT_OPTICS:
        raise MaizevizError(f"unknown band '{band}' (known: {', '.join(BANDS)})",
                            quantity="band")
    d = DEFAULT_OPTICS[band]
    return Optics(d.reflectance if reflectance is None else reflectance,
                  d.transmittance if transmittance is None else transmittance,
                  d.ground_reflectance if ground_reflectance is None else ground_reflectance,
                  band)
