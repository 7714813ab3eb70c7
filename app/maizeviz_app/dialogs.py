"""The questions only a window can ask: which file to open or write, what to do with unsaved
work, whether to start a long computation. Each returns the answer (None or False: the user
declined); the study does the rest.
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtWidgets import QFileDialog, QInputDialog, QMessageBox, QWidget

PROJECT_FILTER = "maizeviz project (*.maizeviz)"
POINTS_FILTER = "Points (*.csv *.parquet *.pq);;All files (*)"
CANOPY_MESH_FILTER = "Canopy mesh with plant and leaf ids (*.ply *.obj);;All files (*)"
#: Units and up axis a mesh file may be written in (what the open dialog offers).
MESH_FRAMES = {"cm, z up": ("cm", "z"), "m, z up": ("m", "z"), "mm, z up": ("mm", "z"),
               "cm, y up": ("cm", "y"), "m, y up": ("m", "y"), "mm, y up": ("mm", "y")}
MESH_FILTER = ("PLY (*.ply);;VTK legacy (*.vtk);;VTK XML unstructured (*.vtu);;"
               "VTK XML polydata (*.vtp);;Wavefront OBJ (*.obj);;STL (*.stl)")
#: Exports: what -> (the dialog's title, the default file name, its filter).
EXPORTS = {"canopy": ("Export the canopy mesh", "canopy.ply", MESH_FILTER),
           "table": ("Export the transmission table", "transmission.csv", "CSV (*.csv)"),
           "measures": ("Export the canopy measures", "canopy_measures.csv", "CSV (*.csv)"),
           "heatmap": ("Export the heatmap", "heatmap.png", "PNG (*.png)"),
           "plot": ("Export transmission vs height", "transmission.png", "PNG (*.png)"),
           "steps": ("Export the day's time steps", "steps.csv", "CSV (*.csv)"),
           "leaves": ("Export the light per leaf", "leaf_light.csv", "CSV (*.csv)"),
           "plants": ("Export the light per plant", "plant_light.csv", "CSV (*.csv)"),
           "day": ("Export the day figure", "day.png", "PNG (*.png)")}


def _folder(window) -> str:
    return window.folder()


def open_file(window, what: str) -> str:
    """A points CSV (``what`` "points") or a project ("project") to open; '' if none."""
    title, filt = {"points": ("Open digitized points", POINTS_FILTER),
                   "project": ("Open project", PROJECT_FILTER)}[what]
    path, _ = QFileDialog.getOpenFileName(window, title, _folder(window), filt)
    return path


def choose_mesh(window) -> tuple[str, str, str, str | None] | None:
    """A canopy mesh (PLY or OBJ with a plant and a leaf id per face), its units and up
    axis, and its field (x0, y0, x1, y1 cm as typed, None: the mesh's extent); None if the
    user stopped."""
    path, _ = QFileDialog.getOpenFileName(window, "Open a canopy mesh", _folder(window),
                                          CANOPY_MESH_FILTER)
    if not path:
        return None
    frame, ok = QInputDialog.getItem(
        window, "Units of the mesh", "The file's coordinates are in (OpenAlea and Helios "
        "write z up, many scanners y up):", list(MESH_FRAMES), 0, False)
    if not ok:
        return None
    field, ok = QInputDialog.getText(
        window, "Field of the mesh", "The ground plot x0, y0, x1, y1 in cm, in field "
        "coordinates (it sets leaf area index, ground cover and the periodic field's tile; "
        "leave empty for the plot the file carries, as maizeviz's exports do, else the "
        "mesh's extent seen from above):")
    if not ok:
        return None
    unit, up = MESH_FRAMES[frame]
    return path, unit, up, field.strip() or None


def save_project_file(window, current: str | None) -> str:
    """Where to save the project ('' : nowhere); ``.maizeviz`` added when missing."""
    start = current or str(Path(_folder(window)) / "study.maizeviz")
    path, _ = QFileDialog.getSaveFileName(window, "Save project", start, PROJECT_FILTER)
    if path and not path.endswith(".maizeviz"):
        path += ".maizeviz"
    return path


def export_file(window, what: str) -> str:
    """Where to write an export (see :data:`EXPORTS`); the filter's extension added when the
    name has none; '' : nowhere."""
    title, default, filt = EXPORTS[what]
    path, chosen = QFileDialog.getSaveFileName(window, title,
                                               str(Path(_folder(window)) / default), filt)
    if path and "." not in Path(path).name and "(*." in chosen:
        path += chosen.split("(*", 1)[1].split(")")[0]
    return path


def ask_unsaved(parent: QWidget, project: str | None) -> QMessageBox.StandardButton:
    """Save, Discard or Cancel, about work not in a project yet."""
    name = Path(project).name if project else "this study"
    box = QMessageBox(QMessageBox.Icon.Warning, "Unsaved changes",
                      f"{name} has changes that are not in a project: an edited layout or "
                      "light results. Save them first?",
                      QMessageBox.StandardButton.Save | QMessageBox.StandardButton.Discard
                      | QMessageBox.StandardButton.Cancel, parent)
    box.setDefaultButton(QMessageBox.StandardButton.Save)
    return QMessageBox.StandardButton(box.exec())


def confirm_slow(parent: QWidget, estimate: str) -> bool:
    """Ask before starting work estimated at ``estimate`` (more than a quarter of an hour);
    it runs in the background and can be cancelled."""
    box = QMessageBox(QMessageBox.Icon.Question, "Start a long computation?",
                      f"{estimate}.\n\nIt runs in the background and can be cancelled; "
                      "a coarser level, a lower density or fewer directions or steps make "
                      "it shorter.",
                      QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.Cancel, parent)
    box.button(QMessageBox.StandardButton.Yes).setText("Start")
    box.setDefaultButton(QMessageBox.StandardButton.Cancel)
    return box.exec() == QMessageBox.StandardButton.Yes


def cache_folder() -> str:
    """Where opened projects' points files are unpacked."""
    from PySide6.QtCore import QStandardPaths

    base = QStandardPaths.writableLocation(QStandardPaths.StandardLocation.CacheLocation)
    return str(Path(base or Path.home() / ".cache" / "maizeviz") / "projects")
