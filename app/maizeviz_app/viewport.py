"""The 3D view: the canopy as one mesh, the ground with a grid and cm labels, camera presets.

Rendering happens only when something changed, once:

- pyvistaqt's idle timer (5 renders a second by default) is off (``auto_update=False``).
- :meth:`Viewport.render` only schedules a repaint (``QWidget.update``): pyvista calls it after
  every change, Qt merges the requests, and the widget's paint renders the scene once. Calling
  the render window directly would render twice (pyvistaqt then repaints to show the frame).
- Multisampling is off: on software OpenGL (llvmpipe) 8x MSAA, pyvista's default, triples the
  cost of a frame.

The canopy is one actor over one merged mesh (leaves and stalks), with per-triangle cell data
``plant`` (digitized plant id), ``instance`` (placement, from 1), ``leaf`` (rank; 0 for
stalks) and ``light`` (2 direct, 1 second class, 0 none, -1 not traced; -2 for stalks), and
``plant`` and ``leaf`` per vertex too: those colourings use them (cheaper to draw on software
OpenGL than colours per triangle; see :func:`_point_values`), light uses the cell data: the
sun's classes through a lookup table, light values (a sky's, a day's, a leaf's sunlit share)
as one RGB per triangle (``light_rgb``) computed from the view's colour scale
(:mod:`maizeviz_app.colour`: range, colour map, log), so that a clipped range clamps leaves to
the ends of the map and stalks keep their colour. Colouring switches the mapper's array and
lookup table; nothing is rebuilt. The mesh is made
by :func:`canopy_polydata`, which worker threads call, so the GUI thread only swaps it in.

Touch the widget from the GUI thread only.
"""

from __future__ import annotations

import threading
import time

import numpy as np
import pyvista as pv
from PySide6.QtCore import QPointF, QRectF, Qt, QTimer, Signal
from PySide6.QtGui import QColor, QFont, QImage, QLinearGradient, QPainter, QPen
from PySide6.QtWidgets import QWidget
from pyvistaqt import QtInteractor

from maizeviz.ids import groups
from maizeviz_app.colour import tick_text
from maizeviz_app.options import (
    CAMERA_ALIASES,
    CAMERAS,
    COLOURINGS,
    LIGHT_CLASSES,
    NOT_TRACED,
    STALK,
)
from maizeviz_app.picking import Pick, make_pickable, part_bounds, part_mesh, pick

#: Text alignments of the painted axes and legends.
CENTRE = Qt.AlignmentFlag.AlignCenter
LEFT = Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter

_PLANT_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
                  "#7f7f7f", "#bcbd22", "#17becf")


def canopy_polydata(canopy) -> pv.PolyData:
    """One mesh of a :class:`~maizeviz.canopy.build.Canopy`'s leaves and stalks (float32
    vertices, cm) with the cell data listed in the module docstring, its ground made too
    (:func:`ground_for`). Safe off the GUI thread."""
    _prepare_ground(canopy.layout)
    return _settle(_polydata(canopy, canopy.vertices, canopy.faces, canopy.face_plant,
                             canopy.face_instance, canopy.face_leaf))


def _polydata(canopy, vertices: np.ndarray, faces: np.ndarray, face_plant: np.ndarray,
              face_instance: np.ndarray, face_leaf: np.ndarray) -> pv.PolyData:
    """The mesh of leaf triangles ``faces`` (F, 3) over ``vertices`` with their plant,
    instance (from 0) and leaf, and ``canopy``'s stalks after them."""
    nv, nf = len(vertices), len(faces)
    points = np.empty((nv + len(canopy.stalk_vertices), 3), np.float32)
    points[:nv] = vertices
    points[nv:] = canopy.stalk_vertices
    index = np.int32 if len(points) < 2 ** 31 else np.int64     # VTK's 32-bit cell storage
    all_faces = np.empty((nf + len(canopy.stalk_faces), 3), index)
    all_faces[:nf] = faces
    all_faces[nf:] = canopy.stalk_faces + nv
    n_stalk = len(canopy.stalk_faces)
    if canopy.stalk_instance is not None:          # a mesh's plants: stalks of their own sizes
        stalk_inst = np.asarray(canopy.stalk_instance, np.int32)
    else:
        per_stalk = n_stalk // max(canopy.n_plants, 1)
        stalk_inst = np.repeat(np.arange(canopy.n_plants, dtype=np.int32), per_stalk)
    plant_of_inst = np.array([p.plant for p in canopy.layout.placements], np.int32)
    plant = np.concatenate([face_plant, plant_of_inst[stalk_inst]]).astype(np.int32)
    leaf = np.concatenate([face_leaf, np.zeros(n_stalk, np.int32)]).astype(np.int32)
    points, all_faces, per_point = _point_values(points, all_faces, plant, leaf)
    poly = pv.PolyData.from_regular_faces(points, all_faces)
    poly.cell_data["plant"] = plant
    poly.cell_data["instance"] = np.concatenate([face_instance, stalk_inst]) + 1
    poly.cell_data["leaf"] = leaf
    light = np.full(nf + n_stalk, NOT_TRACED, np.int8)
    light[nf:] = STALK
    poly.cell_data["light"] = light
    poly.point_data["plant"], poly.point_data["leaf"] = per_point
    poly.field_data["leaf_triangles"] = np.array([nf])
    return poly


def _point_values(points: np.ndarray, faces: np.ndarray, plant: np.ndarray, leaf: np.ndarray):
    """``plant`` and ``leaf`` (per triangle) as values per vertex, for colouring: software
    OpenGL draws a mesh coloured per vertex in about 3/4 of the time of one coloured per
    triangle (VTK looks a triangle's colour up by its primitive id in every fragment). Every
    leaf and stalk has vertices of its own, so a vertex has one plant and one leaf; where a mesh
    shares a vertex between leaves (an imported canopy), the vertex is split, so the colours
    are those of the triangles. Returns (points, faces, (plant, leaf) per point)."""
    flat = faces.ravel()
    per_point = []
    for values in (plant, leaf):
        mine = np.zeros(len(points), np.int32)
        mine[flat] = np.repeat(values, 3)
        per_point.append(mine)
    if all(np.array_equal(p[faces], v[:, None].repeat(3, axis=1))
           for p, v in zip(per_point, (plant, leaf))):
        return points, faces, tuple(per_point)
    # one vertex per (vertex, plant and leaf), grouped by the id columns themselves (ids of
    # any width: no packing into one number)
    pairs, pair = groups(plant, leaf)
    first = np.empty(len(pairs), np.intp)
    first[pair[::-1]] = np.arange(len(pair))[::-1]  # the first triangle of each (plant, leaf)
    keys, inverse = groups(flat, np.repeat(pair, 3))
    leaf_of = first[keys[:, 1]]                     # a triangle of each new vertex's leaf
    return (points[keys[:, 0]], inverse.reshape(faces.shape).astype(faces.dtype),
            (plant[leaf_of].astype(np.int32), leaf[leaf_of].astype(np.int32)))


def _settle(poly: pv.PolyData) -> pv.PolyData:
    """Compute and keep what VTK works out of a new mesh before its first frame (its bounds,
    the bounds of the points the cells use, each coordinate's range), so that the worker
    thread pays for it and the first frame on the GUI thread does not. Call it last: any
    change to the mesh makes VTK compute them again."""
    poly.GetBounds()
    poly.GetCellsBounds([0.0] * 6)
    poly.GetPoints().GetData().GetRange(0)
    return make_pickable(poly)


#: Leaf and stalk triangles a canopy may have to be drawn whole. A frame costs about the time
#: to draw its triangles on software OpenGL (Mesa llvmpipe), and the first frame of a new mesh
#: about twice that (VTK builds and uploads its buffers on the GUI thread): 2.7 M triangles
#: 0.6 to 0.7 s a frame; the 336,400 the view used to draw at K = 4 left event-loop gaps of
#: 201 to 244 ms from the slider to their first frame on a quiet machine, 172,000 half of that.
#: Above it the view draws part of the canopy at the level asked (:data:`FINE_BUDGET`) and the
#: rest at a coarser level (see display_polydata; the window uses 36 triangles a leaf).
VIEW_BUDGET = 200_000
#: Triangles of the level asked drawn at most above :data:`VIEW_BUDGET`: the plants of the
#: sample tile nearest its centre whose triangles fit (at K = 4 on the example, 4 of its 9
#: plants, 132,000 triangles, and the other 77 plants at 36 triangles a leaf, 40,000).
FINE_BUDGET = 160_000


def display_polydata(canopy, coarse, fine: np.ndarray | None = None) -> pv.PolyData:
    """What the view draws of a canopy larger than :data:`VIEW_BUDGET`: the plants standing in
    the sample tile (the central one, whose light is traced and reported) nearest its centre
    whose triangles fit within :data:`FINE_BUDGET` at the canopy's own level, the others from
    ``coarse`` (the same plants and layout at a coarser level). Safe off the GUI thread.

    The mesh has the cell data of :func:`canopy_polydata`, and in field data ``source``: for
    each drawn leaf triangle, its triangle in ``canopy`` (-1 for a coarse one);
    ``canopy_triangles``; ``canopy_leaf`` (each canopy triangle's leaf), ``leaf_first`` (a
    triangle of each leaf) and ``drawn_leaf`` (each coarse triangle's leaf), so that light
    given per triangle of ``canopy`` colours the coarse plants per leaf
    (:meth:`Viewport.set_light`); ``view_note`` says what is drawn how. ``fine``: (P,) bool,
    the placements drawn at the canopy's level, if not those chosen as above.
    """
    note = fine is None
    if fine is None:
        fine = sample_plants(canopy, FINE_BUDGET)
    sampled = np.asarray(fine, bool)
    fine = np.flatnonzero(sampled[canopy.face_instance])
    rough = np.flatnonzero(~sampled[coarse.face_instance])
    # only the vertices these triangles use (the canopy's other plants' would be uploaded to
    # OpenGL for nothing: 1.3 M of the 1.5 M at K = 4)
    faces = np.vstack([canopy.faces[fine], coarse.faces[rough] + len(canopy.vertices)])
    used = np.zeros(len(canopy.vertices) + len(coarse.vertices), bool)
    used[faces.ravel()] = True
    renumber = np.cumsum(used) - 1
    vertices = np.vstack([canopy.vertices[used[:len(canopy.vertices)]],
                          coarse.vertices[used[len(canopy.vertices):]]])
    poly = _polydata(
        canopy, vertices, renumber[faces],
        *(np.concatenate([getattr(canopy, name)[fine], getattr(coarse, name)[rough]])
          for name in ("face_plant", "face_instance", "face_leaf")))
    poly.field_data["canopy_triangles"] = np.array([canopy.n_triangles])
    poly.field_data["source"] = np.concatenate([fine, np.full(len(rough), -1)]).astype(np.int64)
    # the leaves of the canopy, and for each coarse triangle drawn its leaf among them (-1: a
    # leaf the canopy does not have), worked out here so that colouring is cheap
    nf = canopy.n_triangles
    _, label = groups(np.concatenate([canopy.face_instance, coarse.face_instance[rough]]),
                      np.concatenate([canopy.face_leaf, coarse.face_leaf[rough]]))
    present = np.zeros(int(label.max()) + 1 if len(label) else 0, bool)
    present[label[:nf]] = True
    rank = np.cumsum(present) - 1                   # leaf of the canopy, in (instance, leaf) order
    inv = rank[label[:nf]]
    first = np.empty(int(present.sum()), np.int64)
    first[inv[::-1]] = np.arange(nf)[::-1]          # the first triangle of each leaf
    want = label[nf:]
    poly.field_data["canopy_leaf"] = inv.astype(np.int32)
    poly.field_data["leaf_first"] = first
    poly.field_data["drawn_leaf"] = np.where(present[want], rank[want], -1).astype(np.int64)
    if note:
        n, tile = int(sampled.sum()), int(sample_plants(canopy, None).sum())
        which = (f"the {n} plants of the sampled tile" if n == tile else
                 f"{n} of the {tile} plants of the sampled tile (those nearest its centre)")
        poly.field_data["view_note"] = [
            f"the view draws {which} at this level, {len(fine):,} triangles, and the other "
            f"{len(sampled) - n} plants at the display level, {len(rough):,} triangles (light, "
            "tables and exports use every triangle)"]
    _prepare_ground(canopy.layout)
    return _settle(poly)


def sample_plants(canopy, budget: int | None) -> np.ndarray:
    """(P,) bool: the placements standing in the sample tile (``canopy.layout.centre_bounds``),
    those nearest its centre whose triangles together fit within ``budget`` (None: all)."""
    x0, y0, x1, y1 = canopy.layout.centre_bounds
    xy = np.array([(p.x, p.y) for p in canopy.layout.placements], np.float64).reshape(-1, 2)
    inside = (x0 <= xy[:, 0]) & (xy[:, 0] <= x1) & (y0 <= xy[:, 1]) & (xy[:, 1] <= y1)
    if budget is None:
        return inside
    order = np.flatnonzero(inside)
    order = order[np.argsort(np.hypot(xy[order, 0] - (x0 + x1) / 2,
                                      xy[order, 1] - (y0 + y1) / 2), kind="stable")]
    per_plant = np.bincount(canopy.face_instance, minlength=len(xy))
    fits = np.cumsum(per_plant[order]) <= budget
    fits[:1] = True           # the central plant at least (a single plant over the budget)
    out = np.zeros(len(xy), bool)
    out[order[fits]] = True
    return out


def _per_drawn(mesh: pv.PolyData, values: np.ndarray, classes: bool) -> np.ndarray:
    """Values given per triangle of the canopy (F,) for each leaf triangle the view draws: its
    own where it is drawn as itself, else its leaf's (the most common class of the leaf's
    triangles, or the leaf's value: per-leaf values are the same on every triangle)."""
    if "source" not in mesh.field_data:
        return values
    source = np.asarray(mesh.field_data["source"])
    out = np.empty(len(source), values.dtype)
    own = source >= 0
    out[own] = values[source[own]]
    first = np.asarray(mesh.field_data["leaf_first"])
    if classes:                      # classes -1..2: the most common one per leaf
        inv = np.asarray(mesh.field_data["canopy_leaf"]).astype(np.int64)
        counts = np.bincount(inv * 4 + values.astype(np.int64) + 1, minlength=4 * len(first))
        per_leaf = counts.reshape(len(first), 4).argmax(axis=1) - 1
    else:
        per_leaf = values[first]
    drawn = np.asarray(mesh.field_data["drawn_leaf"])
    fill = NOT_TRACED if classes else np.nan
    out[~own] = np.where(drawn >= 0, per_leaf[np.maximum(drawn, 0)], fill)
    return out


def _rgb(colour: str) -> tuple[int, int, int]:
    """A colour name or #rrggbb as 0-255 RGB."""
    r, g, b = pv.Color(colour).int_rgb
    return int(r), int(g), int(b)


def _categorical(values: dict[int, tuple[str, str]]):
    """A lookup table of named categories: value -> (label, colour)."""
    lut = pv.LookupTable()
    lut.IndexedLookupOn()
    lut.SetNumberOfTableValues(len(values))
    for i, (value, (label, colour)) in enumerate(sorted(values.items())):
        r, g, b = pv.Color(colour).float_rgb
        lut.SetTableValue(i, r, g, b, 1.0)
        lut.SetAnnotation(value, label)
    return lut


class Viewport(QtInteractor):
    """The canopy view (see the module docstring)."""

    #: After each frame: the number of frames rendered so far.
    rendered = Signal(int)
    #: The (low, high) the light values' colours span, each time they are painted.
    limits_shown = Signal(float, float)
    #: A click on the canopy (a :class:`~maizeviz_app.picking.Pick`), or beside it (None).
    picked = Signal(object)
    #: A canopy's mesh was put on screen (show_canopy).
    canopy_set = Signal()
    #: The camera moved by the user or a preset: its pose ((position, focal point, up), cm).
    camera_moved = Signal(object)

    #: A press and release closer than this (pixels) is a click, not a drag of the camera.
    CLICK_PX = 4
    #: Colour of the picked leaf or plant.
    HIGHLIGHT = "#00e5ff"

    def __init__(self, parent=None):
        super().__init__(parent, auto_update=False, multi_samples=0, lighting="none")
        # two lights (pyvista's light kit has five; each is shading work for every pixel of
        # every frame on software OpenGL): one at the camera, one from high above
        self.add_light(pv.Light(light_type="headlight", intensity=0.75))
        self.add_light(pv.Light(position=(0.3, -0.4, 1.0), focal_point=(0, 0, 0),
                                light_type="scene light", intensity=0.45))
        self.setMinimumSize(320, 200)
        self.render_count = 0
        self.set_background("#e4edf5")          # a gradient costs a full-screen pass per frame
        # no VTK orientation triad, scalar bar or 3D text: each is a render pass or text
        # layout at every frame (60-80 ms each on llvmpipe); the ground carries the cm labels
        # in its texture, the legend is a Qt widget drawn once per colouring, and the axes and
        # scale bar are Qt's too, painted from the camera after each frame
        self.key = Legend(self)
        self.key.move(10, 10)
        self.key.hide()
        from maizeviz_app.view_overlay import ViewOverlay

        self.overlay = ViewOverlay(self)
        self.ren_win.AddObserver("EndEvent", self._on_frame)
        self.canopy_mesh: pv.PolyData | None = None
        self.colouring = "leaf"
        #: What the "light" colouring shows: "classes" (a sun) or "values" (a sky, a day).
        self.light_variant = "classes"
        self._light_key: tuple[str, str] = ("", "")        # colour-bar title, unit
        self._assimilation_key: tuple[str, str] = ("", "")
        self._canopy_actor = None
        self._ground_bounds = None
        self._layout = None
        self._framed = False
        self._digitizing_frame = None
        self._scale = None                   # the light values' ColourScale (set_colour_scale)
        #: What a sun's painting shows and why (set_sun).
        self.painting_note = ""
        #: Milliseconds the last click took to be answered (the pick and every slot of
        #: ``picked``: the selection, the info card), from the release event's delivery.
        self.last_pick_ms: float | None = None
        self._press: tuple[float, float] | None = None
        self._held = None                       # a left press not yet handed to VTK
        self.info = InfoCard(self)
        #: how the plants other than the selection are drawn (set_others)
        self.others = "shown"
        self._moving = False                    # the lighter canopy drawn (the camera moves)
        self._moving_source = None
        self._moving_mtime = -1
        self._moving_mesh = None
        self._rest = QTimer(self)
        self._rest.setSingleShot(True)
        self._rest.timeout.connect(self.stop_moving)
        self.info.hide()
        #: The (low, high) the light values' colours span, once painted.
        self.shown_limits: tuple[float, float] | None = None

    # ------------------------------------------------------------------ rendering
    def render(self) -> None:
        """Schedule one repaint (see the module docstring); never renders on the spot."""
        if getattr(self, "_closed", False):
            return
        try:
            self.update()
        except RuntimeError:                      # the widget is being deleted
            pass

    def _on_frame(self, *_args) -> None:
        self.render_count += 1
        cam = self.renderer.GetActiveCamera()
        if hasattr(self, "overlay"):
                self.overlay.update_from(
                cam.GetPosition(), cam.GetFocalPoint(), cam.GetViewUp(), cam.GetViewAngle(),
                cam.GetParallelScale() if cam.GetParallelProjection() else None)
        self.rendered.emit(self.render_count)

    # ------------------------------------------------------------------ canopy
    def show_canopy(self, canopy, mesh: pv.PolyData | None = None) -> None:
        """Show a canopy (its mesh prepared by :func:`canopy_polydata` when given); the camera
        frames the first canopy and then stays where the user put it."""
        poly = mesh if mesh is not None else canopy_polydata(canopy)
        self.canopy_mesh = poly
        self._layout = canopy.layout
        self._clear_digitizing()
        if self._canopy_actor is None:
            self._canopy_actor = self.add_mesh(poly, name="canopy", render=False,
                                               show_scalar_bar=False, smooth_shading=False,
                                               scalars="leaf")
        else:
            self._canopy_actor.mapper.SetInputData(poly)
        self._canopy_actor.SetVisibility(True)
        self._highlight_actor()
        self._set_ground(canopy.layout)
        if "light_value" not in poly.cell_data:
            self.light_variant = "classes"
        if self.colouring == "assimilation" and not self.has_assimilation():
            self.colouring = "light"
        if self.colouring == "light" and not self.has_light():
            self.colouring = "leaf"
        self._apply_colouring()
        if not self._framed:
            self.camera_preset("reset")
            self._framed = True
        self.render()
        self.canopy_set.emit()

    def has_assimilation(self) -> bool:
        """The canopy shown has CO2 assimilation values to colour by."""
        return self.canopy_mesh is not None and \
            "assimilation_value" in self.canopy_mesh.cell_data

    def has_light(self) -> bool:
        if self.canopy_mesh is None:
            return False
        if self.light_variant == "values":
            return "light_value" in self.canopy_mesh.cell_data
        return bool(np.any(self.canopy_mesh.cell_data["light"] >= 0))

    def set_light(self, classes: np.ndarray | None) -> None:
        """Light class of every leaf triangle (F,) (see ``maizeviz.light.results.per_leaf.
        triangle_light``), or None to forget it; the view follows if coloured by light."""
        if self.canopy_mesh is None:
            return
        light = self.canopy_mesh.cell_data["light"]
        nf = int(self.canopy_mesh.field_data["leaf_triangles"][0])
        given = int(self.canopy_mesh.field_data.get("canopy_triangles", [nf])[0])
        if classes is None:
            light[:nf] = NOT_TRACED
        else:
            if len(classes) != given:
                raise ValueError(f"{len(classes)} light classes for {given} leaf triangles")
            light[:nf] = _per_drawn(self.canopy_mesh, np.asarray(classes), True)
        self.canopy_mesh.cell_data["light"] = light          # marks the array modified
        if classes is not None:
            self.light_variant = "classes"
        if self.colouring == "light":
            self._apply_colouring()
            self.render()

    def set_sun(self, painting, asked: str = "auto", classes: np.ndarray | None = None) -> None:
        """A sun's light as ``painting`` (a :class:`maizeviz.light.results.painting.SunPainting`)
        says is honest, or as ``asked`` (``auto``, ``triangles``, ``leaves``): each triangle's
        class, or each leaf's sunlit share on the colour scale. Without a painting, the
        triangles' ``classes``. :attr:`painting_note` says which and why."""
        if painting is None:
            self.painting_note = ""
            self.set_light(classes)
            return
        per = painting.chosen(asked)
        self.painting_note = painting.note(per)
        if per == "leaves":
            self.set_light_values(painting.share, "sunlit share of each leaf (too few rays "
                                  "per triangle to class each)" if painting.per == "leaves"
                                  else "sunlit share of each leaf", "")
        else:
            self.set_light(painting.classes)

    def set_light_values(self, values: np.ndarray, title: str, unit: str) -> None:
        """A value per leaf triangle (F,) (a sky's or a day's light per m2 of leaf, NaN where
        not traced) for the "light" colouring, with a colour bar titled ``title``; the view
        follows if coloured by light."""
        if self.canopy_mesh is None:
            return
        self.canopy_mesh.cell_data["light_value"] = self._cells_of(values, "light")
        self.light_variant = "values"
        self._light_key = (title, unit)
        if self.colouring == "light":
            self._apply_colouring()
            self.render()

    def set_assimilation_values(self, values: np.ndarray | None, title: str = "",
                                unit: str = "") -> None:
        """Gross CO2 assimilation per m2 of leaf on each leaf triangle (F,) float (NaN where
        not traced) for the ``assimilation`` colouring, with a colour bar titled ``title``;
        None forgets it (a light without a leaf model), and a view coloured by it goes back
        to the light."""
        if self.canopy_mesh is None:
            return
        if values is None:
            if "assimilation_value" in self.canopy_mesh.cell_data:
                del self.canopy_mesh.cell_data["assimilation_value"]
            if self.colouring == "assimilation":
                self.colouring = "light" if self.has_light() else "leaf"
                self._apply_colouring()
                self.render()
            return
        self.canopy_mesh.cell_data["assimilation_value"] = self._cells_of(values,
                                                                         "assimilation")
        self._assimilation_key = (title, unit)
        if self.colouring == "assimilation":
            self._apply_colouring()
            self.render()

    def _cells_of(self, values: np.ndarray, what: str) -> np.ndarray:
        """(n_cells,) float32 of the drawn mesh from a value per leaf triangle of the canopy
        (F,): stalks -1 (below any range); ValueError for a wrong length."""
        assert self.canopy_mesh is not None
        nf = int(self.canopy_mesh.field_data["leaf_triangles"][0])
        given = int(self.canopy_mesh.field_data.get("canopy_triangles", [nf])[0])
        if len(values) != given:
            raise ValueError(f"{len(values)} {what} values for {given} leaf triangles")
        cells = np.full(self.canopy_mesh.n_cells, -1.0, np.float32)     # stalks below range
        cells[:nf] = _per_drawn(self.canopy_mesh, np.asarray(values), False)
        return cells

    def colour_by(self, what: str) -> bool:
        """Colour the canopy by ``plant``, ``leaf``, ``light`` or ``assimilation``; False
        (and nothing changes) for light or assimilation when no such result belongs to this
        canopy."""
        if what not in COLOURINGS:
            raise ValueError(f"unknown colouring {what}")
        if what == "light" and not self.has_light() or \
                what == "assimilation" and not self.has_assimilation():
            return False
        if what != self.colouring:
            self.colouring = what
            self._apply_colouring()
            self.render()
        return True

    def _apply_colouring(self) -> None:
        if self._canopy_actor is None or self.canopy_mesh is None:
            return
        mapper = self._canopy_actor.mapper
        what = self.colouring
        cells = self.canopy_mesh.cell_data
        array = what
        if what == "light" and self.light_variant == "values":
            self._paint_values(mapper, "light_value", self._light_key)
            return
        if what == "assimilation":
            self._paint_values(mapper, "assimilation_value", self._assimilation_key)
            return
        mapper.SetColorModeToMapScalars()
        if what == "light":
            shown = {k: v for k, v in LIGHT_CLASSES.items() if k != NOT_TRACED}
            lut = _categorical(LIGHT_CLASSES)
            lo, hi = float(min(LIGHT_CLASSES)), float(max(LIGHT_CLASSES))
            self.key.set_categories("light received (the paper's classes)",
                                       [shown[k] for k in sorted(shown, reverse=True)])
        elif what == "plant":
            ids = np.unique(cells["plant"])
            cats = {int(p): (f"plant {p}", _PLANT_COLOURS[k % len(_PLANT_COLOURS)])
                    for k, p in enumerate(ids)}
            lut = _categorical(cats)
            lo, hi = float(ids.min()), float(ids.max())
            self.key.set_categories("digitized plant", list(cats.values()))
        else:
            hi = float(max(cells["leaf"].max(), 1))
            lut = pv.LookupTable(cmap="summer", n_values=max(int(hi), 2))
            lut.SetBelowRangeColor(*pv.Color(LIGHT_CLASSES[STALK][1]).float_rgb, 1.0)
            lut.UseBelowRangeColorOn()
            lo = 1.0
            self.key.set_gradient("leaf rank (from the base)", np.asarray(lut.values),
                                     int(lo), int(hi), LIGHT_CLASSES[STALK])
        lut.SetTableRange(lo, hi)
        mapper.SetLookupTable(lut)
        if array in self.canopy_mesh.point_data:     # plant, leaf: per vertex (cheaper)
            mapper.SetScalarModeToUsePointFieldData()
            mapper.SetInterpolateScalarsBeforeMapping(False)   # one value per leaf anyway
        else:                                        # light: per triangle
            mapper.SetScalarModeToUseCellFieldData()
        mapper.SelectColorArray(array)
        mapper.SetScalarRange(lo, hi)
        mapper.SetUseLookupTableScalarRange(True)
        mapper.ScalarVisibilityOn()
        self.key.show()

    def set_colour_scale(self, scale) -> None:
        """Colour light values by ``scale`` (a :class:`~maizeviz_app.colour.ColourScale`,
        followed: a change repaints the canopy if it shows light values)."""
        if self._scale is not None:
            self._scale.events.disconnect(self._on_scale)
        self._scale = scale
        scale.events.connect(self._on_scale)
        self._on_scale()

    def _on_scale(self, *_args) -> None:
        if self.colouring == "light" and self.light_variant == "values" or \
                self.colouring == "assimilation":
            self._apply_colouring()
            self.render()

    def _paint_values(self, mapper, array: str, key: tuple[str, str]) -> None:
        """Values per triangle (cell data ``array``: ``light_value`` or
        ``assimilation_value``; leaves' values, NaN not traced, -1 for stalks) as colours of
        the view's scale, one RGB per triangle (``light_rgb``), the colour bar titled
        ``key`` (title, unit): stalks and triangles not traced keep their own colours
        whatever the range clips."""
        from maizeviz_app.colour import ColourError, ColourScale, colour_table, colours_of

        mesh = self.canopy_mesh
        assert mesh is not None
        nf = int(mesh.field_data["leaf_triangles"][0])
        values = np.asarray(mesh.cell_data[array])
        scale = self._scale if self._scale is not None else ColourScale(cmap="inferno")
        try:
            lo, hi = scale.limits(values[:nf])
        except ColourError:                       # a range being typed: the data's for now
            lo, hi = ColourScale(log=scale.log).limits(values[:nf])
        table = colour_table(scale.cmap)
        rgb = np.empty((mesh.n_cells, 3), np.uint8)
        rgb[:nf] = colours_of(values[:nf], lo, hi, table, scale.log,
                              nan=_rgb(LIGHT_CLASSES[NOT_TRACED][1]))
        rgb[nf:] = _rgb(LIGHT_CLASSES[STALK][1])
        mesh.cell_data["light_rgb"] = rgb
        self.shown_limits = (lo, hi)
        self.limits_shown.emit(lo, hi)
        mapper.SetScalarModeToUseCellFieldData()
        mapper.SelectColorArray("light_rgb")
        mapper.SetColorModeToDirectScalars()
        mapper.ScalarVisibilityOn()
        title, unit = key
        leaf = values[:nf][np.isfinite(values[:nf])]
        low = ("≤ " if len(leaf) and leaf.min() < lo else "") + tick_text(lo)
        high = ("≥ " if len(leaf) and leaf.max() > hi else "") + tick_text(hi)
        items = [LIGHT_CLASSES[STALK]]
        if np.isnan(values[:nf]).any():
            items.append(LIGHT_CLASSES[NOT_TRACED])
        self.key.set_gradient(title + (" (log scale)" if scale.log else ""), table,
                              low, f"{high} {unit}".rstrip(), items)
        self.key.show()

    # ------------------------------------------------------------------ ground
    def _set_ground(self, layout) -> None:
        """The ground: the field with its plant cells as a grid, and the x and y axes with
        cm labels in a margin around it, all one textured rectangle (one cheap draw); made by
        the worker that made the canopy's mesh when it could (:func:`ground_for`)."""
        key = _ground_key(layout)
        if key == self._ground_bounds:
            return
        self._ground_bounds = key
        ground, texture = ground_for(layout)
        self.add_mesh(ground, name="ground", texture=texture, render=False,
                      pickable=False, lighting=False)

    # ------------------------------------------------------------------ camera
    def camera_preset(self, name: str) -> None:
        """``top``, ``front`` (looking along the rows, +y), ``side`` (across them, +x),
        ``iso`` (from the south-west corner, 45 degrees up) or ``reset`` (the view a canopy
        first opens in: from the south-west, above, so that the ground's labels read the right
        way up); each frames the canopy. The earlier names ``along``, ``across`` and
        ``perspective`` are understood."""
        name = CAMERA_ALIASES.get(name, name)
        if name not in CAMERAS:
            raise ValueError(f"unknown camera preset {name}")
        cam = self.camera
        if name == "top":
            self.view_xy(render=False)
        elif name == "front":
            self.view_xz(render=False)
        elif name == "side":
            self.view_yz(negative=True, render=False)
        elif name == "iso":
            self.view_vector((-1.0, -1.0, np.sqrt(2.0)), viewup=(0, 0, 1), render=False)
        else:
            self.view_vector((-0.75, -1.3, 0.95), viewup=(0, 0, 1), render=False)
        cam.SetParallelProjection(False)
        self.reset_camera(render=False)
        if name == "reset":
            cam.Zoom(1.25)
        self.render()
        self.camera_moved.emit(self.camera_pose())

    def camera_pose(self):
        """The camera's position, focal point and view up (cm), as three tuples."""
        cam = self.camera
        return tuple(tuple(float(v) for v in vec) for vec in
                     (cam.GetPosition(), cam.GetFocalPoint(), cam.GetViewUp()))

    def set_camera_pose(self, pose) -> None:
        """Put the camera at ``pose`` (as :meth:`camera_pose` gives it); nothing when it is
        there already."""
        if pose is None or pose == self.camera_pose():
            return
        cam = self.camera
        position, focal, up = pose
        cam.SetPosition(*position)
        cam.SetFocalPoint(*focal)
        cam.SetViewUp(*up)
        self.renderer.ResetCameraClippingRange()
        self.render()

    # ------------------------------------------------------------------ digitizing
    def hide_canopy(self) -> None:
        """Make room for a digitizing session: the canopy and the ground go (the canopy comes
        back with :meth:`restore_canopy` or the next :meth:`show_canopy`)."""
        for name in ("canopy", "ground", "selection"):
            self.remove_actor(name, render=False)
        self.info.set_lines([])
        self._canopy_actor = None
        self._ground_bounds = None
        self.key.hide()
        self._digitizing_frame = None
        self.render()

    def restore_canopy(self) -> None:
        """The canopy back after a digitizing session (the plant being digitized goes)."""
        self._clear_digitizing()
        if self.canopy_mesh is not None and self._layout is not None:
            self.show_canopy(_Shown(self._layout), self.canopy_mesh)
            self.camera_preset("reset")
        self.render()

    def _clear_digitizing(self) -> None:
        self.clear_digitized(render=False)

    # ----------------------------------------------------- the plant being digitized
    # Used by the digitizer panel: one actor per leaf surface (named "leafsurf...", so a new
    # canopy clears them), the points as one small semi-transparent actor, the last press as
    # one opaque dot. Each call asks for one frame unless told not to.
    def show_digitized_leaf(self, name: str, vertices: np.ndarray, faces: np.ndarray,
                            render: bool = True) -> None:
        """Add or replace one leaf surface (vertices (n, 3) cm, faces (F, 3) int)."""
        poly = pv.PolyData.from_regular_faces(np.asarray(vertices, np.float32),
                                              np.asarray(faces, np.int64))
        self.add_mesh(poly, name=name, color="yellowgreen", smooth_shading=True,
                      reset_camera=False, render=False)
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

    def show_leaf_surfaces(self, meshes, points) -> None:
        """The plant being digitized in one call: leaf meshes (``LeafMesh`` list) as one
        surface and the digitized points (N, 3) cm, small and semi-transparent over it; the
        camera reframes when the points leave the framed region (a new plant)."""
        self.clear_digitized(render=False)
        if meshes:
            verts = np.concatenate([m.points for m in meshes]).astype(np.float32)
            offs = np.cumsum([0] + [len(m.points) for m in meshes[:-1]])
            faces = np.concatenate([m.faces.astype(np.int64) + o for m, o in zip(meshes, offs)])
            self.show_digitized_leaf("leafsurf", verts, faces, render=False)
        pts = np.asarray(points, np.float32).reshape(-1, 3)
        if len(pts):
            self.show_digitized_points(pts, None, render=False)
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            frame = self._digitizing_frame
            if frame is None or np.any(lo < frame[0]) or np.any(hi > frame[1]):
                pad = np.maximum(0.3 * (hi - lo), 10.0)
                self._digitizing_frame = (lo - pad, hi + pad)
                self.frame_bounds(np.column_stack(self._digitizing_frame).ravel(), render=False)
        self.render()

    # ------------------------------------------------------------------ picking
    def resizeEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        self.overlay.place()
        if self.info.isVisible():
            self.info.set_lines(self.info.text().splitlines())

    # A left press is held back from VTK until the mouse moves: a click then picks without
    # VTK's camera interaction starting and stopping, each of which renders a frame at once
    # (two frames of 150-300 ms per click at K = 4 on software OpenGL); a drag is handed to
    # VTK from the press's own position, so the camera turns as before.
    def mousePressEvent(self, event) -> None:  # noqa: N802 - Qt's name
        if event.button() == Qt.MouseButton.LeftButton and event.buttons() == event.button():
            self._press = (event.position().x(), event.position().y())
            self._held = event.clone()
            return
        self._release_held()
        super().mousePressEvent(event)

    def mouseMoveEvent(self, event) -> None:  # noqa: N802 - Qt's name
        if self._held is not None and self._press is not None:
            pos = event.position()
            if abs(pos.x() - self._press[0]) + abs(pos.y() - self._press[1]) > self.CLICK_PX:
                self._release_held()
        super().mouseMoveEvent(event)

    def mouseReleaseEvent(self, event) -> None:  # noqa: N802 - Qt's name
        t0 = time.perf_counter()
        if self._held is not None and event.button() == Qt.MouseButton.LeftButton:
            self._held, self._press = None, None                  # a click: VTK never saw it
            pos = event.position()
            self.picked.emit(self.pick_at(pos.x(), pos.y()))
            self.last_pick_ms = 1000 * (time.perf_counter() - t0)
            return
        self._press = None
        super().mouseReleaseEvent(event)
        self.stop_moving()
        self.camera_moved.emit(self.camera_pose())      # a drag VTK turned the camera by

    def wheelEvent(self, event) -> None:  # noqa: N802 - Qt's name
        if self.start_moving() or self._moving:
            self._rest.start(self.MOVING_REST_MS)
        super().wheelEvent(event)
        self.camera_moved.emit(self.camera_pose())

    def _release_held(self) -> None:
        """Hand the held press to VTK (a drag begins)."""
        held, self._held = self._held, None
        if held is not None:
            self.start_moving()
            super().mousePressEvent(held)

    # A lighter drawing while the camera moves (ParaView's level of detail): a drag or a wheel
    # turn draws every k-th triangle of a canopy above MOVING_TRIANGLES, coloured as the
    # canopy; the whole canopy is drawn again once the camera stops (the release, or
    # MOVING_REST_MS after the last wheel step).
    MOVING_TRIANGLES = 40_000
    MOVING_REST_MS = 250

    def start_moving(self) -> bool:
        """Draw the lighter canopy until :meth:`stop_moving` (False: the canopy is light
        enough, hidden, or not there)."""
        canopy, mesh = self._canopy_actor, self.canopy_mesh
        if canopy is None or mesh is None or self._moving or not canopy.GetVisibility() or \
                mesh.n_cells <= 1.5 * self.MOVING_TRIANGLES:
            return False
        lod = self._moving_actor(mesh)
        lod.GetMapper().ShallowCopy(canopy.GetMapper())     # the colours, as drawn now
        lod.GetMapper().SetInputData(self._moving_mesh)
        lod.SetProperty(canopy.GetProperty())
        lod.SetVisibility(True)
        canopy.SetVisibility(False)
        self._moving = True
        return True

    def stop_moving(self) -> None:
        """The whole canopy drawn again (the camera stopped)."""
        if not self._moving:
            return
        self._moving = False
        self._rest.stop()
        self.actors["canopy_moving"].SetVisibility(False)
        if self._canopy_actor is not None:
            self._canopy_actor.SetVisibility(True)
        self.render()

    def _moving_actor(self, mesh: pv.PolyData):
        """The lighter canopy's actor, its mesh remade when the canopy's changed: every k-th
        triangle (cell data kept, so it colours as the canopy)."""
        mtime = int(mesh.GetMTime())
        if self._moving_source is not mesh or self._moving_mtime != mtime:
            k = int(np.ceil(mesh.n_cells / self.MOVING_TRIANGLES))
            self._moving_mesh = _every_kth(mesh, k)
            self._moving_source, self._moving_mtime = mesh, mtime
        actor = self.actors.get("canopy_moving")
        if actor is None:
            actor = self.add_mesh(self._moving_mesh, name="canopy_moving", render=False,
                                  reset_camera=False, pickable=False, show_scalar_bar=False)
            actor.SetVisibility(False)
        return actor

    def pick_at(self, x: float, y: float) -> Pick | None:
        """What of the canopy is under the widget point (``x``, ``y``), None if nothing."""
        if self._canopy_actor is None or not self._canopy_actor.GetVisibility():
            return None
        ratio = self.devicePixelRatioF()
        return pick(self.canopy_mesh, self.renderer, x * ratio, (self.height() - y - 1) * ratio)

    def display_point(self, world) -> tuple[float, float]:
        """The widget point (x, y) where the world point ``world`` (cm) is drawn."""
        ren = self.renderer
        ren.SetWorldPoint(float(world[0]), float(world[1]), float(world[2]), 1.0)
        ren.WorldToDisplay()
        dx, dy, _ = ren.GetDisplayPoint()
        ratio = self.devicePixelRatioF()
        return dx / ratio, self.height() - 1 - dy / ratio

    def highlight(self, instance: int, leaf: int = -1) -> bool:
        """Draw placement ``instance``'s leaf ``leaf`` (or the whole plant, -1) highlighted,
        over the canopy; a negative ``instance`` clears. False if none of it is drawn. One
        actor, made once, takes each selection's triangles (a new actor per click costs
        pyvista's set-up, 5-50 ms)."""
        part = None
        if instance >= 0 and self.canopy_mesh is not None:
            part = part_mesh(self.canopy_mesh, instance, leaf)
        actor = self.actors.get("selection")
        if part is None:
            changed = self._draw_others(False)
            if actor is not None and actor.GetVisibility():
                actor.SetVisibility(False)
                changed = True
            if changed:
                self.render()
            return False
        actor = self._highlight_actor()
        actor.mapper.dataset = part
        actor.SetVisibility(True)
        self._draw_others(True)
        self.render()
        return True

    PROBE = "#ff6f00"

    def show_probe(self, points, closed: bool = False) -> None:
        """The probe's points (k, 3) cm and the line through them (closed: a polygon); none:
        nothing drawn."""
        for name in ("probe_points", "probe_line"):
            if name in self.actors:
                self.remove_actor(name, render=False)
        pts = np.asarray(points, np.float64).reshape(-1, 3)
        if len(pts):
            self.add_mesh(pv.PolyData(pts), name="probe_points", color=self.PROBE,
                          point_size=9, style="points", pickable=False, reset_camera=False,
                          render=False, lighting=False)
        if len(pts) >= 2:
            order = list(range(len(pts))) + ([0] if closed and len(pts) >= 3 else [])
            line = pv.PolyData(pts, lines=np.array([len(order), *order]))
            self.add_mesh(line, name="probe_line", color=self.PROBE, line_width=3,
                          pickable=False, reset_camera=False, render=False, lighting=False)
        self.render()

    def set_others(self, mode: str) -> None:
        """How the plants other than the selection are drawn while there is one: "shown",
        "faded" (the selection seen through them) or "hidden" (the selection alone)."""
        from maizeviz_app.view_state import OTHERS

        if mode not in OTHERS:
            raise ValueError(f"unknown mode {mode}; one of {', '.join(OTHERS)}")
        self.others = mode
        actor = self.actors.get("selection")
        if self._draw_others(actor is not None and bool(actor.GetVisibility())):
            self.render()

    def _draw_others(self, selected: bool) -> bool:
        """The canopy drawn as :attr:`others` says (as it is without a selection); whether
        anything changed."""
        from maizeviz_app.view_state import FADED_OPACITY

        actor = self._canopy_actor
        if actor is None:
            return False
        mode = self.others if selected else "shown"
        visible = mode != "hidden"
        opacity = FADED_OPACITY if mode == "faded" else 1.0
        prop = actor.GetProperty()
        if bool(actor.GetVisibility()) == visible and prop.GetOpacity() == opacity:
            return False
        actor.SetVisibility(visible)
        prop.SetOpacity(opacity)
        return True

    def _highlight_actor(self):
        """The actor that draws the selection (made once, hidden; show_canopy makes it, so
        that the first click does not pay for it)."""
        actor = self.actors.get("selection")
        if actor is None:
            dummy = pv.PolyData.from_regular_faces(np.eye(3, dtype=np.float32),
                                                   np.array([[0, 1, 2]]))
            actor = self.add_mesh(dummy, name="selection", color=self.HIGHLIGHT, render=False,
                                  reset_camera=False, pickable=False, lighting=True)
            # drawn over the canopy's same triangles, not fighting them for the pixels
            actor.mapper.SetResolveCoincidentTopologyToPolygonOffset()
            actor.mapper.SetRelativeCoincidentTopologyPolygonOffsetParameters(-2.0, -2.0)
            actor.SetVisibility(False)
        return actor

    def frame_part(self, instance: int, leaf: int = -1) -> bool:
        """Point the camera at placement ``instance`` (its leaf ``leaf``), keeping its
        direction; False if none of it is drawn."""
        if self.canopy_mesh is None:
            return False
        bounds = part_bounds(self.canopy_mesh, instance, leaf)
        if bounds is None:
            return False
        self.frame_bounds(bounds)
        return True

    def close(self) -> None:
        try:
            self.ren_win.RemoveObservers("EndEvent")
        except AttributeError:
            pass
        super().close()


def _every_kth(mesh: pv.PolyData, k: int) -> pv.PolyData:
    """Every ``k``-th triangle of ``mesh``, its points and cell data kept (the lighter
    canopy a moving camera draws)."""
    if not mesh.is_all_triangles:
        return mesh.extract_cells(np.arange(0, mesh.n_cells, k)).extract_surface(
            algorithm="dataset_surface")
    faces = mesh.faces.reshape(-1, 4)[::k]
    out = pv.PolyData(mesh.points, faces=faces.ravel())
    for name in mesh.cell_data:
        out.cell_data[name] = np.asarray(mesh.cell_data[name])[::k]
    if mesh.cell_data.active_scalars_name:
        out.cell_data.active_scalars_name = mesh.cell_data.active_scalars_name
    return out


def _card(widget: QWidget) -> QPainter:
    """A painter on ``widget`` after its card: a rounded, nearly opaque white rectangle (the
    view shows through a little); the pen set for dark text."""
    p = QPainter(widget)
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    p.setPen(Qt.PenStyle.NoPen)
    p.setBrush(QColor(255, 255, 255, 220))
    p.drawRoundedRect(QRectF(widget.rect()), 6, 6)
    p.setPen(QColor("#222222"))
    return p


class InfoCard(QWidget):
    """What was picked, over the 3D view's bottom left: a few lines of text on a white card
    (a Qt widget: nothing is drawn in the 3D scene). Clicks go through it to the view."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setAttribute(Qt.WidgetAttribute.WA_TransparentForMouseEvents)
        self._lines: list[str] = []

    def set_lines(self, lines: list[str]) -> None:
        """Show ``lines`` (none: hide the card)."""
        self._lines = list(lines)
        if not self._lines:
            self.hide()
            return
        fm = self.fontMetrics()
        width = max(fm.horizontalAdvance(t) for t in self._lines) + 20
        height = (fm.height() + 2) * len(self._lines) + 12
        self.resize(width, height)
        parent = self.parentWidget()
        if parent is not None:
            self.move(10, max(parent.height() - height - 10, 10))
        self.show()
        self.raise_()
        self.update()

    def text(self) -> str:
        return "\n".join(self._lines)

    def paintEvent(self, _event) -> None:  # noqa: N802 - Qt's name
        p = _card(self)
        fm = self.fontMetrics()
        y = 6
        for k, line in enumerate(self._lines):
            font = p.font()
            font.setBold(k == 0)
            p.setFont(font)
            p.drawText(QRectF(10, y, self.width() - 20, fm.height() + 2), LEFT, line)
            y += fm.height() + 2
        p.end()


class _Shown:
    """What :meth:`Viewport.show_canopy` needs of a canopy whose mesh it already has."""

    def __init__(self, layout):
        self.layout = layout


#: Grounds made for the last few layouts (key -> plane, texture), by the workers that make the
#: canopies' meshes, so that a new field's first frame does not wait for its texture (50-150
#: ms of painting and copying on the GUI thread).
_GROUNDS: dict[tuple, tuple[pv.PolyData, pv.Texture]] = {}
_GROUNDS_LOCK = threading.Lock()


def _ground_key(layout) -> tuple:
    return tuple(round(v, 6) for v in layout.bounds) + (layout.row_spacing,
                                                        layout.plant_spacing)


def ground_for(layout) -> tuple[pv.PolyData, pv.Texture]:
    """The ground plane and its texture (:func:`ground_image`) of ``layout``'s field, made
    once per field (any thread: the texture is painted on a QImage)."""
    key = _ground_key(layout)
    with _GROUNDS_LOCK:
        made = _GROUNDS.get(key)
    if made is not None:
        return made
    x0, y0, x1, y1, rs, ps = key
    margin = max(25.0, 0.09 * max(x1 - x0, y1 - y0))
    gx0, gy0, gx1, gy1 = x0 - margin, y0 - margin, x1 + margin, y1 + margin
    ground = pv.Plane(center=((gx0 + gx1) / 2, (gy0 + gy1) / 2, -0.05),
                      i_size=gx1 - gx0, j_size=gy1 - gy0)
    image = ground_image((x0, y0, x1, y1), margin, _ticks(x0, x1, rs), _ticks(y0, y1, ps))
    made = (ground, pv.Texture(image))
    with _GROUNDS_LOCK:
        while len(_GROUNDS) >= 4:
            _GROUNDS.pop(next(iter(_GROUNDS)))
        _GROUNDS[key] = made
    return made


def _prepare_ground(layout) -> None:
    """Make ``layout``'s ground ahead (a worker, where an application exists to paint text)."""
    from PySide6.QtGui import QGuiApplication

    if QGuiApplication.instance() is not None:
        ground_for(layout)


def _ticks(lo: float, hi: float, step: float) -> np.ndarray:
    """Grid positions from ``lo`` to ``hi`` every ``step`` (both ends included)."""
    n = int(np.floor((hi - lo) / step + 1e-9))
    xs = lo + step * np.arange(n + 1)
    if hi - xs[-1] > 1e-6 * step:
        xs = np.append(xs, hi)
    return xs


def ground_labels(field: tuple[float, float, float, float], margin: float, xs: np.ndarray,
                  ys: np.ndarray) -> list[tuple[str, float, float, float, float]]:
    """What the ground's margin says, and where: (text, x, y, width, angle) with the centre
    (x, y) in cm, the width in label heights (a label is ``0.6 * margin`` cm high) and the
    angle in degrees as QPainter turns it (clockwise on the image, y up the field).

    Tick labels in cm under the x edge and along the y edge, at most 7 and 5 of them (none
    at the corner, where the first x label is); the axis names. What lies along y is read
    from the far end (so it stands upright from the views that look up the field) and, turned,
    needs only a label's height of the margin."""
    x0, y0, x1, y1 = field
    step_x = max(1, int(np.ceil(len(xs) / 7)))
    step_y = max(1, int(np.ceil(len(ys) / 5)))
    out = [(f"{x:.0f}", float(x), y0 - margin * 0.27, 4.0, 0.0) for x in xs[::step_x]]
    out += [(f"{y:.0f}", x0 - margin * 0.27, float(y), 4.0, 90.0) for y in ys[::step_y]
            if not (len(xs) and y - y0 < margin * 0.5)]
    out.append(("x (cm, across the rows)", (x0 + x1) / 2, y0 - margin * 0.72, 40.0, 0.0))
    out.append(("y (cm, along the rows)", x0 - margin * 0.72, (y0 + y1) / 2, 40.0, 90.0))
    return out


def ground_image(field: tuple[float, float, float, float], margin: float, xs: np.ndarray,
                 ys: np.ndarray, max_px: int = 2048) -> np.ndarray:
    """The ground texture (h, w, 4) uint8, row 0 at the largest y (as pyvista maps an image
    on a plane): the field (tan) with grid
    lines at ``xs`` / ``ys`` (cm), and a ``margin`` (cm) carrying the tick labels in cm and
    the axis names. Any thread (QPainter on a QImage), once an application exists."""
    x0, y0, x1, y1 = field
    width_cm, height_cm = x1 - x0 + 2 * margin, y1 - y0 + 2 * margin
    scale = min(4.0, max_px / max(width_cm, height_cm))
    w, h = int(round(width_cm * scale)), int(round(height_cm * scale))
    img = QImage(w, h, QImage.Format.Format_RGBA8888)
    img.fill(QColor("#ece3cc"))

    def px(x, y):
        return QPointF((x - x0 + margin) * scale, (y1 + margin - y) * scale)

    p = QPainter(img)
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    p.fillRect(QRectF(px(x0, y1), px(x1, y0)), QColor("#cdb98f"))
    p.setPen(QPen(QColor("#8a7a55"), max(1.0, 0.35 * scale)))
    for x in xs:
        p.drawLine(px(x, y0), px(x, y1))
    for y in ys:
        p.drawLine(px(x0, y), px(x1, y))
    font = QFont("DejaVu Sans")
    font.setPixelSize(max(8, int(margin * scale * 0.42)))
    p.setFont(font)
    p.setPen(QColor("#333333"))
    box = margin * scale * 0.6
    for text, x, y, wide, angle in ground_labels(field, margin, xs, ys):
        p.save()
        p.translate(px(x, y))
        p.rotate(angle)
        p.drawText(QRectF(-wide * box / 2, -box / 2, wide * box, box), CENTRE, text)
        p.restore()
    p.end()
    arr = np.frombuffer(img.constBits(), np.uint8).reshape(h, img.bytesPerLine())[:, :4 * w]
    return arr.reshape(h, w, 4).copy()


class Legend(QWidget):
    """The colour key over the 3D view: categories (swatches) or a gradient. A Qt widget, so
    it costs nothing at each frame."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setAttribute(Qt.WidgetAttribute.WA_TransparentForMouseEvents)
        self._title = ""
        self._items: list[tuple[str, str]] = []
        self._gradient: tuple | None = None

    def set_categories(self, title: str, items: list[tuple[str, str]]) -> None:
        self._title, self._items, self._gradient = title, list(items), None
        self._fit()

    def set_gradient(self, title: str, colours: np.ndarray, lo, hi,
                     below=None) -> None:
        """A colour bar from ``lo`` to ``hi`` (numbers or text with units); ``below``: a
        swatch (label, colour) or a list of them for values off the bar."""
        self._title, self._gradient = title, (np.asarray(colours), lo, hi)
        self._items = list(below) if isinstance(below, list) else ([below] if below else [])
        self._fit()

    def text(self) -> str:
        """What the legend says (title and labels)."""
        parts = [self._title] + [label for label, _ in self._items]
        if self._gradient is not None:
            parts += [str(self._gradient[1]), str(self._gradient[2])]
        return " | ".join(parts)

    def _fit(self) -> None:
        fm = self.fontMetrics()
        line = fm.height() + 4
        rows = len(self._items) + (2 if self._gradient is not None else 0)
        width = max([fm.horizontalAdvance(self._title)] +
                    [fm.horizontalAdvance(t) + 26 for t, _ in self._items] + [120]) + 16
        self.resize(width, 10 + line * (rows + 1))
        self.update()

    def paintEvent(self, _event) -> None:  # noqa: N802 - Qt's name
        p = _card(self)
        fm = self.fontMetrics()
        line = fm.height() + 4
        y = 6
        p.drawText(QRectF(8, y, self.width() - 16, line), LEFT, self._title)
        y += line
        if self._gradient is not None:
            colours, lo, hi = self._gradient
            grad = QLinearGradient(8, 0, self.width() - 8, 0)
            for k, c in enumerate(colours):
                grad.setColorAt(k / max(len(colours) - 1, 1), QColor(*[int(v) for v in c[:3]]))
            p.fillRect(QRectF(8, y + 2, self.width() - 16, line - 4), grad)
            y += line
            p.drawText(QRectF(8, y, self.width() - 16, line), Qt.AlignmentFlag.AlignLeft, str(lo))
            p.drawText(QRectF(8, y, self.width() - 16, line), Qt.AlignmentFlag.AlignRight, str(hi))
            y += line
        for label, colour in self._items:
            p.fillRect(QRectF(8, y + 3, 16, line - 6), QColor(colour))
            p.drawText(QRectF(30, y, self.width() - 38, line), LEFT, label)
            y += line
        p.end()
