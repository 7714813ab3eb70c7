"""A heatmap drawn for a canvas of its own (``heatmap_figure(fit=...)``, the app's docked
view): the figure is the canvas's size, every text at the points asked, the second title
line and the long labels left out where it is small, so nothing is shrunk to fit."""

from __future__ import annotations

import numpy as np
import pytest

from maizeviz.light.report.heatmap import FULL_TITLE_IN, heatmap_figure
from maizeviz.light.results.maps import TransmissionMap


def _map() -> TransmissionMap:
    rng = np.random.default_rng(1)
    x, y = np.linspace(0.0, 60.0, 13), np.linspace(0.0, 60.0, 13)
    t = rng.uniform(0.0, 0.3, (12, 12))
    return TransmissionMap(100.0, x, y, t, np.full((12, 12), 20, np.int64), float(t.mean()))


def _texts(fig) -> list:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.text import Text

    FigureCanvasAgg(fig).draw()
    return [t for t in fig.findobj(Text) if t.get_visible() and t.get_text()]


@pytest.mark.parametrize("fit", [(4.67, 1.75), (7.4, 2.9), (8.0, 6.0)])
def test_a_fitted_heatmap_keeps_its_canvas_size_and_its_points(fit):
    dpi, font = 96.0, 9.5
    fig = heatmap_figure(_map(), title="sun zenith 22.3 deg, azimuth 167 deg; level 36",
                         fit=fit, dpi=dpi, font_pt=font)
    texts = _texts(fig)
    assert fig.get_size_inches() == pytest.approx(fit)
    assert {t.get_size() for t in texts} == {font}
    title = fig.get_suptitle()
    small = min(fit) < FULL_TITLE_IN
    assert title.startswith("direct-light transmission at 100 cm") and \
        ("level 36" in title) == (not small)
    assert (fig.axes[0].get_xlabel() == "x (cm)") == small
    # every text inside the figure (constrained layout, nothing pushed off the canvas)
    width, height = fit[0] * dpi, fit[1] * dpi
    for t in texts:
        box = t.get_window_extent()
        assert box.x0 >= -1 and box.y0 >= -1 and box.x1 <= width + 1 and \
            box.y1 <= height + 1, (t.get_text(), box, width, height)
    # few ticks where small: their labels do not crowd
    ticks = [t for t in fig.axes[0].get_yticklabels() if t.get_text()]
    assert len(ticks) <= max(int(fit[1] / 0.5), 2) + 1


def test_the_default_heatmap_is_unchanged():
    fig = heatmap_figure(_map(), title="t")
    assert fig.get_size_inches()[0] == pytest.approx(8.0) and fig.dpi == 110
    assert fig.axes[0].get_xlabel() == "x (cm, across rows)"
