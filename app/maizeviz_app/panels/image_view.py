"""A picture scaled to fit its widget, keeping its aspect: the light panel's figures (drawn
elsewhere, in workers, as RGBA arrays)."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QSize, Qt
from PySide6.QtGui import QImage, QPixmap
from PySide6.QtWidgets import QLabel, QSizePolicy


class ImageView(QLabel):
    """A picture scaled to fit the widget, keeping its aspect (figures drawn elsewhere)."""

    def __init__(self, placeholder: str = "", parent=None):
        super().__init__(placeholder, parent)
        self._placeholder = placeholder
        self._image: QImage | None = None
        self.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.setMinimumSize(160, 120)
        self.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Ignored)
        self.setStyleSheet("background: white; color: #666;")

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

    def _rescale(self) -> None:
        if self._image is None:
            return
        self.setPixmap(QPixmap.fromImage(self._image).scaled(
            self.size(), Qt.AspectRatioMode.KeepAspectRatio,
            Qt.TransformationMode.SmoothTransformation))

    def sizeHint(self) -> QSize:  # noqa: N802
        return QSize(360, 200)
