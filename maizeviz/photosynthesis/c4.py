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
    Rd(T)   = Rd25   Q10^((T - 25)/10) / (1 + exp(1.3 (T - 55)))
    k(T)    = k25    Q10^((T - 25)/10)

Two temperature responses of ``Vmax`` are offered (``temperature_response``):

- ``"collatz"`` (the default): the paper's own (Collatz et al. 1992, appendix B, equation set
  5B), ``s1 = s3 = 0.3 /C``, upper limit ``s2 = 36 C``, lower ``s4 = 13 C``; BioCro
  (``collatz_photo``) and JULES (``tupp``/``tlow`` of its C4 grass, Cox 2001) code the same.
  With maize parameters Vmax is 44.7 umol/m2/s at 35 C and 25.5 at 40 C.
- ``"clm45"``: the Community Land Model 4.5's (Oleson et al. 2013, section 8.2; Bonan 2019,
  chapter 11), ``s1 = 0.3 /C`` above ``s2 = 40 C``, ``s3 = 0.2 /C`` below ``s4 = 15 C``: 62.6
  at 35 C, 54.8 at 40 C; a bright leaf assimilates 1.3-1.9 times the paper's figure between
  35 and 40 C. maizeviz 0.2 computed with this one;
  results and projects saved then, which do not name a response, are read as it.

Parameters (Collatz et al. 1992, Table 2, fitted to gas exchange of maize leaves): Vmax 39
umol/m2/s, alpha 0.04, k 0.7 mol/m2/s, theta 0.83, beta 0.93, Rd 0.8 umol/m2/s, Q10 2. Stomata
are not modelled: ``ci`` is a fixed share of the ambient CO2 (0.4 for C4 leaves, the model's
own starting value; ``ci_ratio``).

The photon basis of alpha: absorbed photons. The paper's independent variable is the absorbed
quantum flux (its abstract); maizeviz feeds alpha the PAR each triangle absorbs (from the ray
tracing), as the land-surface models that carry this model do: JULES
multiplies its C4 alpha by ``apar = (1 - omega) ipar`` (Cox 2001; ``omega`` the leaf's
scattering coefficient) and CLM 4.5 by the PAR absorbed by sunlit and shaded leaves (Oleson et
al. 2013, section 8.1). BioCro's ``c4photo`` applies the same 0.04 to the photon flux incident
on the leaf (its ``Qp``): with a maize leaf's PAR absorptance of about 0.85 that is a light-
limited slope 1/0.85 = 1.18 times maizeviz's (alpha 0.047 here: 7.6 % more gross
assimilation on the bundled canopy's clear day in docs/validation.md, 82.89 against 77.04 g).
The 1992 paper fitted alpha to gas exchange of maize leaves; to reproduce a model that reads it
on incident light, give ``alpha / absorptance`` (``--alpha``).

References
----------
Collatz, G. J., Ribas-Carbo, M. & Berry, J. A. (1992). Coupled photosynthesis-stomatal
conductance model for leaves of C4 plants. Australian Journal of Plant Physiology 19, 519-538.
Collatz, G. J., Ball, J. T., Grivet, C. & Berry, J. A. (1991). Physiological and environmental
regulation of stomatal conductance, photosynthesis and transpiration. Agricultural and Forest
Meteorology 54, 107-136.
Cox, P. M. (2001). Description of the TRIFFID dynamic global vegetation model. Hadley Centre
Technical Note 24 (the C4 Vmax response as JULES codes it).
Oleson, K. W. et al. (2013). Technical description of version 4.5 of the Community Land Model
(CLM). NCAR Technical Note NCAR/TN-503+STR (section 8.2, the C4 temperature functions).
Bonan, G. (2019). Climate Change and Terrestrial Ecosystem Modeling. Cambridge University
Press (chapter 11: CLM's form of the model).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from maizeviz.errors import MaizevizError, check_range
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


#: The temperature responses of Vmax by name: ``(s1, s2, s3, s4)`` of the module docstring,
#: steepness above [degC-1], upper limit [degC], steepness below [degC-1], lower limit [degC].
TEMPERATURE_RESPONSES: dict[str, tuple[float, float, float, float]] = {
    "collatz": (0.3, 36.0, 0.3, 13.0),   # Collatz et al. 1992, appendix B, eq. set 5B
    "clm45": (0.3, 40.0, 0.2, 15.0),     # Oleson et al. 2013, CLM 4.5 section 8.2
}
#: The temperature response of maizeviz 0.2, which its records do not name.
LEGACY_TEMPERATURE_RESPONSE = "clm45"
#: The temperature responses in words, for tables and the app.
TEMPERATURE_RESPONSE_LABELS = {"collatz": "Collatz et al. 1992",
                               "clm45": "CLM 4.5 (Oleson et al. 2013)"}


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
    temperature_response : {"collatz", "clm45"}
        How Vmax falls in heat and cold: the paper's own (default) or CLM 4.5's
        (:data:`TEMPERATURE_RESPONSES`).

    References
    ----------
    Collatz, G. J., Ribas-Carbo, M. & Berry, J. A. (1992). Coupled photosynthesis-stomatal
    conductance model for leaves of C4 plants. Australian Journal of Plant Physiology 19,
    519-538. https://doi.org/10.1071/PP9920519
    Oleson, K. W. et al. (2013). Technical description of version 4.5 of the Community Land
    Model (CLM). NCAR/TN-503+STR. https://doi.org/10.5065/D6RR1W7M
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
    temperature_response: str = "collatz"

    name = "c4"

    def __post_init__(self) -> None:
        for field_, low, high in (("vmax", 0, 500), ("alpha", 0, 0.125), ("k", 0, 100),
                                  ("theta", 0.01, 1), ("beta", 0.01, 1), ("rd", 0, 50),
                                  ("q10", 1, 5), ("co2_ppm", 0, 5000), ("ci_ratio", 0, 1)):
            check_range(getattr(self, field_), f"the C4 model's {field_}", low, high,
                        "photosynthesis")
            object.__setattr__(self, field_, float(getattr(self, field_)))
        form = str(self.temperature_response).strip().lower()
        if form not in TEMPERATURE_RESPONSES:
            raise MaizevizError(f"the C4 model's temperature_response is "
                                f"'{self.temperature_response}', not one of "
                                f"{', '.join(TEMPERATURE_RESPONSES)}",
                                quantity="photosynthesis")
        object.__setattr__(self, "temperature_response", form)

    @property
    def label(self) -> str:
        """The model and its temperature response in words (tables, the app)."""
        return (f"C4, Collatz et al. 1992 (temperature response: "
                f"{TEMPERATURE_RESPONSE_LABELS[self.temperature_response]})")

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
        s1, s2, s3, s4 = TEMPERATURE_RESPONSES[self.temperature_response]
        return self.vmax * self._q10(t) / ((1.0 + np.exp(s1 * (t - s2)))
                                           * (1.0 + np.exp(s3 * (s4 - t))))

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
        # the same fall above 55 C in both responses (Collatz et al. 1992, eq. set 5B)
        return self.rd * self._q10(t) / (1.0 + np.exp(1.3 * (t - 55.0)))

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
        """The model as a record (its name, parameters and temperature response).

        Returns
        -------
        dict
            ``{"model": "c4", "vmax": 39.0, ..., "temperature_response": "collatz"}``.
        """
        return {"model": self.name, **asdict(self)}
