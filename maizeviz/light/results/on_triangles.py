"""What absorbed-light and assimilation results share: a value on every leaf triangle.

:class:`~maizeviz.light.results.absorbed.AbsorbedLight` and
:class:`~maizeviz.light.results.absorbed.AbsorbedPeriod` (W or J absorbed per scene triangle),
:class:`~maizeviz.light.results.assimilation.Assimilation` and
:class:`~maizeviz.light.results.assimilation.PeriodAssimilation` (umol/s or mol of CO2 per leaf
triangle) are :class:`TriangleResult`: each has its per-triangle values and optionally their
shares from independent batches of rays (the standard errors' source,
:mod:`~maizeviz.light.results.uncertainty`). Every result, these and the intercepted light's
(:class:`~maizeviz.light.results.traced.TracedLight`), is :class:`OnCanopy`: it knows the
canopy it was computed on, so that ``result.table("leaf")`` needs no canopy passed back.

The canopy is a reference, not a copy, and it stays behind when a result is pickled (a result
crosses processes: the app's light process, Dask workers); a result read back, or from a
project, takes the canopy as an argument (``table("leaf", canopy)``) or :meth:`with_canopy`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Self

import numpy as np

from maizeviz.light.results.uncertainty import batch_error

if TYPE_CHECKING:
    from maizeviz.canopy.build import Canopy


@dataclass(frozen=True, eq=False)
class OnCanopy:
    """A result that knows the canopy it was computed on (every light and carbon result).

    Attributes
    ----------
    canopy : Canopy or None
        The canopy the result was computed on (keyword-only; left out of pickles and of
        equality): the per-leaf and per-plant tables use it when none is given.
    """

    canopy: Canopy | None = field(default=None, kw_only=True, repr=False, compare=False)

    def with_canopy(self, canopy: Canopy | None) -> Self:
        """The same result, knowing the canopy it was computed on.

        Parameters
        ----------
        canopy : Canopy or None
            The canopy it was traced on (None forgets it).

        Returns
        -------
        OnCanopy
            A copy of the same class holding ``canopy`` (its arrays shared, not copied).
        """
        return replace(self, canopy=canopy)

    def _on(self, canopy: Canopy | None) -> Canopy | None:
        """The canopy a table is made on: the one given, else the result's own."""
        return canopy if canopy is not None else self.canopy

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state["canopy"] = None                 # the canopy stays in the process that has it
        return state


@dataclass(frozen=True, eq=False)
class TriangleResult(OnCanopy):
    """The base of the results that hold a value per triangle (see the module docstring)."""

    # ---- what a result provides
    def _triangle_values(self) -> np.ndarray:
        """(F,) float64: the result's value on each triangle, in its own unit."""
        raise NotImplementedError

    def _triangle_batches(self) -> Any:
        """(BATCHES, F) dense or sparse: each batch's share of :meth:`_triangle_values`, or
        None when the result was not traced in batches."""
        raise NotImplementedError

    # ---- what every result gives
    @property
    def triangle_total(self) -> float:
        """The sum of the per-triangle values (W, J, umol/s or mol, as the result's).

        Returns
        -------
        float
            The total over the result's triangles (absorbed light: the scene's, leaves then
            stalks where they were traced; assimilation: the leaves').
        """
        return float(np.sum(self._triangle_values()))

    @property
    def triangle_total_error(self) -> float | None:
        """Monte Carlo standard error of :attr:`triangle_total`, from the batches.

        Returns
        -------
        float or None
            In the total's unit; None when the result was not traced in batches.
        """
        rows = self._triangle_batches()
        if rows is None:
            return None
        return float(batch_error(np.asarray(rows.sum(axis=1), dtype=np.float64).ravel()))
