"""File > Save view as image (a PNG of a chosen width with its colour key) and View > Camera
presets (top, front, side, iso, reset)."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtGui import QImage
from test_light_modes import compute, shown, small_light


def _array(image: QImage) -> np.ndarray:
    image = image.convertToFormat(QImage.Format.Format_RGB888)
    w, h = image.width(), image.height()
    raw = np.frombuffer(image.constBits(), np.uint8).reshape(h, image.bytesPerLine())
    return raw[:, :3 * w].reshape(h, w, 3).astype(int)


def _direction(view) -> np.ndarray:
    d = np.array(view.camera.focal_point) - np.array(view.camera.position)
    return d / np.linalg.norm(d)


def test_camera_presets_look_where_they_say_and_reset_goes_back(window, qtbot, small_points):
    w = shown(qtbot, window(small_points, tile=1))
    view = w.viewport
    start = (np.array(view.camera.position), np.array(view.camera.focal_point))
    texts = {k: a.shortcut().toString() for k, a in w.menu_actions.items()}
    assert [texts[f"camera_{n}"] for n in ("top", "front", "side", "iso", "reset")] == \
        ["Ctrl+1", "Ctrl+2", "Ctrl+3", "Ctrl+4", "Ctrl+0"]
    want = {"top": (0, 0, -1), "front": (0, 1, 0), "side": (1, 0, 0),
            "iso": (1 / 2, 1 / 2, -np.sqrt(0.5))}
    bounds = np.array(view.canopy_mesh.bounds).reshape(3, 2)
    for name, direction in want.items():
        w.menu_actions[f"camera_{name}"].trigger()
        np.testing.assert_allclose(_direction(view), direction, atol=1e-6)
        # framed: the camera looks at the canopy's middle
        assert np.all(np.abs(np.array(view.camera.focal_point) - bounds.mean(axis=1)) < 1.0)
    w.menu_actions["camera_reset"].trigger()
    np.testing.assert_allclose(view.camera.position, start[0], rtol=1e-6)
    np.testing.assert_allclose(view.camera.focal_point, start[1], rtol=1e-6)
    view.camera_preset("along")                       # the earlier names still work
    np.testing.assert_allclose(_direction(view), want["front"], atol=1e-6)


def test_the_view_saved_as_an_image_is_the_view_with_its_colour_key(window, qtbot,
                                                                    small_points, tmp_path):
    from maizeviz_app.colour import colour_table
    from maizeviz_app.snapshot import render_size

    w = shown(qtbot, window(small_points, tile=1))
    small_light(w.light_panel, "sky")
    compute(qtbot, w)
    view = w.viewport
    assert view.key.isVisible() and view.light_variant == "values"
    qtbot.wait(300)
    on_screen = _array(view.grabFramebuffer())
    rw, rh = render_size(view)
    one = tmp_path / "view.png"
    with qtbot.waitSignal(w.saved, timeout=30_000):
        w.view_link.save_image(one)
    image = _array(QImage(str(one)))
    assert image.shape[:2] == (rh, rw) == on_screen.shape[:2]
    # the 3D part is what the screen shows
    key = view.key.geometry()
    outside = np.ones(image.shape[:2], bool)
    outside[:key.bottom() + 2, :key.right() + 2] = False
    assert np.abs(image - on_screen)[outside].mean() < 2.0
    # the colour key is painted where it stands: the middle of its bar is the map's middle
    line = view.key.fontMetrics().height() + 4
    bar = image[key.y() + 6 + line + line // 2, key.x() + 8: key.x() + key.width() - 8]
    table = colour_table(w.model.colour.view.cmap)
    mid = bar[len(bar) // 2]
    assert np.abs(mid - table[128].astype(int)).max() < 25
    assert np.abs(bar[2] - table[0].astype(int)).max() < 25
    # twice as wide: the same picture, sharper
    two = tmp_path / "view2x.png"
    w.view_link.save_image(two, 2 * rw)
    big = _array(QImage(str(two)))
    assert big.shape[:2] == (2 * rh, 2 * rw)
    halved = big.reshape(rh, 2, rw, 2, 3).mean(axis=(1, 3))
    assert np.abs(halved - image)[outside].mean() < 12.0
    # a width it cannot make: said, nothing written
    w.view_link.save_image(tmp_path / "tiny.png", 5)
    assert not (tmp_path / "tiny.png").exists()
    assert "image width 5 px" in w.messages.toPlainText()


@pytest.mark.parametrize("width", [640, 1000])
def test_a_chosen_width_keeps_the_views_shape(window, qtbot, small_points, tmp_path, width):
    from maizeviz_app.snapshot import height_for

    w = shown(qtbot, window(small_points, tile=1))
    path = tmp_path / "v.png"
    w.view_link.save_image(path, width)
    image = QImage(str(path))
    assert (image.width(), image.height()) == (width, height_for(w.viewport, width))


def test_a_figure_opens_in_a_zoomable_window_of_its_own(window, qtbot, small_points, tmp_path):
    """Issue 37: figures readable at laptop size: a double-click on the heatmap or the
    transmission plot opens it at its own pixels (the dock shows it scaled down), zoomable
    by buttons and keys, and saves it as a PNG."""
    from maizeviz_app.panels.image_view import ImageView
    from PySide6.QtCore import Qt

    w = shown(qtbot, window(small_points, tile=1))
    small_light(w.light_panel, "sun")
    compute(qtbot, w)
    view = next(v for v in w.findChildren(ImageView) if "transmission" in v.window_title)
    qtbot.waitUntil(lambda: view.image() is not None, timeout=120_000)
    assert view.pixmap().width() <= view.image().width()     # the dock: scaled to fit
    qtbot.mouseDClick(view, Qt.MouseButton.LeftButton)
    fig = view.figure_window
    assert fig is not None and fig.isVisible()
    assert fig.picture.pixmap().size() == view.image().size()  # its own pixels at 100 %
    fig.set_zoom(fig.zoom * 1.25)
    assert fig.picture.pixmap().width() == round(view.image().width() * 1.25) or \
        abs(fig.picture.pixmap().width() - view.image().width() * 1.25) <= 1
    assert fig.zoom_label.text() == "125%"
    out = tmp_path / "plot.png"
    assert fig.save(out)
    assert QImage(str(out)).size() == view.image().size()
    fig.close()
