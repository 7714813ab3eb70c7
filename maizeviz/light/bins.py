"""Binning a sensor plane: bin edges over the sample rectangle, sensors and lit sensors per bin,
and the binned map itself. Plain arrays, no light result: the tracing (daylight) and the drawing
(heatmap) both use it, neither imports the other for it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from maizeviz.errors import MaizevizError


@dataclass(frozen=True)
class TransmissionMap:
    """Transmission binned over a sample plane.

    Attributes
    ----------
    height_cm : the plane's height
    x_edges : (a + 1,) cm; y_edges : (b + 1,) cm
    transmission : (a, b), NaN in bins without a sensor
    rays : (a, b) int, sensors per bin
    total : transmission of the whole plane
    """

    height_cm: float
    x_edges: np.ndarray
    y_edges: np.ndarray
    transmission: np.ndarray
    rays: np.ndarray
    total: float


def bin_edges(rect: tuple[float, float, float, float],
              bin_cm: float) -> tuple[np.ndarray, np.ndarray]:
    """Bin edges (a + 1,), (b + 1,) cm over the rectangle, bins as close to ``bin_cm`` as fit."""
    if not bin_cm > 0:
        raise MaizevizError(f"the heatmap bin must be > 0 cm, got {bin_cm}", quantity="heatmap_bin")
    x0, y0, x1, y1 = rect
    nx = max(1, int(round((x1 - x0) / bin_cm)))
    ny = max(1, int(round((y1 - y0) / bin_cm)))
    return np.linspace(x0, x1, nx + 1), np.linspace(y0, y1, ny + 1)


def binned(xy: np.ndarray, lit: np.ndarray, xe: np.ndarray,
           ye: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sensors per bin and lit sensors per bin: two (a, b) float64 arrays.

    Parameters
    ----------
    xy : (N, 2) cm, sensor positions; lit : (N,) bool or float weights
    xe, ye : evenly spaced bin edges (:func:`bin_edges`), cm; sensors on the last edge fall in
        the last bin
    """
    i = np.clip(((xy[:, 0] - xe[0]) * ((len(xe) - 1) / (xe[-1] - xe[0]))).astype(np.int64),
                0, len(xe) - 2)
    j = np.clip(((xy[:, 1] - ye[0]) * ((len(ye) - 1) / (ye[-1] - ye[0]))).astype(np.int64),
                0, len(ye) - 2)
    flat = i * (len(ye) - 1) + j
    size = (len(xe) - 1) * (len(ye) - 1)
    counts = np.bincount(flat, minlength=size).astype(np.float64)
    lit_counts = np.bincount(flat, weights=np.asarray(lit, dtype=np.float64), minlength=size)
    shape = (len(xe) - 1, len(ye) - 1)
    return counts.reshape(shape), lit_counts.reshape(shape)
