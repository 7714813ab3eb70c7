"""GUI tests: a real window under Xvfb (pytest-xvfb starts it), driven with pytest-qt."""

import os
import tempfile
import threading

import pytest

os.environ.setdefault("QT_API", "pyside6")
os.environ["XDG_CONFIG_HOME"] = tempfile.mkdtemp(prefix="maizeviz-settings-")


@pytest.fixture
def window(qtbot):
    """A main window on the bundled example; closed (viewport included) after the test."""
    from maizeviz.resources import example_points
    from maizeviz_app.main_window import MainWindow

    made = []

    def make(points=None, tile=3):
        points = points or example_points()
        w = MainWindow(points, tile)
        w.show()
        qtbot.waitExposed(w)
        made.append(w)
        return w

    yield make
    for w in made:
        w.close()


@pytest.fixture(autouse=True)
def no_leftover_threads(qtbot):
    """Fail a test that leaves a worker thread running (leftovers crash later tests)."""
    before = {t.ident for t in threading.enumerate()}
    yield
    from PySide6.QtCore import QThreadPool
    pool = QThreadPool.globalInstance()
    pool.waitForDone(10_000)
    assert pool.activeThreadCount() == 0, "a worker is still running after the test"
    extra = [t for t in threading.enumerate() if t.ident not in before and t.is_alive()
             and not t.daemon]
    assert not extra, f"threads left running: {extra}"


@pytest.fixture
def two_plants(tmp_path):
    """A points file of a digitized block of two plants in one row (fast to build)."""
    from maizeviz.io.points import write_points
    from maizeviz.leaf.synth import block_grids

    path = tmp_path / "two_plants.csv"
    write_points(path, block_grids(1, 2, seed=3))
    return path
