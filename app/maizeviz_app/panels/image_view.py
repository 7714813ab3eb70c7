"""A picture scaled to fit its widget, keeping its aspect: the light panel's figures (drawn
elsewhere, in workers, as RGBA arrays). A double-click opens it in a window of its own
(:class:`FigureWindow`), at its own pixels and zoomable (Ctrl+wheel, Ctrl++ / Ctrl+-,
Ctrl+0 for its own size), where a laptop's dock shows it too small to read; *Save image...*
there writes it as a PNG."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QSize, Qt, QTimer, Signal
from PySide6.QtGui import QImage, QKeySequence, QPixmap, QShortcut
from PySide6.QtWidgets import (
    QDialog,
    QFileDialog,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QScrollArea,
    QSizePolicy,
    QVBoxLayout,
)

#: Zoom steps of a figure window (Ctrl++ / Ctrl+-), and its limits.
ZOOM_STEP = 1.25
ZOOM_LIMITS = (0.25, 8.0)


#: Quiet time (ms) after the last resize before a view says its new canvas.
RESIZE_SETTLE_MS = 250


class ImageView(QLabel):
    """A picture scaled to fit the widget, keeping its aspect (figures drawn elsewhere).

    ``canvas_resized(width, height, dpi)``: the view's size in device pixels and its dpi
    (logical dpi times the device pixel ratio), said once a resize settles, so a figure can
    be drawn for it: at the view's own pixels its texts keep their size in points."""

    canvas_resized = Signal(int, int, float)

    def __init__(self, placeholder: str = "", parent=None):
        super().__init__(placeholder, parent)
        self._settle = QTimer(self)
        self._settle.setSingleShot(True)
        self._settle.setInterval(RESIZE_SETTLE_MS)
        self._settle.timeout.connect(self._say_canvas)
        self._placeholder = placeholder
        self._image: QImage | None = None
        self.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.setMinimumSize(160, 120)
        self.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Ignored)
        self.setStyleSheet("background: white; color: #666;")
        self.setToolTip("double-click: the figure in a window of its own, zoomable")
        self.window_title = placeholder or "figure"
        self.figure_window: FigureWindow | None = None

    def mouseDoubleClickEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().mouseDoubleClickEvent(event)
        self.open_window()

    def open_window(self) -> FigureWindow | None:
        """The picture in a window of its own (None while there is none)."""
        if self._image is None:
            return None
        if self.figure_window is not None:
            self.figure_window.close()
        self.figure_window = FigureWindow(self._image, self.window_title, self.window())
        self.figure_window.show()
        return self.figure_window

    def set_rgba(self, rgba: np.ndarray | None) -> None:
        if rgba is None:
            self._image = None
            self.clear()
            self.setText(self._placeholder)         # what will appear here
            return
        h, w = rgba.shape[:2]
        self._image = QImage(np.ascontiguousarray(rgba).data, w, h, 4 * w,
                             QImage.Format.Format_RGBA8888).copy()
        self._rescale()

    def image(self) -> QImage | None:
        return self._image

    def resizeEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        self._rescale()
        self._settle.start()

    def canvas(self) -> tuple[int, int, float]:
        """(width, height) in device pixels and the dpi a figure drawn for this view takes."""
        ratio = self.devicePixelRatioF()
        return (round(self.width() * ratio), round(self.height() * ratio),
                float(self.logicalDpiY()) * ratio)

    def _say_canvas(self) -> None:
        if self.isVisible() and self.width() > 1 and self.height() > 1:
            self.canvas_resized.emit(*self.canvas())

    def _rescale(self) -> None:
        if self._image is None:
            return
        ratio = self.devicePixelRatioF()            # a figure drawn for device pixels
        pixmap = QPixmap.fromImage(self._image).scaled(
            self.size() * ratio, Qt.AspectRatioMode.KeepAspectRatio,
            Qt.TransformationMode.SmoothTransformation)
        pixmap.setDevicePixelRatio(ratio)
        self.setPixmap(pixmap)

    def sizeHint(self) -> QSize:  # noqa: N802
        return QSize(360, 200)


class FigureWindow(QDialog):
    """A figure at its own pixels, zoomable, with a button that saves it (a non-modal
    window: the main window goes on working)."""

    def __init__(self, image: QImage, title: str, parent=None):
        super().__init__(parent)
        self.setWindowTitle(title)
        self.image = image
        self.zoom = 1.0
        self.picture = QLabel()
        self.picture.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.picture.setAccessibleName("figure")
        scroll = QScrollArea()
        scroll.setWidget(self.picture)
        scroll.setWidgetResizable(True)
        self.zoom_label = QLabel()
        buttons = QHBoxLayout()
        steps = (("−", "zoom out (Ctrl+-)", 1 / ZOOM_STEP),
                 ("100 %", "the figure's own size (Ctrl+0)", 0.0),
                 ("+", "zoom in (Ctrl++)", ZOOM_STEP))
        for text, tip, factor in steps:
            b = QPushButton(text)
            b.setToolTip(tip)
            b.setAccessibleName(tip.split(" (")[0])
            b.clicked.connect(lambda _=False, f=factor: self.set_zoom(self.zoom * f if f else 1.0))
            buttons.addWidget(b)
        buttons.addWidget(self.zoom_label)
        buttons.addStretch(1)
        save = QPushButton("Save image…")
        save.setToolTip("write the figure as a PNG")
        save.clicked.connect(self.choose_save)
        buttons.addWidget(save)
        lay = QVBoxLayout(self)
        lay.addWidget(scroll, 1)
        lay.addLayout(buttons)
        for keys, factor in ((QKeySequence.StandardKey.ZoomIn, ZOOM_STEP),
                             (QKeySequence.StandardKey.ZoomOut, 1 / ZOOM_STEP)):
            QShortcut(QKeySequence(keys), self, lambda f=factor: self.set_zoom(self.zoom * f))
        QShortcut(QKeySequence("Ctrl+0"), self, lambda: self.set_zoom(1.0))
        self.set_zoom(1.0)
        screen = self.screen().availableGeometry() if self.screen() else None
        w, h = image.width() + 40, image.height() + 80
        if screen is not None:
            w, h = min(w, int(screen.width() * 0.9)), min(h, int(screen.height() * 0.9))
        self.resize(w, h)

    def set_zoom(self, zoom: float) -> None:
        """Show the figure ``zoom`` times its own size (within :data:`ZOOM_LIMITS`)."""
        self.zoom = min(max(zoom, ZOOM_LIMITS[0]), ZOOM_LIMITS[1])
        size = self.image.size() * self.zoom
        self.picture.setPixmap(QPixmap.fromImage(self.image).scaled(
            size, Qt.AspectRatioMode.KeepAspectRatio, Qt.TransformationMode.SmoothTransformation))
        self.zoom_label.setText(f"{self.zoom:.0%}")

    def wheelEvent(self, event) -> None:  # noqa: N802 - Qt's name
        if event.modifiers() & Qt.KeyboardModifier.ControlModifier:
            self.set_zoom(self.zoom * (ZOOM_STEP if event.angleDelta().y() > 0
                                       else 1 / ZOOM_STEP))
            event.accept()
        else:
            super().wheelEvent(event)

    def save(self, path: str) -> bool:
        """Write the figure (its own pixels) as a PNG (``.png`` added when missing)."""
        path = str(path) if str(path).lower().endswith(".png") else f"{path}.png"
        return self.image.save(path)

    def choose_save(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Save the figure", "figure.png",
                                              "PNG (*.png)")
        if path:
            self.save(path)
