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


def _bins_of(v: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Bin index of each of ``v`` (cm) between evenly spaced ``edges``; the last edge and beyond
    fall in the last bin, before the first in the first."""
    return np.clip(((v - edges[0]) * ((len(edges) - 1) / (edges[-1] - edges[0]))).astype(np.int64),
                   0, len(edges) - 2)


def binned(xy: np.ndarray, lit: np.ndarray, xe: np.ndarray,
           ye: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sensors per bin and lit sensors per bin: two (a, b) float64 arrays.

    Parameters
    ----------
    xy : (N, 2) cm, sensor positions; lit : (N,) bool or float weights
    xe, ye : evenly spaced bin edges (:func:`bin_edges`), cm; sensors on the last edge fall in
        the last bin
    """
    flat = _bins_of(xy[:, 0], xe) * (len(ye) - 1) + _bins_of(xy[:, 1], ye)
    size = (len(xe) - 1) * (len(ye) - 1)
    counts = np.bincount(flat, minlength=size).astype(np.float64)
    lit_counts = np.bincount(flat, weights=np.asarray(lit, dtype=np.float64), minlength=size)
    shape = (len(xe) - 1, len(ye) - 1)
    return counts.reshape(shape), lit_counts.reshape(shape)


def binned_grid(xs: np.ndarray, ys: np.ndarray, lit: np.ndarray, xe: np.ndarray,
                ye: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`binned` for sensors on a grid, by its rows and columns: the same two arrays.

    Parameters
    ----------
    xs : (nx,) cm, the grid's x; ys : (ny,) cm, its y
    lit : (nx * ny,) bool, grid order (x slow, y fast)
    xe, ye : as :func:`binned`
    """
    a, b = len(xe) - 1, len(ye) - 1
    ix, iy = _bins_of(xs, xe), _bins_of(ys, ye)
    counts = np.outer(np.bincount(ix, minlength=a), np.bincount(iy, minlength=b))
    flat = (ix[:, None] * b + iy[None, :]).ravel()
    lit_counts = np.bincount(flat[np.asarray(lit, dtype=bool)], minlength=a * b)
    return counts.astype(np.float64), lit_counts.reshape(a, b).astype(np.float64)
