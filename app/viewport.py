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
stalks) and ``light`` (2 direct, 1 second class, 0 none, -1 not traced; -2 for stalks).
Colouring switches the mapper's array and lookup table; nothing is rebuilt. The mesh is made
by :func:`canopy_polydata`, which worker threads call, so the GUI thread only swaps it in.

Touch the widget from the GUI thread only.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv
from PySide6.QtCore import Signal
from pyvistaqt import QtInteractor

from maizeviz_app.options import CAMERAS, COLOURINGS, LIGHT_CLASSES, NOT_TRACED, STALK

_PLANT_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
                  "#7f7f7f", "#bcbd22", "#17becf")


def canopy_polydata(canopy) -> pv.PolyData:
    """One mesh of a :class:`~maizeviz.canopy.scene.Canopy`'s leaves and stalks (float32
    vertices, cm) with the cell data listed in the module docstring. Safe off the GUI thread."""
    nv, nf = len(canopy.vertices), len(canopy.faces)
    points = np.empty((nv + len(canopy.stalk_vertices), 3), np.float32)
    points[:nv] = canopy.vertices
    points[nv:] = canopy.stalk_vertices
    faces = np.empty((nf + len(canopy.stalk_faces), 3), np.int64)
    faces[:nf] = canopy.faces
    faces[nf:] = canopy.stalk_faces + nv
    poly = pv.PolyData.from_regular_faces(points, faces)
    n_stalk = len(canopy.stalk_faces)
    per_stalk = n_stalk // max(canopy.n_plants, 1)
    stalk_inst = np.repeat(np.arange(canopy.n_plants, dtype=np.int32), per_stalk)
    plant_of_inst = np.array([p.plant for p in canopy.layout.placements], np.int32)
    poly.cell_data["plant"] = np.concatenate([canopy.face_plant, plant_of_inst[stalk_inst]])
    poly.cell_data["instance"] = np.concatenate([canopy.face_instance, stalk_inst]) + 1
    poly.cell_data["leaf"] = np.concatenate([canopy.face_leaf, np.zeros(n_stalk, np.int32)])
    light = np.full(nf + n_stalk, NOT_TRACED, np.int8)
    light[nf:] = STALK
    poly.cell_data["light"] = light
    poly.field_data["leaf_triangles"] = np.array([nf])
    return poly


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

    def __init__(self, parent=None):
        super().__init__(parent, auto_update=False, multi_samples=0)
        self.setMinimumSize(320, 200)
        self.render_count = 0
        self.ren_win.AddObserver("EndEvent", self._on_frame)
        self.set_background("white", top="lightskyblue")
        self.add_axes(line_width=2, labels_off=False)
        self.canopy_mesh: pv.PolyData | None = None
        self.colouring = "leaf"
        self._canopy_actor = None
        self._scalar_bar = None
        self._ground_bounds = None
        self._framed = False
        self._digitizing_frame = None

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
        self.rendered.emit(self.render_count)

    # ------------------------------------------------------------------ canopy
    def show_canopy(self, canopy, mesh: pv.PolyData | None = None) -> None:
        """Show a canopy (its mesh prepared by :func:`canopy_polydata` when given); the camera
        frames the first canopy and then stays where the user put it."""
        poly = mesh if mesh is not None else canopy_polydata(canopy)
        self.canopy_mesh = poly
        self._clear_digitizing()
        if self._canopy_actor is None:
            self._canopy_actor = self.add_mesh(poly, name="canopy", render=False,
                                               show_scalar_bar=False, smooth_shading=False,
                                               scalars="leaf")
        else:
            self._canopy_actor.mapper.SetInputData(poly)
        self._canopy_actor.SetVisibility(True)
        self._set_ground(canopy.layout)
        if self.colouring == "light" and not self.has_light():
            self.colouring = "leaf"
        self._apply_colouring()
        if not self._framed:
            self.camera_preset("perspective")
            self._framed = True
        self.render()

    def has_light(self) -> bool:
        if self.canopy_mesh is None:
            return False
        return bool(np.any(self.canopy_mesh.cell_data["light"] >= 0))

    def set_light(self, classes: np.ndarray | None) -> None:
        """Light class of every leaf triangle (F,) (see ``maizeviz.light.leaf_light.
        triangle_light``), or None to forget it; the view follows if coloured by light."""
        if self.canopy_mesh is None:
            return
        light = self.canopy_mesh.cell_data["light"]
        nf = int(self.canopy_mesh.field_data["leaf_triangles"][0])
        if classes is None:
            light[:nf] = NOT_TRACED
        else:
            if len(classes) != nf:
                raise ValueError(f"{len(classes)} light classes for {nf} leaf triangles")
            light[:nf] = classes
        self.canopy_mesh.cell_data["light"] = light          # marks the array modified
        if self.colouring == "light":
            self._apply_colouring()
            self.render()

    def colour_by(self, what: str) -> bool:
        """Colour the canopy by ``plant``, ``leaf`` or ``light``; False (and nothing changes)
        for light when no light result belongs to this canopy."""
        if what not in COLOURINGS:
            raise ValueError(f"unknown colouring {what}")
        if what == "light" and not self.has_light():
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
        if what == "light":
            lut = _categorical(LIGHT_CLASSES)
            lo, hi = min(LIGHT_CLASSES), max(LIGHT_CLASSES)
            title = "light (paper's hit classes)"
        elif what == "plant":
            ids = np.unique(cells["plant"])
            lut = _categorical({int(p): (f"plant {p}", _PLANT_COLOURS[k % len(_PLANT_COLOURS)])
                                for k, p in enumerate(ids)})
            lo, hi = float(ids.min()), float(ids.max())
            title = "digitized plant"
        else:
            hi = float(max(cells["leaf"].max(), 1))
            lut = pv.LookupTable(cmap="summer", n_values=max(int(hi), 2))
            lut.SetBelowRangeColor(*pv.Color(LIGHT_CLASSES[STALK][1]).float_rgb, 1.0)
            lut.UseBelowRangeColorOn()
            lo = 1.0
            title = "leaf rank"
        lut.SetTableRange(lo, hi)
        mapper.SetLookupTable(lut)
        mapper.SetScalarModeToUseCellFieldData()
        mapper.SelectColorArray(what)
        mapper.SetScalarRange(lo, hi)
        mapper.SetUseLookupTableScalarRange(True)
        mapper.ScalarVisibilityOn()
        self._set_scalar_bar(lut, title, categorical=what != "leaf")

    def _set_scalar_bar(self, lut, title: str, categorical: bool) -> None:
        from vtkmodules.vtkRenderingAnnotation import vtkScalarBarActor

        bar = self._scalar_bar
        if bar is None:
            bar = vtkScalarBarActor()
            bar.SetOrientationToVertical()
            bar.SetPosition(0.015, 0.3)
            bar.SetWidth(0.09)
            bar.SetHeight(0.62)
            bar.SetMaximumWidthInPixels(140)
            bar.SetBarRatio(0.22)
            bar.SetUnconstrainedFontSize(True)
            for prop in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty(),
                         bar.GetAnnotationTextProperty()):
                prop.SetColor(0.1, 0.1, 0.1)
                prop.SetFontSize(11)
                prop.ShadowOff()
                prop.ItalicOff()
                prop.BoldOff()
            self.renderer.AddViewProp(bar)
            self._scalar_bar = bar
        bar.SetLookupTable(lut)
        bar.SetTitle(title)
        # annotations (categories) sit opposite the tick labels: both on the right
        if categorical:
            bar.SetTextPositionToPrecedeScalarBar()
        else:
            bar.SetTextPositionToSucceedScalarBar()
        bar.SetDrawAnnotations(categorical)
        bar.SetNumberOfLabels(0 if categorical else 5)
        bar.SetLabelFormat("%.0f")
        bar.SetVisibility(True)

    # ------------------------------------------------------------------ ground
    def _set_ground(self, layout) -> None:
        bounds = tuple(round(v, 6) for v in layout.bounds) + (layout.row_spacing,
                                                              layout.plant_spacing)
        if bounds == self._ground_bounds:
            return
        self._ground_bounds = bounds
        x0, y0, x1, y1, rs, ps = bounds
        ground = pv.Plane(center=((x0 + x1) / 2, (y0 + y1) / 2, -0.05), i_size=x1 - x0,
                          j_size=y1 - y0)
        self.add_mesh(ground, name="ground", color="#d8c9a3", render=False, pickable=False)
        xs = _ticks(x0, x1, rs)
        ys = _ticks(y0, y1, ps)
        segs = [((x, y0, 0.0), (x, y1, 0.0)) for x in xs] + \
               [((x0, y, 0.0), (x1, y, 0.0)) for y in ys]
        pts = np.array(segs, np.float32).reshape(-1, 3)
        lines = np.column_stack([np.full(len(segs), 2), np.arange(0, 2 * len(segs), 2),
                                 np.arange(1, 2 * len(segs), 2)]).ravel()
        self.add_mesh(pv.PolyData(pts, lines=lines), name="grid", color="#8a7a55",
                      line_width=1, render=False, pickable=False)
        self._set_labels(x0, y0, x1, y1, xs, ys)

    def _set_labels(self, x0, y0, x1, y1, xs, ys) -> None:
        from vtkmodules.vtkRenderingCore import vtkBillboardTextActor3D

        for name in [n for n in self.actors if str(n).startswith("label")]:
            self.remove_actor(name, render=False)
        step_x = max(1, int(np.ceil(len(xs) / 8)))
        step_y = max(1, int(np.ceil(len(ys) / 8)))
        off = 0.04 * max(x1 - x0, y1 - y0)
        items = [(f"{x:.0f}", (x, y0 - off, 0.0)) for x in xs[::step_x]]
        items += [(f"{y:.0f}", (x0 - off, y, 0.0)) for y in ys[::step_y]]
        items += [("x cm (across rows)", ((x0 + x1) / 2, y0 - 2.6 * off, 0.0)),
                  ("y cm (along rows)", (x0 - 2.6 * off, (y0 + y1) / 2, 0.0))]
        for k, (text, pos) in enumerate(items):
            actor = vtkBillboardTextActor3D()
            actor.SetInput(text)
            actor.SetPosition(*pos)
            prop = actor.GetTextProperty()
            prop.SetFontSize(12)
            prop.SetColor(0.15, 0.15, 0.15)
            prop.SetJustificationToCentered()
            prop.SetVerticalJustificationToCentered()
            self.add_actor(actor, name=f"label{k}", render=False, pickable=False)

    # ------------------------------------------------------------------ camera
    def camera_preset(self, name: str) -> None:
        """``top``, ``along`` (looking along the rows, +y), ``across`` (along +x) or
        ``perspective``; frames the canopy."""
        if name not in CAMERAS:
            raise ValueError(f"unknown camera preset {name}")
        cam = self.camera
        if name == "top":
            self.view_xy(render=False)
        elif name == "along":
            self.view_xz(render=False)
        elif name == "across":
            self.view_yz(render=False)
        else:
            self.view_isometric(render=False)
        cam.SetParallelProjection(False)
        self.reset_camera(render=False)
        if name == "perspective":
            cam.Zoom(1.25)
        self.render()

    # ------------------------------------------------------------------ digitizing
    def hide_canopy(self) -> None:
        """Make room for a digitizing session (the canopy comes back with
        :meth:`restore_canopy` or the next :meth:`show_canopy`)."""
        for actor in (self._canopy_actor,):
            if actor is not None:
                actor.SetVisibility(False)
        if self._scalar_bar is not None:
            self._scalar_bar.SetVisibility(False)
        for name in ("ground", "grid") + tuple(n for n in self.actors
                                               if str(n).startswith("label")):
            if name in self.actors:
                self.actors[name].SetVisibility(False)
        self._digitizing_frame = None
        self.render()

    def restore_canopy(self) -> None:
        """The canopy back after a digitizing session (the leaf surfaces go)."""
        self._clear_digitizing()
        if self._canopy_actor is not None:
            self._canopy_actor.SetVisibility(True)
        if self._scalar_bar is not None:
            self._scalar_bar.SetVisibility(True)
        for name in ("ground", "grid") + tuple(n for n in self.actors
                                               if str(n).startswith("label")):
            if name in self.actors:
                self.actors[name].SetVisibility(True)
        if self._canopy_actor is not None:
            self.camera_preset("perspective")
        self.render()

    def _clear_digitizing(self) -> None:
        for name in ("leafsurf", "digitized"):
            if name in self.actors:
                self.remove_actor(name, render=False)

    def show_leaf_surfaces(self, meshes, points) -> None:
        """The plant being digitized: leaf meshes (``LeafMesh`` list) as one surface, and the
        digitized points (N, 3) cm, small and semi-transparent over it. The camera reframes
        when the points leave the framed region (a new plant)."""
        if meshes:
            verts = np.concatenate([m.points for m in meshes]).astype(np.float32)
            offs = np.cumsum([0] + [len(m.points) for m in meshes[:-1]])
            faces = np.concatenate([m.faces.astype(np.int64) + o for m, o in zip(meshes, offs)])
            self.add_mesh(pv.PolyData.from_regular_faces(verts, faces), name="leafsurf",
                          color="yellowgreen", show_edges=True, edge_color="darkgreen",
                          render=False)
        elif "leafsurf" in self.actors:
            self.remove_actor("leafsurf", render=False)
        pts = np.asarray(points, np.float32).reshape(-1, 3)
        if len(pts):
            self.add_mesh(pv.PolyData(pts), name="digitized", color="red", opacity=0.55,
                          render_points_as_spheres=True, point_size=5, render=False)
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            frame = self._digitizing_frame
            if frame is None or np.any(lo < frame[0]) or np.any(hi > frame[1]):
                pad = np.maximum(0.3 * (hi - lo), 10.0)
                self._digitizing_frame = (lo - pad, hi + pad)
                b = np.column_stack(self._digitizing_frame).ravel()
                self.reset_camera(render=False, bounds=tuple(float(v) for v in b))
        self.render()

    def close(self) -> None:
        try:
            self.ren_win.RemoveObservers("EndEvent")
        except AttributeError:
            pass
        super().close()


def _ticks(lo: float, hi: float, step: float) -> np.ndarray:
    """Grid positions from ``lo`` to ``hi`` every ``step`` (both ends included)."""
    n = int(np.floor((hi - lo) / step + 1e-9))
    xs = lo + step * np.arange(n + 1)
    if hi - xs[-1] > 1e-6 * step:
        xs = np.append(xs, hi)
    return xs
