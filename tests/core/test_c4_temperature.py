"""The C4 model's two temperature responses against independent implementations of their
published equations.

Collatz, Ribas-Carbo & Berry (1992), appendix B, equation set 5B (as BioCro's
``collatz_photo`` and JULES' C4 ``tupp``/``tlow`` code it)::

    Vmax(T) = Vmax25 2^((T - 25)/10) / ((1 + exp(0.3 (13 - T))) (1 + exp(0.3 (T - 36))))
    Rd(T)   = Rd25   2^((T - 25)/10) / (1 + exp(1.3 (T - 55)))
    k(T)    = k25    2^((T - 25)/10)

CLM 4.5 (Oleson et al. 2013, section 8.2; Bonan 2019, chapter 11) keeps Rd and k and changes
the Vmax fall: ``(1 + exp(0.3 (T - 40))) (1 + exp(0.2 (15 - T)))``. The functions below are
written from those equations in plain Python floats (math.exp, math.pow), not from maizeviz.
"""

import math

import numpy as np
import pytest

import maizeviz as mv
from maizeviz.errors import MaizevizError
from maizeviz.photosynthesis.c4 import C4Leaf
from maizeviz.photosynthesis.split import leaf_model, model_from_dict


def collatz_vmax(t: float, v25: float = 39.0) -> float:
    return v25 * math.pow(2.0, (t - 25.0) / 10.0) / (
        (1.0 + math.exp(0.3 * (13.0 - t))) * (1.0 + math.exp(0.3 * (t - 36.0))))


def clm45_vmax(t: float, v25: float = 39.0) -> float:
    return v25 * math.pow(2.0, (t - 25.0) / 10.0) / (
        (1.0 + math.exp(0.3 * (t - 40.0))) * (1.0 + math.exp(0.2 * (15.0 - t))))


def rd(t: float, rd25: float = 0.8) -> float:
    return rd25 * math.pow(2.0, (t - 25.0) / 10.0) / (1.0 + math.exp(1.3 * (t - 55.0)))


def gross(q: float, t: float, vmax_t: float, ci_ppm: float = 160.0) -> float:
    """Collatz et al.'s two quadratics (eqs. 2B, 3B) by the textbook root formula."""
    aq = 0.04 * q
    b = vmax_t + aq
    m = (b - math.sqrt(b * b - 4 * 0.83 * vmax_t * aq)) / (2 * 0.83)
    kc = 0.7 * math.pow(2.0, (t - 25.0) / 10.0) * ci_ppm
    b = m + kc
    return (b - math.sqrt(b * b - 4 * 0.93 * m * kc)) / (2 * 0.93)


TEMPS = [-5.0, 0.0, 10.0, 13.0, 20.0, 25.0, 30.0, 35.0, 36.0, 40.0, 45.0, 50.0, 56.0]


@pytest.mark.parametrize("form, vmax_of", [("collatz", collatz_vmax), ("clm45", clm45_vmax)])
def test_vmax_rd_and_k_are_the_published_equations(form, vmax_of):
    leaf = C4Leaf(temperature_response=form)
    t = np.array(TEMPS)
    np.testing.assert_allclose(leaf.vmax_at(t), [vmax_of(x) for x in TEMPS], rtol=1e-12)
    np.testing.assert_allclose(leaf.respiration(t), [rd(x) for x in TEMPS], rtol=1e-12)
    np.testing.assert_allclose(leaf.k_at(t), [0.7 * 2 ** ((x - 25) / 10) for x in TEMPS],
                               rtol=1e-12)


@pytest.mark.parametrize("form, vmax_of", [("collatz", collatz_vmax), ("clm45", clm45_vmax)])
def test_gross_assimilation_over_light_and_temperature(form, vmax_of):
    leaf = C4Leaf(temperature_response=form)
    for t in TEMPS:
        for q in (0.0, 50.0, 400.0, 1200.0, 2500.0):
            want = gross(q, t, vmax_of(t))
            # the model's cancellation-free root and the textbook one agree to rounding
            assert float(leaf.gross_umol(q, t)) == pytest.approx(want, rel=1e-9, abs=1e-12)


def test_the_figures_the_issue_quotes():
    """Maize parameters: the paper's response gives Vmax 44.7 at 35 C and 25.5 at 40 C;
    CLM 4.5's 62.6 and 54.8 (1.4 and 2.1 times)."""
    paper, clm = C4Leaf(), C4Leaf(temperature_response="clm45")
    assert paper.temperature_response == "collatz"
    assert float(paper.vmax_at(35.0)) == pytest.approx(44.7, abs=0.05)
    assert float(paper.vmax_at(40.0)) == pytest.approx(25.5, abs=0.05)
    assert float(clm.vmax_at(35.0)) == pytest.approx(62.6, abs=0.05)
    assert float(clm.vmax_at(40.0)) == pytest.approx(54.8, abs=0.05)


def test_the_response_is_named_in_the_record_and_old_records_read_as_clm45():
    rec = C4Leaf().as_dict()
    assert rec["temperature_response"] == "collatz"
    assert model_from_dict(rec) == C4Leaf()
    assert model_from_dict(C4Leaf(temperature_response="clm45").as_dict()) == \
        C4Leaf(temperature_response="clm45")
    # what maizeviz 0.2 wrote: its CLM constants, no response named
    old = {"model": "c4", "vmax": 39.0, "alpha": 0.04, "k": 0.7, "theta": 0.83,
           "beta": 0.93, "rd": 0.8, "q10": 2.0, "co2_ppm": 400.0, "ci_ratio": 0.4,
           "s1": 0.3, "s2": 40.0, "s3": 0.2, "s4": 15.0, "s5": 1.3, "s6": 55.0}
    assert model_from_dict(old).temperature_response == "clm45"
    assert "Collatz et al. 1992" in C4Leaf().label
    assert "CLM 4.5" in C4Leaf(temperature_response="clm45").label


def test_an_unknown_response_is_one_line_naming_the_choices():
    with pytest.raises(MaizevizError, match="temperature_response.*collatz, clm45"):
        leaf_model("c4", temperature_response="arrhenius")
    assert mv.leaf_model("c4", temperature_response="CLM45").temperature_response == "clm45"
