"""Monte Carlo standard errors from independent batches of rays.

The primary rays of a traced light are dealt at random into :data:`BATCHES` equal batches;
each ray, and everything it scatters, belongs to its batch, so the batches are independent
estimates of every figure. A result keeps each batch's share of every triangle
(:class:`Batches`, sparse: most triangles see few rays); the standard error of any sum over
triangles (a leaf, a plant, the canopy) is the spread of its batch estimates
(:func:`batch_error`). A plant's error comes from its batches' sums, never from its leaves'
errors: they share the batches.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from maizeviz.canopy.build import Canopy

#: Independent batches the primary rays are dealt into.
BATCHES = 8


def batch_error(per_batch) -> float | np.ndarray:
    """Monte Carlo standard error of a total from its batches' shares.

    Parameters
    ----------
    per_batch : (BATCHES, ...) float64, what each batch's rays contributed to the total (the
        rows sum to the estimate)

    Returns
    -------
    standard error of the estimate (same unit, shape ``per_batch.shape[1:]``): the batches
    are independent estimates ``BATCHES x row``, whose mean is the estimate; its standard
    error is their standard deviation over ``sqrt(BATCHES)``.
    """
    x = np.asarray(per_batch, dtype=np.float64)
    k = x.shape[0]
    return np.std(k * x, axis=0, ddof=1) / np.sqrt(k)


@dataclass(frozen=True)
class Batches:
    """Per-batch shares of an absorbed-light result (each row one batch; rows sum to the
    result's per-triangle arrays): what standard errors are computed from.

    Attributes
    ----------
    absorbed : (BATCHES, F) scipy.sparse CSR array, W (or J over a period) per triangle
    direct : (BATCHES, F) the part of ``absorbed`` from the sun's direct beam
    sunlit_cm2 : (BATCHES, F) area in the direct beam, cm2
    parts : (4, BATCHES) float64 or None, each batch's share of the ground's absorbed light,
        of the light reflected out of the top, escaped sideways and left unresolved (the
        balance's own units)
    """

    absorbed: Any
    direct: Any
    sunlit_cm2: Any
    parts: np.ndarray | None = None

    def balance_errors(self, scale: float) -> dict[str, float] | None:
        """Standard errors of the balance's parts other than the leaves' (``absorbed_ground``,
        ``reflected_top``, ``escaped_sides``, ``unresolved``), each batch's ``parts`` (4,
        BATCHES) times ``scale`` (to the balance's unit); None without them."""
        if self.parts is None:
            return None
        names = ("absorbed_ground", "reflected_top", "escaped_sides", "unresolved")
        return {n: float(batch_error(self.parts[i] * scale)) for i, n in enumerate(names)}

    def error(self, weights=None, what: str = "absorbed") -> float:
        """Standard error of ``sum(weights * what)`` over the triangles (weights (F,), None:
        all 1)."""
        m = getattr(self, what)
        per = m.sum(axis=1) if weights is None else m @ np.asarray(weights, np.float64)
        return float(batch_error(np.asarray(per)))


def dense_rows(batches) -> np.ndarray | None:
    """(BATCHES, F) float64 of a sparse per-batch array (None stays None)."""
    if batches is None:
        return None
    return np.asarray(batches.todense(), dtype=np.float64) if hasattr(batches, "todense") \
        else np.asarray(batches, dtype=np.float64)


def errors_by(canopy: Canopy, batches, col: str, rect, periodic: bool,
              by: str) -> dict:
    """Standard error of ``col`` per leaf ((instance, leaf) keys) or per plant (instance
    keys) from per-batch per-triangle shares ``batches`` (BATCHES, F), dense or sparse."""
    import pandas as pd

    from maizeviz.light.results.per_leaf import leaf_sums

    key = ["instance"] if by == "plant" else ["instance", "leaf"]
    parts = []
    for b in dense_rows(batches):  # type: ignore[union-attr]
        part = pd.DataFrame(leaf_sums(canopy, {col: b}, rect, periodic))
        parts.append(part.groupby(key)[col].sum() if not part.empty
                     else pd.Series(dtype=float))
    table = pd.concat(parts, axis=1).fillna(0.0).sort_index()     # keys x batches
    keys = table.index.tolist()
    per = table.to_numpy(dtype=np.float64).T
    se = np.asarray(batch_error(per)) if keys else np.zeros(0)
    return dict(zip(keys, se.tolist()))
