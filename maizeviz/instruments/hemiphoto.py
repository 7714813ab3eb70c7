"""Virtual hemispherical photographs: an upward fisheye view of canopy and sky from a point.

The lens is equidistant (the distance of a pixel from the image centre is proportional to its
zenith angle: the horizon on the image circle), looking up, north at the top and east on the
left (as the sky is seen from below). One line of sight is traced through each pixel's centre;
a pixel is sky (white) where it leaves the canopy, else the organ it meets: leaves green and
stalks brown, or all black (``colour=False``, a thresholded photograph). The gap fraction of a
zenith ring is the share of its pixels that see the sky, as in hemispherical photo software
(Gap Light Analyzer, CAN-EYE); the rings are the canopy analyser's five by default.

References
----------
Rich, P. M. (1990). Characterizing plant canopies with hemispherical photographs. Remote
Sensing Reviews 5, 13-29. https://doi.org/10.1080/02757259009532119
Frazer, G. W., Canham, C. D. & Lertzman, K. P. (1999). Gap Light Analyzer (GLA), version 2.0:
imaging software to extract canopy structure and gap light transmission indices from
true-colour fisheye photographs. Simon Fraser University, Burnaby, and the Institute of
Ecosystem Studies, Millbrook, NY.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.instruments.analyser import RING_EDGES_DEG
from maizeviz.instruments.sight import Sight

#: Colours (RGB) of the photograph's pixels.
SKY_RGB = (255, 255, 255)
LEAF_RGB = (46, 125, 50)
STALK_RGB = (141, 110, 69)
PLANT_BLACK = (0, 0, 0)
OUTSIDE_RGB = (128, 128, 128)
#: Lines of sight lower than this are traced at it (a horizontal one never leaves the field).
LOWEST_SIGHT_DEG = 89.5
#: Image sizes accepted, pixels a side.
MIN_SIZE, MAX_SIZE = 16, 8192


@dataclass(frozen=True)
class Hemiphoto:
    """One hemispherical photograph.

    Parameters
    ----------
    x, y, height_cm : float
        Where the lens is, in field coordinates [cm].
    image : numpy.ndarray
        (S, S, 3) uint8, the photograph (RGB).
    zenith_deg : numpy.ndarray
        (S, S) float64 each pixel's zenith angle, above 90 outside the image circle [deg].
    sky : numpy.ndarray
        (S, S) bool, the pixels that see the sky.
    stalk : numpy.ndarray
        (S, S) bool, the pixels that see a stalk.
    ring_edges_deg : tuple of (float, float)
        The zenith rings (lo, hi) of :attr:`gap_fraction` [deg].
    notes : list of str
        What the user should know about this photograph.
    """

    x: float
    y: float
    height_cm: float
    image: np.ndarray
    zenith_deg: np.ndarray
    sky: np.ndarray
    stalk: np.ndarray
    ring_edges_deg: tuple[tuple[float, float], ...]
    notes: list[str] = field(default_factory=list)

    def ring_pixels(self) -> np.ndarray:
        """How many pixels each zenith ring holds.

        Returns
        -------
        numpy.ndarray
            (R,) int, the pixels whose centre lies in each ring.
        """
        return np.array([np.count_nonzero((self.zenith_deg >= lo) & (self.zenith_deg < hi))
                         for lo, hi in self.ring_edges_deg])

    @property
    def gap_fraction(self) -> np.ndarray:
        """(R,) share of each ring's pixels that see the sky."""
        out = []
        for lo, hi in self.ring_edges_deg:
            ring = (self.zenith_deg >= lo) & (self.zenith_deg < hi)
            n = max(int(np.count_nonzero(ring)), 1)
            out.append(np.count_nonzero(self.sky & ring) / n)
        return np.array(out)

    @property
    def openness(self) -> float:
        """Share of the image circle's pixels that see the sky."""
        inside = self.zenith_deg < 90.0
        return float(np.count_nonzero(self.sky & inside) / np.count_nonzero(inside))

    def save_png(self, path: str | Path) -> Path:
        """Write the photograph as a PNG (atomically: a whole file or none).

        Parameters
        ----------
        path : str or Path
            The file to write.

        Returns
        -------
        pathlib.Path
            The path written.
        """
        import matplotlib.image as mpimg

        from maizeviz.io.atomic import atomic_path

        path = Path(path)
        with atomic_path(path) as tmp:
            mpimg.imsave(tmp, self.image, format="png")
        return path

    def as_dict(self) -> dict:
        """A JSON-ready record of the photograph.

        Returns
        -------
        dict
            The lens's place, the image's size, its openness and each ring's gap fraction
            (the image itself is not in it).
        """
        return {"instrument": "hemiphoto", "x_cm": self.x, "y_cm": self.y,
                "height_cm": self.height_cm, "size_px": int(self.image.shape[0]),
                "openness": self.openness,
                "rings": [{"ring": i + 1, "from_deg": lo, "to_deg": hi, "pixels": int(n),
                           "gap_fraction": float(g)}
                          for i, ((lo, hi), n, g) in enumerate(zip(
                              self.ring_edges_deg, self.ring_pixels(), self.gap_fraction))],
                "notes": list(self.notes)}


def pixel_directions(size: int, north_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Zenith angle (S, S) deg of each pixel of an equidistant upward fisheye of ``size``
    pixels a side, and its line of sight (S, S, 3) toward the sky in field coordinates (north
    at the top, east on the left; zenith > 90 outside the image circle)."""
    c = (np.arange(size) + 0.5) - size / 2.0
    dx, dy = np.meshgrid(c, -c)                        # dy up the image
    r = np.hypot(dx, dy) / (size / 2.0)
    zen = 90.0 * r
    az = np.degrees(np.arctan2(-dx, dy))               # clockwise from north: east on the left
    z = np.radians(np.minimum(zen, LOWEST_SIGHT_DEG))
    a = np.radians(az - north_deg)
    dirs = np.stack([np.sin(z) * np.sin(a), np.sin(z) * np.cos(a), np.cos(z)], axis=-1)
    return zen, dirs


def check_rings(rings: Sequence[tuple[float, float]]) -> tuple[tuple[float, float], ...]:
    """Zenith rings [(lo, hi), ...] deg with 0 <= lo < hi <= 90."""
    out = []
    for ring in rings:
        lo, hi = (float(v) for v in ring)
        if not (0.0 <= lo < hi <= 90.0):
            raise MaizevizError(f"a zenith ring must run from lo to hi deg with 0 <= lo < hi <= "
                                f"90, got {lo:g}-{hi:g}", quantity="rings")
        out.append((lo, hi))
    if not out:
        raise MaizevizError("give at least one zenith ring", quantity="rings")
    return tuple(out)


def hemiphoto(sight: Sight, x: float, y: float, height_cm: float = 0.0, *, size: int = 512,
              colour: bool = True, north_deg: float = 0.0,
              rings: Sequence[tuple[float, float]] = RING_EDGES_DEG) -> Hemiphoto:
    """Take a hemispherical photograph from (x, y, height_cm).

    Parameters
    ----------
    sight : Sight
        The canopy's lines of sight (:meth:`Sight.of`).
    x, y, height_cm : float
        The lens's position in field coordinates [cm].
    size : int
        Pixels a side (16 to 8192).
    colour : bool
        Leaves green and stalks brown; False: every plant pixel black.
    north_deg : float
        Angle from north to the field's +y axis, clockwise (the layout's) [deg].
    rings : sequence of (float, float)
        Zenith rings (lo, hi) of the gap fractions (default the canopy analyser's five)
        [deg].

    Returns
    -------
    Hemiphoto
        The photograph, which pixels see the sky or a stalk, and each ring's gap fraction.
    """
    for name, v in (("x", x), ("y", y), ("height_cm", height_cm)):
        if not math.isfinite(float(v)):
            raise MaizevizError(f"the lens's {name} must be a finite number, got {v}",
                                quantity=name)
    if height_cm < 0:
        raise MaizevizError(f"the lens's height must be >= 0 cm, got {height_cm}",
                            quantity="height_cm")
    if not (isinstance(size, (int, np.integer)) and MIN_SIZE <= size <= MAX_SIZE):
        raise MaizevizError(f"the photograph's size must be a whole number of pixels from "
                            f"{MIN_SIZE} to {MAX_SIZE}, got {size}", quantity="size")
    ring_edges = check_rings(rings)
    zen, dirs = pixel_directions(int(size), north_deg)
    inside = zen < 90.0
    origin = np.array([x, y, height_cm], dtype=np.float64)
    d = dirs[inside]
    hit = sight.first(np.broadcast_to(origin, d.shape), d)
    sky = np.zeros(zen.shape, dtype=bool)
    stalk = np.zeros(zen.shape, dtype=bool)
    sky[inside] = hit < 0
    stalk[inside] = hit >= sight.n_leaf_triangles
    image = np.empty(zen.shape + (3,), dtype=np.uint8)
    image[:] = OUTSIDE_RGB
    image[inside] = LEAF_RGB if colour else PLANT_BLACK
    if colour:
        image[stalk] = STALK_RGB
    image[sky] = SKY_RGB
    notes = []
    if height_cm >= sight.top:
        notes.append("the lens is above the canopy: the photograph is all sky")
    if sight.outside(x, y):
        notes.append(sight.outside_note("the lens", x, y))
    return Hemiphoto(float(x), float(y), float(height_cm), image, zen, sky, stalk, ring_edges,
                     notes)
