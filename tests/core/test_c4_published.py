"""The C4 leaf model against its paper, and canopy light use against the leaf models' own
ceilings.

Collatz, Ribas-Carbo & Berry (1992, Aust. J. Plant Physiol. 19: 519-538) give the model as two
quadratics whose smaller root is the co-limited rate (their equations 2 and 3) and fit it to
maize leaves (their Table 2: Vmax 39 umol/m2/s, alpha 0.04, k 0.7 mol/m2/s, theta 0.83, beta
0.93, Rd 0.8, Q10 2). The plotted points of their figures could not be read here (no copy of
the paper within reach of the search tools), so the response curves are derived from those
equations and values by another route than maizeviz's (numpy.roots on each quadratic, the
smaller real root taken, against maizeviz's cancellation-free closed form), over the light
and CO2 ranges the paper's gas-exchange figures span; BioCro's ``collatz_c4_assimilation``
(biocro/biocro, src/module_library) solves the same two quadratics the same way.

The canopy checks need no source: a leaf model never fixes more CO2 than its initial slope
times the photons absorbed (C4: alpha; WOFOST: EFF, which is 0.062 mol CO2 per mol of
absorbed photons), so a day's gross assimilation per MJ of absorbed PAR is bounded by
alpha x 4.57 x 44.01 g CO2 per MJ (8.04 g for alpha 0.04); it approaches that bound in dim
diffuse light and falls below it in bright sun (docs/validation.md, radiation-use
efficiency).
"""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from maizeviz.photosynthesis.c4 import C4Leaf
from maizeviz.photosynthesis.units import PAR_UMOL_PER_J, kg_ha_h
from maizeviz.photosynthesis.wofost import WofostLeaf

sys.path.insert(0, str(Path(__file__).parent))
from test_scatter import patches  # noqa: E402

#: Collatz et al. (1992), Table 2 (maize).
TABLE2 = {"vmax": 39.0, "alpha": 0.04, "k": 0.7, "theta": 0.83, "beta": 0.93, "rd": 0.8,
          "q10": 2.0}
#: mol CO2 per mol (44.01 g).
CO2_G = 44.01


def _smaller_root(a: float, b: float, c: float) -> float:
    """The smaller real root of a x^2 + b x + c = 0 by numpy.roots (companion matrix
    eigenvalues), not by the closed form the model uses."""
    roots = np.roots([a, b, c])
    real = roots[np.abs(roots.imag) <= 1e-9 * max(1.0, np.abs(roots).max())].real
    return float(real.min())


def _paper(q: float, ci_ppm: float, vt: float, kt: float) -> float:
    """Gross assimilation [umol/m2/s] from Collatz et al.'s equations at Table 2's curvatures:
    theta M^2 - M (Vt + alpha Q) + Vt alpha Q = 0, then beta A^2 - A (M + kt ci) + M kt ci = 0
    (ci as a mole fraction, kt in mol/m2/s: kt ci in umol/m2/s for ci in umol/mol)."""
    aq = TABLE2["alpha"] * q
    m = _smaller_root(TABLE2["theta"], -(vt + aq), vt * aq)
    kc = kt * ci_ppm
    return _smaller_root(TABLE2["beta"], -(m + kc), m * kc)


def test_the_model_holds_the_papers_maize_parameters():
    leaf = C4Leaf()
    assert {k: getattr(leaf, k) for k in TABLE2} == TABLE2


@pytest.mark.parametrize("ci_ppm", [40.0, 100.0, 160.0, 300.0])
def test_light_response_is_the_papers_equations(ci_ppm):
    """A against absorbed photon flux 0-2000 umol/m2/s at 25 C, at four intercellular CO2
    levels (the light-response families of the paper's gas exchange): maizeviz's closed form
    equals the quadratics solved by numpy.roots to 1e-9."""
    leaf = C4Leaf()
    vt, kt = float(leaf.vmax_at(25.0)), float(leaf.k_at(25.0))
    q = np.linspace(0.0, 2000.0, 41)
    got = leaf.gross_umol(q, 25.0, ci_ppm)
    want = [_paper(x, ci_ppm, vt, kt) for x in q]
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
    # the curve's shape as the paper describes it: slope alpha in the dark, a plateau set by
    # the lower of Vt and kt ci in bright light
    assert (got[1] - got[0]) / (q[1] - q[0]) == pytest.approx(0.04, rel=0.1)
    assert got[-1] < min(vt, kt * ci_ppm) and got[-1] > 0.8 * min(vt, kt * ci_ppm)


@pytest.mark.parametrize("q", [200.0, 500.0, 1000.0, 2000.0])
def test_co2_response_is_the_papers_equations(q):
    """A against intercellular CO2 0-600 umol/mol at 25 C, at four photon fluxes (the
    A-ci families): to 1e-9; first order in ci with slope k = 0.7 near zero; saturating at
    the light-Rubisco rate M once ci is high."""
    leaf = C4Leaf()
    vt, kt = float(leaf.vmax_at(25.0)), float(leaf.k_at(25.0))
    ci = np.linspace(0.0, 600.0, 61)
    got = leaf.gross_umol(q, 25.0, ci)
    want = [_paper(q, c, vt, kt) for c in ci]
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
    tiny = leaf.gross_umol(q, 25.0, np.array([0.0, 0.01]))
    assert (tiny[1] - tiny[0]) / 0.01 == pytest.approx(0.7, rel=1e-2)
    m = _smaller_root(TABLE2["theta"], -(vt + 0.04 * q), vt * 0.04 * q)
    assert got[-1] == pytest.approx(m, rel=0.03)


def test_wofost_eff_in_photons_and_the_c4_ceiling():
    """WOFOST's EFF 0.45 kg CO2/ha/h per J/m2/s is 0.062 mol CO2 per mol of absorbed photons
    (at 4.57 umol/J): half again the C4 model's alpha. The C4 ceiling per MJ of absorbed PAR
    is alpha x 4.57 mol x 44.01 g = 8.04 g CO2."""
    eff_umol = 0.45 / kg_ha_h(1.0)             # umol CO2/m2/s per W/m2 of absorbed PAR
    assert eff_umol / PAR_UMOL_PER_J == pytest.approx(0.0622, abs=5e-4)
    w = WofostLeaf()
    assert float(w.gross(1e-3)) / 1e-3 == pytest.approx(eff_umol, rel=1e-3)
    assert 0.04 * PAR_UMOL_PER_J * CO2_G == pytest.approx(8.04, abs=0.01)


def _overcast(tmp_path, factor=0.35):
    """A Beijing day as a weather file: the clear day's ghi times ``factor``, all diffuse."""
    import maizeviz as mv
    from maizeviz.light.sources.irradiance import read_weather, weather_period

    clear = mv.clear_sky_period("2005-08-01", 39.9, 116.4, "Asia/Shanghai", 120)
    lines = ["time,ghi,dhi,temp_air"]
    for t, g in zip(clear.times, clear.ghi):
        lines.append(f"{t.isoformat()},{factor * float(g):.3f},{factor * float(g):.3f},28")
    path = tmp_path / "overcast.csv"
    path.write_text("\n".join(lines) + "\n")
    return clear, weather_period(read_weather(path), 39.9, 116.4)


def test_a_days_light_use_stays_under_the_quantum_yield_and_nears_it_in_dim_light(tmp_path):
    """Gross CO2 per MJ of PAR the leaves absorb, over a clear day and an overcast one (35 %
    of it, all diffuse), on a spherical canopy of LAI 4 at 28 C: never above the model's
    ceiling (C4: 8.04 g CO2/MJ, 3.2 g of dry matter, whatever the day; WOFOST: EFF's 12.5);
    within 15 % of it under the overcast sky, lower on the clear day, where sunlit leaves use
    less of each photon (measured: C4 0.96 and 0.76, WOFOST 0.87 and 0.61). The ceiling, not
    the clear day, is what keeps the C4 model below maize's season RUE (docs/validation.md)."""
    import maizeviz as mv

    canopy = patches(4.0, 100.0, seed=5)
    eng = mv.LightEngine(canopy, periodic=True, density=0.5, heights_cm=(0.0,))
    clear, overcast = _overcast(tmp_path)
    ceilings = {"c4": 0.04 * PAR_UMOL_PER_J * CO2_G,
                "wofost": 0.45 / kg_ha_h(1.0) * CO2_G}
    use = {}
    for name, ceiling in ceilings.items():
        for label, period in (("clear", clear), ("overcast", overcast)):
            day = eng.absorbed_day(period, directions=16, photosynthesis=mv.leaf_model(name),
                                   temperature_c=28.0)
            absorbed_mj = day.balance.absorbed_leaves
            use[name, label] = day.assimilation.canopy_gross_g_m2 / absorbed_mj
            assert 0 < use[name, label] <= ceiling * (1 + 1e-9)
        assert use[name, "overcast"] > 0.85 * ceiling
        assert use[name, "clear"] < use[name, "overcast"]
    # WOFOST's steeper initial slope uses more of the same light than the C4 model's alpha
    assert use["wofost", "overcast"] > use["c4", "overcast"]
    assert math.isfinite(sum(use.values()))
