"""File > Save view as image: the 3D view as a PNG of a chosen width, with its colour key.

VTK renders the view in tiles at an integer magnification of the view's own size
(``vtkWindowToImageFilter``: the same camera, so the picture is what is on screen, only
sharper), the picture is scaled to the width asked (its height follows the view's shape), and
the colour key over the view (a Qt widget, :class:`~maizeviz_app.viewport.Legend`) is painted
on it at the same place and scale. Each tile is a frame: on software OpenGL a 4x picture of the
K = 4 view takes 16 frames, a few seconds, during which the window waits (the user asked).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from PySide6.QtCore import QPoint, Qt
from PySide6.QtGui import QImage, QPainter
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

#: Widest picture offered, pixels (a 4x magnification of a 2000 px wide view).
MAX_WIDTH = 8000


def render_size(viewport) -> tuple[int, int]:
    """The view's size in the render window's pixels (width, height)."""
    w, h = viewport.ren_win.GetSize()
    return int(w), int(h)


def height_for(viewport, width: int) -> int:
    """The height of a picture ``width`` pixels wide with the view's shape."""
    w, h = render_size(viewport)
    return max(1, round(width * h / max(w, 1)))


def view_image(viewport, width: int | None = None, key: bool = True) -> QImage:
    """The view as an image ``width`` pixels wide (None: the view's own size), with the colour
    key painted over it when it shows (``key``)."""
    w, h = render_size(viewport)
    width = w if width is None else int(width)
    if not 16 <= width <= MAX_WIDTH:
        raise ValueError(f"image width {width} px: give 16 to {MAX_WIDTH:,}")
    scale = max(1, math.ceil(width / max(w, 1)))
    grab = vtkWindowToImageFilter()
    grab.SetInput(viewport.ren_win)
    grab.SetScale(scale)
    grab.SetInputBufferTypeToRGB()
    grab.FixBoundaryOn()
    grab.ReadFrontBufferOff()
    grab.ShouldRerenderOn()
    grab.Update()
    data = grab.GetOutput()
    gw, gh, _ = data.GetDimensions()
    pixels = vtk_to_numpy(data.GetPointData().GetScalars()).reshape(gh, gw, 3)[::-1]
    pixels = np.ascontiguousarray(pixels)
    image = QImage(pixels.data, gw, gh, 3 * gw, QImage.Format.Format_RGB888).copy()
    height = height_for(viewport, width)
    if (gw, gh) != (width, height):
        image = image.scaled(width, height, Qt.AspectRatioMode.IgnoreAspectRatio,
                             Qt.TransformationMode.SmoothTransformation)
    legend = getattr(viewport, "key", None)
    if key and legend is not None and legend.isVisible():
        painter = QPainter(image)
        painter.setRenderHint(QPainter.RenderHint.Antialiasing)
        factor = width / max(viewport.width(), 1)         # widget pixels -> picture pixels
        painter.scale(factor, factor)
        legend.render(painter, QPoint(legend.x(), legend.y()))
        painter.end()
    viewport.render()                # the window's own frame again at its own size
    return image


def save_view_image(viewport, path: str | Path, width: int | None = None) -> Path:
    """Write :func:`view_image` to ``path`` (PNG), atomically; returns the path."""
    from maizeviz.io.atomic import atomic_path

    path = Path(path)
    image = view_image(viewport, width)
    with atomic_path(path) as tmp:
        if not image.save(str(tmp)):          # PNG: the suffix, kept by atomic_path
            raise OSError(f"{path}: the image could not be written")
    return path


def ask_view_image(parent, viewport, folder: str) -> tuple[str, int] | None:
    """Ask where and how wide (the view's width by default; 2x and 4x offered; the height
    follows the view's shape): (path, width), or None if cancelled."""
    from PySide6.QtWidgets import (
        QDialog,
        QDialogButtonBox,
        QFileDialog,
        QFormLayout,
        QHBoxLayout,
        QLabel,
        QPushButton,
        QSpinBox,
    )

    w0, _ = render_size(viewport)
    dialog = QDialog(parent)
    dialog.setWindowTitle("Save view as image")
    form = QFormLayout(dialog)
    width = QSpinBox()
    width.setRange(16, MAX_WIDTH)
    width.setSuffix(" px")
    width.setValue(w0)
    width.setAccessibleName("image width")
    width.setToolTip("the picture's width; its height follows the view's shape")
    height = QLabel("")
    width.valueChanged.connect(lambda v: height.setText(f"{height_for(viewport, v)} px"))
    height.setText(f"{height_for(viewport, w0)} px")
    row = QHBoxLayout()
    row.addWidget(width, 1)
    for times in (1, 2, 4):
        button = QPushButton(f"{times}x")
        button.setToolTip(f"{times} times the view's width ({min(times * w0, MAX_WIDTH)} px)")
        button.setAccessibleName(f"{times} times the view's width")
        button.clicked.connect(lambda _c=False, t=times: width.setValue(min(t * w0, MAX_WIDTH)))
        row.addWidget(button)
    form.addRow("Width", row)
    form.addRow("Height", height)
    form.addRow(QLabel("The picture is the view as it is, with its colour key."))
    buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Save
                               | QDialogButtonBox.StandardButton.Cancel)
    buttons.accepted.connect(dialog.accept)
    buttons.rejected.connect(dialog.reject)
    form.addRow(buttons)
    if dialog.exec() != QDialog.DialogCode.Accepted:
        return None
    path, _ = QFileDialog.getSaveFileName(parent, "Save view as image",
                                          str(Path(folder) / "view.png"), "PNG (*.png)")
    if not path:
        return None
    if not path.lower().endswith(".png"):
        path += ".png"
    return path, int(width.value())
