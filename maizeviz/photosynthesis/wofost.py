"""WOFOST's leaf light response: a negative exponential (Goudriaan 1982; Spitters et al. 1988).

A leaf absorbing ``I`` W/m2 of PAR assimilates (gross) ::

    AMAX (1 - exp(-EFF I / AMAX))      kg CO2 per ha of leaf per hour

``AMAX`` the rate at light saturation (kg CO2/ha leaf/h), ``EFF`` the initial light use
efficiency (kg CO2/ha/h per J/m2/s of absorbed PAR). As in WOFOST's canopy routine
(``assim`` in PCSE), the exponent's denominator is ``max(2, AMAX)``. WOFOST's maize
parameters: ``AMAX`` 70 (its ``AMAXTB`` before flowering) and ``EFF`` 0.45 (``EFFTB``). The
temperature and CO2 corrections WOFOST applies to AMAX at the crop level are not applied here:
give the AMAX of the day's conditions.

References
----------
Spitters, C. J. T., Toussaint, H. A. J. M. & Goudriaan, J. (1986). Separating the diffuse and
direct component of global radiation and its implications for modeling canopy photosynthesis.
Part II. Calculation of canopy photosynthesis. Agricultural and Forest Meteorology 38, 231-242.
Goudriaan, J. & van Laar, H. H. (1994). Modelling Potential Crop Growth Processes. Kluwer.
de Wit, A. et al. (2019). 25 years of the WOFOST cropping systems model. Agricultural Systems
168, 154-167 (PCSE, its Python implementation).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from maizeviz.errors import check_range
from maizeviz.photosynthesis.units import KG_HA_H_PER_UMOL_M2_S


@dataclass(frozen=True)
class WofostLeaf:
    """WOFOST's negative exponential light response (see the module docstring).

    Parameters
    ----------
    amax : float
        Gross assimilation at light saturation [kg CO2 ha-1 of leaf h-1].
    eff : float
        Initial light use efficiency [kg CO2 ha-1 h-1 per J m-2 s-1 of absorbed PAR].

    References
    ----------
    Spitters, C. J. T., Toussaint, H. A. J. M. & Goudriaan, J. (1986). Separating the
    diffuse and direct component of global radiation and its implications for modeling canopy
    photosynthesis. Part II. Calculation of canopy photosynthesis. Agricultural and Forest
    Meteorology 38, 231-242. https://doi.org/10.1016/0168-1923(86)90061-4
    """

    amax: float = 70.0
    eff: float = 0.45

    name = "wofost"

    @property
    def label(self) -> str:
        """The model in words (tables, the app)."""
        return "WOFOST negative exponential (Spitters et al. 1986)"

    def __post_init__(self) -> None:
        check_range(self.amax, "WOFOST's AMAX (kg CO2/ha leaf/h)", 0, 500, "photosynthesis")
        check_range(self.eff, "WOFOST's EFF (kg CO2/ha/h per J/m2/s)", 0, 5, "photosynthesis")
        object.__setattr__(self, "amax", float(self.amax))
        object.__setattr__(self, "eff", float(self.eff))

    def gross_kg_ha_h(self, par_w_m2):
        """Gross assimilation of a leaf absorbing PAR, in WOFOST's units.

        Parameters
        ----------
        par_w_m2 : float or numpy.ndarray
            PAR absorbed [W m-2 of leaf].

        Returns
        -------
        numpy.ndarray
            Gross assimilation [kg CO2 ha-1 of leaf h-1].
        """
        i = np.maximum(np.asarray(par_w_m2, dtype=np.float64), 0.0)
        return self.amax * -np.expm1(-i * self.eff / max(2.0, self.amax))

    def gross(self, par_w_m2, temp_c=25.0):
        """Gross assimilation of a leaf absorbing PAR.

        Parameters
        ----------
        par_w_m2 : float or numpy.ndarray
            PAR absorbed [W m-2 of leaf].
        temp_c : float or numpy.ndarray
            Leaf temperature [degC] (not used: see the module docstring).

        Returns
        -------
        numpy.ndarray
            Gross assimilation [umol CO2 m-2 of leaf s-1].
        """
        return self.gross_kg_ha_h(par_w_m2) / KG_HA_H_PER_UMOL_M2_S

    def respiration(self, temp_c):
        """Leaf respiration: 0, WOFOST books respiration at the crop level, not the leaf's.

        Parameters
        ----------
        temp_c : float or numpy.ndarray
            Leaf temperature [degC].

        Returns
        -------
        numpy.ndarray
            Zeros [umol CO2 m-2 of leaf s-1].
        """
        return np.zeros_like(np.asarray(temp_c, dtype=np.float64))

    def as_dict(self) -> dict[str, float | str]:
        """The model as a record (its name and parameters).

        Returns
        -------
        dict
            ``{"model": "wofost", "amax": ..., "eff": ...}``.
        """
        return {"model": self.name, **asdict(self)}
