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

    def show_canopy(self, canopy) -> None:
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
