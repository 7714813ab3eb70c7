"""Trace until a figure's Monte Carlo standard error and its bias from the density both meet
a target.

A traced figure's standard error falls as one over the square root of its rays; after one
trace at density ``d`` with relative standard error ``e``, a target ``t`` needs about
``d (e / t)^2`` rays per cm2.

The standard error does not show a bias. A figure that is a non-linear function of light
estimated from a few rays per leaf (assimilation through a concave leaf model) comes out low by
an amount that shrinks as the density grows, in proportion to the variance of the light each
leaf's model sees, so as ``1 / d``: ``F(d) = F - c / d``. The same rays, split into two halves
of their batches, give two figures at ``d / 2``; the mean of those minus ``F(d)`` estimates
``-c / d``, the bias of ``F(d)`` (the jackknife's idea, Efron & Tibshirani 1993, with halves;
Richardson's extrapolation to infinite density from ``d / 2`` and ``d``), without another
trace and with little noise (the rays' linear noise cancels). The leaf models' results carry
it (:func:`~maizeviz.light.results.assimilation.assimilate`); absorbed light is linear in the
rays and has none. A bias of ``b`` at ``d`` needs about ``d |b| / t`` rays per cm2.

:func:`trace_until` traces, reads the standard error from the result's independent batches and
the bias from its halves, and traces again at the density that should meet the target (with a
margin, at least double), until both are met or the density would pass its ceiling.

References
----------
Efron, B. & Tibshirani, R. J. (1993). An Introduction to the Bootstrap. Chapman & Hall
(chapter 10, the jackknife estimate of bias).
Richardson, L. F. (1911). The approximate arithmetical solution by finite differences of
physical problems involving differential equations. Philosophical Transactions of the Royal
Society A 210, 307-357. https://doi.org/10.1098/rsta.1911.0009
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from maizeviz.errors import MaizevizError, check_range

#: Densities (rays per cm2) :func:`trace_until` will not go beyond.
MAX_DENSITY = 1024.0
#: Extra rays asked for beyond the estimate (the error estimate is itself noisy).
MARGIN = 1.2
#: Spreads of the bias estimate added to it before it is held against the target.
BIAS_SIGMAS = 2.0


@dataclass(frozen=True)
class Precision:
    """How a target standard error and bias were met.

    Attributes
    ----------
    target : float
        Relative standard error, and relative bias, asked for (0.005: 0.5 % of the figure).
    achieved : float
        Relative standard error of the last trace.
    density : float
        Rays per cm2 of the last trace.
    passes : int
        Traces made.
    bias : float
        Relative bias of the last trace from its density (negative: low; 0 for a figure
        linear in the rays).
    bias_se : float
        Spread of ``bias`` over the halvings it was estimated from.
    """

    target: float
    achieved: float
    density: float
    passes: int
    bias: float = 0.0
    bias_se: float = 0.0

    @property
    def noise_met(self) -> bool:
        """Whether the standard error is at most the target."""
        return self.achieved <= self.target

    @property
    def bias_met(self) -> bool:
        """Whether the bias, plus two of its spreads, is at most the target."""
        return abs(self.bias) + BIAS_SIGMAS * self.bias_se <= self.target

    @property
    def met(self) -> bool:
        """Whether both the standard error and the bias meet the target."""
        return self.noise_met and self.bias_met

    def as_dict(self) -> dict[str, Any]:
        """The record the command line's JSON carries (``precision``).

        Returns
        -------
        dict
            The target, the relative standard error and bias (with its spread), the density,
            the passes, and whether each and both were met.
        """
        return {"target_relative_se": self.target, "relative_se": self.achieved,
                "relative_bias": self.bias, "relative_bias_se": self.bias_se,
                "noise_met": self.noise_met, "bias_met": self.bias_met,
                "density_per_cm2": self.density, "passes": self.passes, "met": self.met}


def check_precision(target: float) -> None:
    """Refuse a target that is not a relative standard error in (0, 0.5]."""
    check_range(target, "the target relative standard error", 1e-6, 0.5, "precision")


def next_density(prec: Precision, ceiling: float) -> float:
    """Rays per cm2 that should meet the target after ``prec`` missed it: the standard error's
    ``1 / sqrt(rays)`` law and the bias's ``1 / rays``, with a margin, at least double."""
    d = prec.density
    noise = d * (prec.achieved / prec.target) ** 2
    bias = d * (abs(prec.bias) + BIAS_SIGMAS * prec.bias_se) / prec.target
    return min(ceiling, max(2.0 * d, max(noise, bias) * MARGIN))


def trace_until(trace: Callable[[float], tuple], density: float, target: float,
                max_density: float | None = None) -> tuple[Any, Precision]:
    """Trace at ``density`` and denser until the figure's relative standard error and its
    relative bias from the density are at most ``target``.

    Parameters
    ----------
    trace : callable
        ``trace(density) -> (result, figure, standard_error)``, or ``(result, figure,
        standard_error, bias, bias_spread)`` for a figure with a bias from the density (all
        in the figure's unit).
    density : float
        Rays per cm2 of the first trace.
    target : float
        Relative standard error wanted (standard error / figure), and the largest relative
        bias.
    max_density : float, optional
        Rays per cm2 not to exceed (the last trace may then miss the target; default
        :data:`MAX_DENSITY`).

    Returns
    -------
    tuple
        The last result, and a :class:`Precision` saying how it went.
    """
    check_precision(target)
    ceiling = MAX_DENSITY if max_density is None else max_density
    passes = 0
    while True:
        result, figure, se, *rest = trace(density)
        passes += 1
        if not figure:
            raise MaizevizError("the traced figure is 0: no standard error relative to it "
                                "can be met (is the sun up, the canopy lit?)",
                                quantity="precision")
        bias, spread = (float(rest[0] or 0.0), float(rest[1] or 0.0)) if rest else (0.0, 0.0)
        prec = Precision(target, abs(se / figure), density, passes, bias / abs(figure),
                         spread / abs(figure))
        if prec.met or density >= ceiling:
            return result, prec
        density = next_density(prec, ceiling)
