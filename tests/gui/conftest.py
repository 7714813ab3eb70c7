"""GUI tests: a real window under Xvfb (pytest-xvfb starts it), driven with pytest-qt.

Panels are tested as widgets over their models on a small canopy (two synthetic plants); a few
tests drive the whole window on the bundled example.
"""

import gc
import os
import tempfile
import threading

import pytest

os.environ.setdefault("QT_API", "pyside6")
os.environ["XDG_CONFIG_HOME"] = tempfile.mkdtemp(prefix="maizeviz-settings-")
os.environ["XDG_CACHE_HOME"] = tempfile.mkdtemp(prefix="maizeviz-cache-")

TIMEOUT = 120_000


@pytest.fixture(scope="session", autouse=True)
def _gl_format():
    """The OpenGL format the app installs before its first window (as maizeviz_app.main)."""
    from maizeviz_app.main import gl_format

    gl_format()


@pytest.fixture(autouse=True)
def fresh_settings():
    """Each test starts without remembered files, geometry or docks."""
    from PySide6.QtCore import QSettings

    QSettings("maizeviz", "maizeviz").clear()
    yield


@pytest.fixture
def window(qtbot):
    """A main window (the bundled example by default), its 3D view made; closed (viewport
    and core processes included) after the test."""
    from maizeviz_app.main_window import MainWindow

    from maizeviz.resources import example_points

    made = []

    def make(points=None, tile=3, wait_ready=True, size=(1366, 740)):
        points = example_points() if points is None else points
        w = MainWindow(points if points != "last" else None, tile)
        w.confirm_unsaved = False          # tests close windows with results unsaved
        if size is not None:
            w.resize(*size)
        made.append(w)
        if wait_ready:
            with qtbot.waitSignal(w.ready, timeout=TIMEOUT):
                w.show()
        else:
            w.show()
        qtbot.waitExposed(w)
        return w

    yield make
    for w in made:
        w.close()


@pytest.fixture(scope="session")
def small_points(tmp_path_factory):
    """Two synthetic plants (one row), digitized-looking: the small canopy of panel tests."""
    from maizeviz.cli import main

    path = tmp_path_factory.mktemp("small") / "two_plants.csv"
    assert main(["synth", "--plants", "1x2", "--seed", "3", "--out", str(path)]) == 0
    return path


@pytest.fixture(scope="session")
def small_canopy(small_points):
    """The two plants at 36 triangles per leaf, tiled 1x1."""
    from maizeviz.canopy.build import build_canopy
    from maizeviz.canopy.layout import layout_for
    from maizeviz.leaf.fit import read_leaves
    from maizeviz.mesh.levels import parse_level

    found = read_leaves(small_points)
    layout = layout_for(found.leaves, (1, 1))
    return build_canopy(found.leaves, layout, parse_level("36"))


@pytest.fixture
def viewport(qtbot):
    """The 3D view alone, shown and exposed; closed after the test."""
    from maizeviz_app.viewport import Viewport

    v = Viewport()
    qtbot.addWidget(v)
    v.resize(640, 480)
    v.show()
    qtbot.waitExposed(v)
    qtbot.wait(100)
    yield v
    v.close()
    del v
    gc.collect()        # the view finalized on the GUI thread, not in a later thread's collection


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


@pytest.fixture
def make_panel(qtbot):
    """Make digitizer panels (``make_panel(viewport=None)``), each a real widget shown at a
    laptop's dock size once its port list is read; each stopped, with its port search, when
    the test ends."""
    from maizeviz_app.panels.digitizer import DigitizerPanel

    made = []

    def make(viewport=None):
        panel = DigitizerPanel(viewport)
        qtbot.addWidget(panel)
        panel.resize(460, 760)
        panel.show()
        qtbot.waitExposed(panel)
        panel.ports.wait()
        qtbot.wait(10)                  # the port list's queued signal delivered
        made.append(panel)
        return panel

    yield make
    for panel in made:
        panel.stop("test over", wait=True)
        panel.ports.stop_search()
        panel.ports.wait()
