"""The C4 leaf photosynthesis model of Collatz, Ribas-Carbo & Berry (1992), with its maize
parameters.

Gross assimilation ``A`` (umol CO2 per m2 of leaf per s) is co-limited by three rates, each
first order in one quantity:

- light: ``alpha Q``, ``Q`` the PAR photons the leaf absorbs (umol/m2/s);
- Rubisco: ``Vmax(T)``;
- CO2 (PEP carboxylase): ``k(T) ci / P``, ``ci / P`` the intercellular CO2 mole fraction.

Two quadratics join them smoothly (the smaller root of each)::

    theta M^2 - M (Vmax(T) + alpha Q) + Vmax(T) alpha Q = 0
    beta A^2  - A (M + k(T) ci/P)     + M k(T) ci/P     = 0

and the leaf respires ``Rd(T)`` (net assimilation ``A - Rd``). Temperatures act through a Q10
and, for ``Vmax``, a fall at both ends and for ``Rd`` above 55 C::

    Vmax(T) = Vmax25 Q10^((T - 25)/10) / ((1 + exp(s1 (T - s2))) (1 + exp(s3 (s4 - T))))
    Rd(T)   = Rd25   Q10^((T - 25)/10) / (1 + exp(s5 (T - s6)))
    k(T)    = k25    Q10^((T - 25)/10)

Parameters (Collatz et al. 1992, Table 2, fitted to gas exchange of maize leaves): Vmax 39
umol/m2/s, alpha 0.04 mol CO2 per mol of absorbed photons, k 0.7 mol/m2/s, theta 0.83, beta
0.93, Rd 0.8 umol/m2/s, Q10 2; the temperature limits s1 = 0.3 /C above s2 = 40 C, s3 = 0.2 /C
below s4 = 15 C, s5 = 1.3 /C above s6 = 55 C as the Community Land Model documents them for
this model (Oleson et al. 2013, section 8.2). Stomata are not modelled: ``ci`` is a fixed share
of the ambient CO2 (0.4 for C4 leaves, the model's own starting value; ``ci_ratio``).

References
----------
Collatz, G. J., Ribas-Carbo, M. & Berry, J. A. (1992). Coupled photosynthesis-stomatal
conductance model for leaves of C4 plants. Australian Journal of Plant Physiology 19, 519-538.
Oleson, K. W. et al. (2013). Technical description of version 4.5 of the Community Land Model
(CLM). NCAR Technical Note NCAR/TN-503+STR (section 8.2, the C4 temperature functions).
Bonan, G. (2019). Climate Change and Terrestrial Ecosystem Modeling. Cambridge University
Press (chapter 11: the same model and temperature functions).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from maizeviz.errors import check_range
from maizeviz.photosynthesis.units import PAR_UMOL_PER_J


def smaller_root(curvature, a, b):
    """Smaller root of ``curvature x^2 - (a + b) x + a b = 0`` (a, b >= 0, curvature in
    (0, 1]): the co-limited rate of two limits ``a`` and ``b``, never above either.

    Written as ``2 a b / (s + sqrt(s^2 - 4 curvature a b))`` (``s = a + b``): no cancellation
    when one limit is tiny (dim light), and 0 when either is 0.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    s = a + b
    disc = np.maximum(s * s - 4.0 * curvature * a * b, 0.0)
    den = s + np.sqrt(disc)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, 2.0 * a * b / np.where(den > 0, den, 1.0), 0.0)


@dataclass(frozen=True)
class C4Leaf:
    """Collatz et al.'s (1992) C4 leaf (see the module docstring), maize parameters by default.

    Parameters
    ----------
    vmax : float
        Rubisco capacity at 25 C [umol CO2 m-2 s-1].
    alpha : float
        Quantum yield [mol CO2 per mol of absorbed PAR photons].
    k : float
        Initial slope of the CO2 response at 25 C [mol m-2 s-1].
    theta, beta : float
        Curvatures of the light-Rubisco and of the CO2 co-limitation [-].
    rd : float
        Leaf (dark) respiration at 25 C [umol CO2 m-2 s-1].
    q10 : float
        Q10 of Vmax, k and Rd [-].
    co2_ppm : float
        Ambient CO2 [umol mol-1].
    ci_ratio : float
        Intercellular over ambient CO2 [-].
    s1, s2 : float
        Vmax falls above ``s2`` [degC] with steepness ``s1`` [degC-1].
    s3, s4 : float
        Vmax falls below ``s4`` [degC] with steepness ``s3`` [degC-1].
    s5, s6 : float
        Rd falls above ``s6`` [degC] with steepness ``s5`` [degC-1].

    References
    ----------
    Collatz, G. J., Ribas-Carbo, M. & Berry, J. A. (1992). Coupled photosynthesis-stomatal
    conductance model for leaves of C4 plants. Australian Journal of Plant Physiology 19,
    519-538. https://doi.org/10.1071/PP9920519
    """

    vmax: float = 39.0
    alpha: float = 0.04
    k: float = 0.7
    theta: float = 0.83
    beta: float = 0.93
    rd: float = 0.8
    q10: float = 2.0
    co2_ppm: float = 400.0
    ci_ratio: float = 0.4
    s1: float = 0.3
    s2: float = 40.0
    s3: float = 0.2
    s4: float = 15.0
    s5: float = 1.3
    s6: float = 55.0

    name = "c4"

    def __post_init__(self) -> None:
        for field_, low, high in (("vmax", 0, 500), ("alpha", 0, 0.125), ("k", 0, 100),
                                  ("theta", 0.01, 1), ("beta", 0.01, 1), ("rd", 0, 50),
                                  ("q10", 1, 5), ("co2_ppm", 0, 5000), ("ci_ratio", 0, 1)):
            check_range(getattr(self, field_), f"the C4 model's {field_}", low, high,
                        "photosynthesis")
            object.__setattr__(self, field_, float(getattr(self, field_)))

    # ------------------------------------------------------------------ temperature
    def _q10(self, temp_c):
        return self.q10 ** ((np.asarray(temp_c, dtype=np.float64) - 25.0) / 10.0)

    def vmax_at(self, temp_c):
        """Rubisco capacity at a leaf temperature.

        Parameters
        ----------
        temp_c : float or numpy.ndarray
            Leaf temperature [degC].

        Returns
        -------
        numpy.ndarray
            Vmax(T) [umol CO2 m-2 s-1].
        """
        t = np.asarray(temp_c, dtype=np.float64)
        return self.vmax * self._q10(t) / ((1.0 + np.exp(self.s1 * (t - self.s2)))
                                           * (1.0 + np.exp(self.s3 * (self.s4 - t))))

    def k_at(self, temp_c):
        """Initial slope of the CO2 response at a leaf temperature.

        Parameters
        ----------
        temp_c : float or numpy.ndarray
            Leaf temperature [degC].

        Returns
        -------
        numpy.ndarray
            The slope k(T) [mol m-2 s-1].
        """
        return self.k * self._q10(temp_c)

    def respiration(self, temp_c):
        """Leaf respiration at a leaf temperature.

        Parameters
        ----------
        temp_c : float or numpy.ndarray
            Leaf temperature [degC].

        Returns
        -------
        numpy.ndarray
            Rd(T) [umol CO2 m-2 of leaf s-1].
        """
        t = np.asarray(temp_c, dtype=np.float64)
        return self.rd * self._q10(t) / (1.0 + np.exp(self.s5 * (t - self.s6)))

    # ------------------------------------------------------------------ assimilation
    def gross_umol(self, q_umol, temp_c=25.0, ci_ppm=None):
        """Gross assimilation of a leaf absorbing a photon flux.

        Parameters
        ----------
        q_umol : float or numpy.ndarray
            PAR photons absorbed [umol m-2 of leaf s-1].
        temp_c : float or numpy.ndarray
            Leaf temperature [degC] (broadcast against ``q_umol``).
        ci_ppm : float, optional
            Intercellular CO2 [umol mol-1] (default ``ci_ratio * co2_ppm``).

        Returns
        -------
        numpy.ndarray
            Gross assimilation [umol CO2 m-2 of leaf s-1].
        """
        ci = self.ci_ratio * self.co2_ppm if ci_ppm is None else ci_ppm
        light = self.alpha * np.maximum(np.asarray(q_umol, dtype=np.float64), 0.0)
        m = smaller_root(self.theta, self.vmax_at(temp_c), light)
        co2 = self.k_at(temp_c) * 1e6 * np.asarray(ci, dtype=np.float64) * 1e-6
        return smaller_root(self.beta, m, co2)

    def gross(self, par_w_m2, temp_c=25.0):
        """Gross assimilation of a leaf absorbing PAR.

        Parameters
        ----------
        par_w_m2 : float or numpy.ndarray
            PAR absorbed [W m-2 of leaf].
        temp_c : float or numpy.ndarray
            Leaf temperature [degC].

        Returns
        -------
        numpy.ndarray
            Gross assimilation [umol CO2 m-2 of leaf s-1].
        """
        return self.gross_umol(np.asarray(par_w_m2, dtype=np.float64) * PAR_UMOL_PER_J, temp_c)

    def as_dict(self) -> dict[str, float | str]:
        """The model as a record (its name and parameters).

        Returns
        -------
        dict
            ``{"model": "c4", ...}``.
        """
        return {"model": self.name, **asdict(self)}
