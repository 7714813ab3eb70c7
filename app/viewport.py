"""The 3D view: the canopy's leaves, stalks and ground in a pyvistaqt interactor.

Actors are replaced by name, so a rebuild never leaks the previous mesh. Touch it from the GUI
thread only.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv
from pyvistaqt import QtInteractor


def _polydata(vertices: np.ndarray, faces: np.ndarray) -> pv.PolyData:
    cells = np.empty((len(faces), 4), dtype=np.int64)
    cells[:, 0] = 3
    cells[:, 1:] = faces
    return pv.PolyData(np.asarray(vertices, dtype=np.float32), cells.ravel())


class Viewport(QtInteractor):
    """A QtInteractor that knows how to show a :class:`~maizeviz.canopy.scene.Canopy`."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.set_background("white", top="lightskyblue")
        self.add_axes()
        self._framed = False

    def hide_canopy(self) -> None:
        """Make room for a digitizing session."""
        for name in ("canopy", "stalks", "ground"):
            self.remove_actor(name, render=False)
        self._framed = False

    def show_leaf_surfaces(self, meshes, points) -> None:
        """Digitized points (N, 3) and leaf meshes (LeafMesh list) of the plant being digitized."""
        for name in [n for n in self.actors if str(n).startswith("leafsurf")]:
            self.remove_actor(name, render=False)
        for k, m in enumerate(meshes):
            self.add_mesh(_polydata(m.points, m.faces), name=f"leafsurf{k}", color="yellowgreen",
                          show_edges=True, edge_color="darkgreen")
        self.add_mesh(pv.PolyData(np.asarray(points, np.float32)), name="digitized",
                      color="red", render_points_as_spheres=True, point_size=9)
        if not self._framed:
            self.reset_camera()
            self._framed = True
        self.render()

    def show_canopy(self, canopy) -> None:
        for name in [n for n in self.actors if str(n).startswith("leafsurf")] + ["digitized"]:
            self.remove_actor(name, render=False)
        leaves = _polydata(canopy.vertices, canopy.faces)
        leaves.cell_data["leaf rank"] = canopy.face_leaf
        self.add_mesh(leaves, name="canopy", scalars="leaf rank", cmap="summer",
                      show_scalar_bar=False, smooth_shading=False)
        if len(canopy.stalk_faces):
            self.add_mesh(_polydata(canopy.stalk_vertices, canopy.stalk_faces), name="stalks",
                          color="peru")
        x0, y0, x1, y1 = canopy.layout.bounds
        ground = pv.Plane(center=((x0 + x1) / 2, (y0 + y1) / 2, 0), i_size=x1 - x0,
                          j_size=y1 - y0)
        self.add_mesh(ground, name="ground", color="tan", opacity=0.6)
        if not self._framed:
            self.view_isometric()
            self.reset_camera()
            self._framed = True
        self.render()

    # ----------------------------------------------------- the plant being digitized
    # Used by the digitizer panel: one actor per leaf surface (named "leafsurf...", so a new
    # canopy clears them), the points as one small semi-transparent actor, the last press as
    # one opaque dot. Each call renders once unless told not to.
    def show_digitized_leaf(self, name: str, vertices: np.ndarray, faces: np.ndarray,
                            render: bool = True) -> None:
        """Add or replace one leaf surface (vertices (n, 3) cm, faces (F, 3) int)."""
        self.add_mesh(_polydata(vertices, faces), name=name, color="yellowgreen",
                      smooth_shading=True, reset_camera=False, render=False)
        if render:
            self.render()

    def remove_digitized(self, names, render: bool = True) -> None:
        for name in names:
            self.remove_actor(name, render=False)
        if render:
            self.render()

    def show_digitized_points(self, points: np.ndarray, last: np.ndarray | None = None,
                              render: bool = True) -> None:
        """Points (N, 3) cm small and semi-transparent, so the surfaces show through; the last
        press (3,) as a bigger opaque dot."""
        self._points_actor("digitized", points, color="crimson", opacity=0.45, point_size=5)
        self._points_actor("digitized-last", last, color="red", opacity=1.0, point_size=11)
        if render:
            self.render()

    def _points_actor(self, name: str, points, **style) -> None:
        points = np.asarray(points if points is not None else [], np.float32).reshape(-1, 3)
        actor = self.actors.get(name)
        if not len(points):
            self.remove_actor(name, render=False)
        elif actor is not None:                 # a press adds a point: update in place
            actor.mapper.dataset.shallow_copy(pv.PolyData(points))
        else:
            self.add_mesh(pv.PolyData(points), name=name, render_points_as_spheres=True,
                          reset_camera=False, render=False, **style)

    def frame_bounds(self, bounds, render: bool = True) -> None:
        """Point the camera at x0, x1, y0, y1, z0, z1 (cm), keeping its direction."""
        self.reset_camera(render=False, bounds=tuple(float(b) for b in bounds))
        if render:
            self.render()

    def clear_digitized(self, render: bool = True) -> None:
        """Remove every actor of the plant being digitized."""
        names = [n for n in self.actors if str(n).startswith(("leafsurf", "digitized"))]
        self.remove_digitized(names, render)
