"""Leaf photosynthesis models (maizeviz.photosynthesis) against what we did not write: the
closed forms of Collatz et al. (1992)'s C4 model in its limits, its parameters' own curves
(quantum yield, Rubisco ceiling, CO2 slope, temperature responses), WOFOST's leaf response as
PCSE's canopy routine computes it at the top of a thin canopy, and the sunlit/shaded split's
conservation and its Jensen gap."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.errors import MaizevizError
from maizeviz.photosynthesis.c4 import C4Leaf, smaller_root
from maizeviz.photosynthesis.split import (
    leaf_model,
    mean_assimilation,
    model_from_dict,
    split_assimilation,
)
from maizeviz.photosynthesis.units import KG_HA_H_PER_UMOL_M2_S, PAR_UMOL_PER_J, kg_ha_h
from maizeviz.photosynthesis.wofost import WofostLeaf


# ----------------------------------------------------------------------------- C4, limits
def test_c4_dim_light_slope_is_the_quantum_yield():
    """In dim light the light limit alone acts: dA/dQ -> alpha (0.04 mol/mol)."""
    leaf = C4Leaf()
    q = np.array([0.0, 0.5, 1.0])
    a = leaf.gross_umol(q, 25.0)
    assert a[0] == 0.0
    assert (a[2] - a[1]) / 0.5 == pytest.approx(0.04, rel=2e-3)


def test_c4_bright_light_high_co2_saturates_at_vmax_of_t():
    """Saturating light and CO2: A -> Vmax(T); at 25 C Vmax(25) = 39 / ((1 + e^-3.3)(1 + e^-3.6))
    (the two inhibition terms of Collatz et al.'s response at 25 C)."""
    leaf = C4Leaf()
    vmax25 = 39.0 / ((1 + math.exp(0.3 * (25 - 36))) * (1 + math.exp(0.3 * (13 - 25))))
    assert float(leaf.vmax_at(25.0)) == pytest.approx(vmax25, rel=1e-12)
    a = leaf.gross_umol(1e7, 25.0, ci_ppm=1e6)
    assert float(a) == pytest.approx(vmax25, rel=1e-3)


def test_c4_low_co2_is_first_order_in_ci_with_slope_k():
    """Bright light, little CO2: A -> k ci (k = 0.7 mol/m2/s at 25 C)."""
    leaf = C4Leaf()
    a = leaf.gross_umol(1e7, 25.0, ci_ppm=np.array([0.05, 0.1]))
    assert (a[1] - a[0]) / 0.05 == pytest.approx(0.7, rel=2e-3)


def test_c4_without_curvature_is_the_minimum_of_its_three_limits():
    """theta = beta = 1 turns the quadratics into Blackman's minimum (Collatz et al. 1992)."""
    leaf = C4Leaf(theta=1.0, beta=1.0)
    q = np.linspace(0, 3000, 31)
    for t, ci in ((15.0, 160.0), (25.0, 40.0), (33.0, 160.0)):
        limits = np.minimum(np.minimum(leaf.alpha * q, leaf.vmax_at(t)), leaf.k_at(t) * ci)
        np.testing.assert_allclose(leaf.gross_umol(q, t, ci), limits, rtol=1e-12, atol=1e-12)


def test_c4_maize_light_response_at_25_c_and_ambient_co2():
    """The parameters' curve at 25 C, ci = 160 umol/mol: light-limited in dim light, two
    thirds of Vmax(25) near 800 umol/m2/s absorbed, 0.85-0.95 of it at 2000 (the CO2 limit,
    112 umol/m2/s, still co-limits through beta = 0.93)."""
    leaf = C4Leaf()
    v = float(leaf.vmax_at(25.0))
    q = np.array([100.0, 800.0, 2000.0])
    a = leaf.gross_umol(q, 25.0)
    assert a[0] == pytest.approx(0.04 * 100, rel=0.05)
    assert 0.6 < a[1] / v < 0.8
    assert 0.85 < a[2] / v < 0.95


def test_c4_temperature_responses():
    """Q10 = 2 between 20 and 30 C away from the limits; Vmax peaks between 30 and 40 C, falls
    to under a fifth of its peak at 10 and 50 C; Rd doubles per 10 C up to 45 C then collapses
    above 55 C."""
    leaf = C4Leaf()
    t = np.arange(0.0, 60.01, 0.5)
    v = leaf.vmax_at(t)
    peak = t[np.argmax(v)]
    assert 30.0 <= peak <= 40.0
    assert leaf.vmax_at(10.0) < 0.2 * v.max() and leaf.vmax_at(50.0) < 0.2 * v.max()
    assert float(leaf.k_at(35.0) / leaf.k_at(25.0)) == pytest.approx(2.0, rel=1e-12)
    assert float(leaf.respiration(35.0) / leaf.respiration(25.0)) == pytest.approx(2.0,
                                                                                  rel=1e-6)
    assert float(leaf.respiration(60.0)) < 0.01 * float(leaf.respiration(45.0))


@settings(max_examples=200, deadline=None)
@given(q=st.floats(0, 4000, allow_subnormal=False), t=st.floats(-5, 55),
       ci=st.floats(0, 2000, allow_subnormal=False),
       theta=st.floats(0.05, 1.0), beta=st.floats(0.05, 1.0))
def test_c4_is_bounded_by_each_limit_and_grows_with_light_and_co2(q, t, ci, theta, beta):
    leaf = C4Leaf(theta=theta, beta=beta)
    a = float(leaf.gross_umol(q, t, ci))
    limits = (leaf.alpha * q, float(leaf.vmax_at(t)), float(leaf.k_at(t)) * ci)
    assert 0.0 <= a <= min(limits) * (1 + 1e-12) + 1e-300
    assert float(leaf.gross_umol(q * 1.1 + 1, t, ci)) >= a * (1 - 1e-12)
    assert float(leaf.gross_umol(q, t, ci * 1.1 + 1)) >= a * (1 - 1e-12)


@settings(max_examples=200, deadline=None)
@given(c=st.floats(0.05, 1.0), a=st.floats(0, 1e4), b=st.floats(0, 1e4))
def test_smaller_root_is_the_quadratics_smaller_root(c, a, b):
    x = float(smaller_root(c, a, b))
    roots = np.roots([c, -(a + b), a * b]).real if c * a * b > 0 else np.array([0.0])
    assert x == pytest.approx(float(roots.min()), rel=1e-8, abs=1e-9)


# ----------------------------------------------------------------------------- WOFOST
def test_units():
    assert KG_HA_H_PER_UMOL_M2_S == pytest.approx(1.584342, rel=1e-6)
    assert float(kg_ha_h(1.0)) == KG_HA_H_PER_UMOL_M2_S


def test_wofost_leaf_is_pcse_assim7_at_the_top_of_a_thin_canopy():
    """PCSE's canopy routine over a canopy of LAI 1e-6 under diffuse light alone is the leaf
    response at the top times the LAI: AMAX (1 - exp(-EFF I / AMAX)) with I the absorbed
    diffuse PAR (1 - REFS) PARDIF KDIF."""
    from pcse.crop.assimilation import assim7

    for amax, eff in ((70.0, 0.45), (40.0, 0.5), (1.5, 0.45)):
        leaf = WofostLeaf(amax, eff)
        for sinb, pardif in ((0.5, 50.0), (0.8, 200.0), (0.3, 400.0)):
            lai = 1e-6
            kdif = 0.72
            refh = (1 - math.sqrt(0.8)) / (1 + math.sqrt(0.8))
            refs = refh * 2 / (1 + 1.6 * sinb)
            i_abs = (1 - refs) * pardif * kdif
            expect = assim7(amax, eff, lai, kdif, sinb, 0.0, pardif) / lai
            assert float(leaf.gross_kg_ha_h(i_abs)) == pytest.approx(expect, rel=1e-5)


def test_wofost_in_umol():
    leaf = WofostLeaf(70.0, 0.45)
    assert float(leaf.gross(1e6)) == pytest.approx(70.0 / KG_HA_H_PER_UMOL_M2_S)
    # initial slope: EFF kg/ha/h per W/m2 -> umol CO2 per umol photon
    slope = float(leaf.gross(1e-3)) / (1e-3 * PAR_UMOL_PER_J)
    assert slope == pytest.approx(0.45 / KG_HA_H_PER_UMOL_M2_S / PAR_UMOL_PER_J, rel=1e-4)


# ----------------------------------------------------------------------------- the split
@pytest.mark.parametrize("name", ["c4", "wofost"])
def test_split_conserves_and_keeps_below_the_mean(name):
    model = leaf_model(name)
    rng = np.random.default_rng(3)
    n = 500
    area = rng.uniform(1e-4, 4e-4, n)
    lit = area * rng.uniform(0, 1, n)
    lit[:50] = 0.0
    direct = np.where(lit > 0, lit * rng.uniform(0, 400, n), 0.0)
    bg = area * rng.uniform(0, 80, n)
    got = split_assimilation(model, area, lit, direct, bg, 25.0)
    # by hand
    hand = lit * model.gross(bg / area + np.where(lit > 0, direct / np.maximum(lit, 1e-300), 0),
                             25.0) + (area - lit) * model.gross(bg / area, 25.0)
    np.testing.assert_allclose(got, hand, rtol=1e-12)
    mean = mean_assimilation(model, area, direct + bg, 25.0)
    assert np.all(got <= mean * (1 + 1e-12))                           # concave response
    np.testing.assert_allclose(got[:50], mean[:50], rtol=1e-12)        # all shaded: the same
    whole = split_assimilation(model, area, area, direct, bg, 25.0)     # all lit: the mean
    np.testing.assert_allclose(whole, mean_assimilation(model, area, direct + bg), rtol=1e-12)


def test_models_by_name_and_bad_parameters_are_one_line():
    assert leaf_model("C4", vmax=30).vmax == 30.0
    assert leaf_model("wofost", amax=None).amax == 70.0
    m = leaf_model("wofost", amax=55, eff=0.4)
    assert model_from_dict(m.as_dict()) == m
    assert model_from_dict(C4Leaf().as_dict()) == C4Leaf()
    for bad in (lambda: leaf_model("c3"), lambda: leaf_model("c4", amax=3),
                lambda: leaf_model("wofost", amax=-1), lambda: C4Leaf(theta=0),
                lambda: C4Leaf(co2_ppm=float("nan")), lambda: model_from_dict({"x": 1})):
        with pytest.raises(MaizevizError) as err:
            bad()
        assert err.value.quantity == "photosynthesis" and "\n" not in str(err.value)
