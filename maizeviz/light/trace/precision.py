"""Trace until a figure's Monte Carlo standard error meets a target.

A traced figure's standard error falls as one over the square root of its rays; after one
trace at density ``d`` with relative standard error ``e``, a target ``t`` needs about
``d (e / t)^2`` rays per cm2. :func:`trace_until` traces, reads the error from the result's
independent batches, and traces again at the density that should meet the target (with a
margin), until it is met or the density would pass its ceiling.
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


@dataclass(frozen=True)
class Precision:
    """How a target standard error was met.

    Attributes
    ----------
    target : relative standard error asked for (0.005: 0.5 % of the figure)
    achieved : relative standard error of the last trace
    density : rays per cm2 of the last trace; passes : traces made
    met : whether ``achieved <= target``
    """

    target: float
    achieved: float
    density: float
    passes: int

    @property
    def met(self) -> bool:
        return self.achieved <= self.target

    def as_dict(self) -> dict[str, Any]:
        return {"target_relative_se": self.target, "relative_se": self.achieved,
                "density_per_cm2": self.density, "passes": self.passes, "met": self.met}


def check_precision(target: float) -> None:
    """Refuse a target that is not a relative standard error in (0, 0.5]."""
    check_range(target, "the target relative standard error", 1e-6, 0.5, "precision")


def trace_until(trace: Callable[[float], tuple[Any, float, float]], density: float,
                target: float, max_density: float | None = None) -> tuple[Any, Precision]:
    """Trace at ``density`` and denser until the figure's relative standard error is at most
    ``target``.

    Parameters
    ----------
    trace : ``trace(density) -> (result, figure, standard_error)``
    density : rays per cm2 of the first trace
    target : relative standard error wanted (standard error / figure)
    max_density : rays per cm2 not to exceed (the last trace may then miss the target;
        default :data:`MAX_DENSITY`)

    Returns
    -------
    the last result, and a :class:`Precision` saying how it went
    """
    check_precision(target)
    ceiling = MAX_DENSITY if max_density is None else max_density
    passes = 0
    while True:
        result, figure, se = trace(density)
        passes += 1
        if not figure:
            raise MaizevizError("the traced figure is 0: no standard error relative to it "
                                "can be met (is the sun up, the canopy lit?)",
                                quantity="precision")
        rel = abs(se / figure)
        if rel <= target or density >= ceiling:
            return result, Precision(target, rel, density, passes)
        density = min(ceiling, max(2.0 * density,
                                        density * (rel / target) ** 2 * MARGIN))
