"""Lines of sight from an instrument's sensors through a canopy's Embree scene.

The instruments look from points inside or under the canopy toward the sky: a line of sight is
open (a gap) when no leaf (or stalk) lies on it before it leaves the canopy's top. They trace
on the light engine's own scenes (:func:`maizeviz.light.scene.embree_scenes.light_scene`, or a
:class:`~maizeviz.light.engine.LightEngine`'s kept ones), open or periodic: in a periodic field
a line of sight that leaves the plot sideways goes on through the next copy of it
(:func:`maizeviz.light.scene.periodic.trace_wrapped`), as the engine's sunlight does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.errors import MaizevizError
from maizeviz.light.scene.embree_scenes import light_scene
from maizeviz.light.scene.request import canopy_top
from maizeviz.mesh.raytrace import RayScene

#: Lines of sight traced per call into Embree (bounds memory: about 100 bytes each).
CHUNK = 1 << 18
#: Distance (cm) above the canopy's top where a line of sight is taken to have reached the sky.
SKY_MARGIN_CM = 1.0


@dataclass(frozen=True)
class Sight:
    """A canopy's scene seen from sensors: what lies on lines of sight toward the sky.

    Parameters
    ----------
    scene : RayScene
        The canopy's scene (leaves, then stalks when it holds them).
    bounds : (x0, y0, x1, y1) float, cm
        The plot (the field's period when ``periodic``).
    top : float, cm
        Height above which nothing stands (the canopy's top plus :data:`SKY_MARGIN_CM`).
    periodic : bool
        Lines of sight leaving the plot sideways go on through the next copy of it.
    n_leaf_triangles : int
        Triangle ids from this one on are stalks.
    """

    scene: RayScene
    bounds: tuple[float, float, float, float]
    top: float
    periodic: bool
    n_leaf_triangles: int

    @classmethod
    def of(cls, canopy: Canopy, periodic: bool = False, with_stalks: bool = True,
           scene: RayScene | None = None) -> Sight:
        """The sight of a canopy, its scene built here or given.

        Parameters
        ----------
        canopy : Canopy
            The canopy the instrument stands in.
        periodic : bool
            Lines of sight leaving the plot sideways go on through the next copy of it (an
            infinite field).
        with_stalks : bool
            Stalks block lines of sight too (when the canopy has them).
        scene : RayScene, optional
            A light engine's scene of the same canopy, built with the same ``periodic`` and
            ``with_stalks`` (:meth:`maizeviz.light.engine.LightEngine.scene`); built here when
            None.

        Returns
        -------
        Sight
            What lies on lines of sight toward the sky in ``canopy``.
        """
        stalks = with_stalks and len(canopy.stalk_faces) > 0
        if scene is None:
            scene = light_scene(canopy, stalks, periodic)
        elif periodic != (getattr(scene, "wrapped", None) is not None):
            raise MaizevizError("the scene given was built for "
                                f"{'an open' if periodic else 'a periodic'} field, the "
                                f"instrument asks for {'a periodic' if periodic else 'an open'} "
                                "one", quantity="periodic")
        return cls(scene, canopy.layout.bounds, canopy_top(canopy, stalks) + SKY_MARGIN_CM,
                   bool(periodic), canopy.n_triangles)

    def outside(self, x: float, y: float) -> bool:
        """Whether a place is off the plot of an open field (where nothing stands around it).

        Parameters
        ----------
        x, y : float
            The place in field coordinates [cm].

        Returns
        -------
        bool
            True when the field is open (not periodic) and (x, y) lies outside its plot.
        """
        x0, y0, x1, y1 = self.bounds
        return not self.periodic and not (x0 <= x <= x1 and y0 <= y <= y1)

    def outside_note(self, what: str, x: float, y: float) -> str:
        """What to tell the user of an instrument held off the plot of an open field.

        Parameters
        ----------
        what : str
            The instrument's part, as the note names it ("probe 1", "the lens").
        x, y : float
            Where it is held, in field coordinates [cm].

        Returns
        -------
        str
            One line naming the place, the plot's extent and the likely slip (units).
        """
        x0, y0, x1, y1 = self.bounds
        return (f"{what} at ({x:g}, {y:g}) cm is outside the plot (x {x0:.1f} to {x1:.1f}, "
                f"y {y0:.1f} to {y1:.1f} cm): it reads the open sky beside the field (positions "
                "are in cm; --periodic repeats the plot)")

    def reach(self, origins: np.ndarray, toward: np.ndarray) -> np.ndarray:
        """How far each line of sight goes before it is above everything that stands.

        Parameters
        ----------
        origins : numpy.ndarray
            (N, 3) float sensor positions [cm].
        toward : numpy.ndarray
            (N, 3) float unit vectors toward the sky (z > 0).

        Returns
        -------
        numpy.ndarray
            (N,) float length of each line of sight up to the height :attr:`top` [cm]; 0 for
            origins above it.
        """
        return np.maximum(self.top - origins[:, 2], 0.0) / toward[:, 2]

    def _check(self, origins: np.ndarray, toward: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        o = np.asarray(origins, dtype=np.float64).reshape(-1, 3)
        d = np.asarray(toward, dtype=np.float64).reshape(-1, 3)
        if len(d) == 1 and len(o) != 1:
            d = np.broadcast_to(d, o.shape)
        if len(d) != len(o):
            raise ValueError(f"{len(d)} directions for {len(o)} origins")
        if not (np.all(np.isfinite(o)) and np.all(np.isfinite(d))):
            raise MaizevizError("a sensor position or viewing direction is not a finite number")
        if np.any(d[:, 2] <= 0):
            raise MaizevizError("lines of sight toward the sky must point above the horizon "
                                "(zenith below 90 deg)")
        return o, np.ascontiguousarray(d)

    def open(self, origins: np.ndarray, toward: np.ndarray) -> np.ndarray:
        """Whether each line of sight reaches the sky.

        Parameters
        ----------
        origins : numpy.ndarray
            (N, 3) float sensor positions [cm].
        toward : numpy.ndarray
            (N, 3) or (3,) float unit vectors toward the sky (z > 0).

        Returns
        -------
        numpy.ndarray
            (N,) bool, True where nothing lies on the line of sight.
        """
        o, d = self._check(origins, toward)
        out = np.empty(len(o), dtype=bool)
        for a in range(0, len(o), CHUNK):
            oc, dc = o[a:a + CHUNK], d[a:a + CHUNK]
            out[a:a + CHUNK] = ~self._blocked(oc, dc, self.reach(oc, dc))
        return out

    def _blocked(self, o: np.ndarray, d: np.ndarray, length: np.ndarray) -> np.ndarray:
        from maizeviz.light.scene.periodic import Wrap, trace_wrapped

        if not self.periodic:
            return self.scene.occluded(o, d, length.astype(np.float32))
        wrap = getattr(self.scene, "wrap", None) or Wrap.of(self.bounds)
        return trace_wrapped(self.scene, wrap, o, d, length, any_hit=True)

    def first(self, origins: np.ndarray, toward: np.ndarray) -> np.ndarray:
        """The canopy triangle first met on each line of sight.

        Parameters
        ----------
        origins : numpy.ndarray
            (N, 3) float sensor positions [cm].
        toward : numpy.ndarray
            (N, 3) or (3,) float unit vectors toward the sky (z > 0).

        Returns
        -------
        numpy.ndarray
            (N,) int64 canopy triangle ids, -1 where the sky is seen (ids from
            :attr:`n_leaf_triangles` on are stalks).
        """
        from maizeviz.light.scene.periodic import Wrap, trace_wrapped

        o, d = self._check(origins, toward)
        out = np.full(len(o), -1, dtype=np.int64)
        resolve = getattr(self.scene, "resolve", None)
        for a in range(0, len(o), CHUNK):
            oc, dc = o[a:a + CHUNK], d[a:a + CHUNK]
            length = self.reach(oc, dc)
            if self.periodic:
                wrap = getattr(self.scene, "wrap", None) or Wrap.of(self.bounds)
                prim, cell, dist = trace_wrapped(self.scene, wrap, oc, dc, length)
                hit = np.flatnonzero(np.isfinite(dist))
                if len(hit) and resolve is not None:
                    prim = prim.copy()
                    prim[hit] = resolve(prim[hit], cell[hit])
            else:
                prim, t = self.scene.first_hit(oc, dc, length.astype(np.float32))
                hit = np.flatnonzero(prim >= 0)
                if len(hit) and resolve is not None:
                    prim = prim.copy()
                    prim[hit] = resolve(prim[hit], None)
            out[a + hit] = prim[hit]
        return out


def default_place(canopy: Canopy) -> tuple[float, float]:
    """Where an instrument is held unless told (x, y) cm: between the rows and between the
    plants, next to the plant nearest the plot's middle (half a row spacing across, half a
    plant spacing along), as one holds it in a plot: not against a stalk."""
    lay = canopy.layout
    x0, y0, x1, y1 = lay.bounds
    cx, cy = (x0 + x1) / 2.0, (y0 + y1) / 2.0
    if not lay.placements:
        return cx, cy
    near = min(lay.placements, key=lambda p: (p.x - cx) ** 2 + (p.y - cy) ** 2)
    return near.x + lay.row_spacing / 2.0, near.y + lay.plant_spacing / 2.0
