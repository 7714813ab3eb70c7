"""Start the desktop app: ``maizeviz`` (through the ``maizeviz.gui`` entry point) or
``python -m maizeviz_app``.

Only Qt and the light parts of maizeviz are imported before the window shows; the 3D view and
the core follow in a warm-up thread (see :mod:`maizeviz_app.main_window`).

``--screenshot PNG`` builds the canopy, computes light once, colours the leaves by light,
saves a picture of the window (canopy, heatmap and transmission plot) and quits: the way to look
at the app on a machine without a screen (under ``xvfb-run``). With ``--workspace digitize`` it
pictures the Digitize workspace instead, during a Demo session (a simulated FASTRAK).
"""

from __future__ import annotations

import importlib.util
import os
import sys
from collections.abc import Sequence

#: What the app needs beyond the core (the ``gui`` extra); checked when the entry point loads,
#: without importing them (pyvista and VTK take seconds to import).
GUI_PACKAGES = ("PySide6", "pyvista", "pyvistaqt")
_missing = [name for name in GUI_PACKAGES if importlib.util.find_spec(name) is None]
if _missing:
    raise ImportError(f"{', '.join(_missing)} not installed")


def gl_format() -> None:
    """The OpenGL format VTK needs, installed before any window exists (pyvistaqt sets the
    same when the 3D view is made, but the main window shows earlier; a window made before
    the default format is set cannot host the 3D view on some platforms)."""
    from PySide6.QtGui import QSurfaceFormat

    fmt = QSurfaceFormat()
    fmt.setRenderableType(QSurfaceFormat.RenderableType.OpenGL)
    fmt.setProfile(QSurfaceFormat.OpenGLContextProfile.CoreProfile)
    fmt.setVersion(3, 2)
    fmt.setSwapBehavior(QSurfaceFormat.SwapBehavior.DoubleBuffer)
    for setter in ("setRedBufferSize", "setGreenBufferSize", "setBlueBufferSize",
                   "setDepthBufferSize", "setAlphaBufferSize"):
        getattr(fmt, setter)(8)
    fmt.setStencilBufferSize(0)
    fmt.setSamples(0)
    QSurfaceFormat.setDefaultFormat(fmt)


def run(argv: Sequence[str] | None = None) -> int:
    from maizeviz.main_command import DEFAULT_TILE, main_parser

    # the same command line as the headless report's (maizeviz.cli.main_job)
    args = main_parser().parse_args(argv)
    os.environ.setdefault("QT_API", "pyside6")
    from PySide6.QtWidgets import QApplication

    gl_format()
    app = QApplication.instance() or QApplication([sys.argv[0]])
    app.setApplicationName("maizeviz")
    app.setOrganizationName("maizeviz")
    from maizeviz_app.main_window import MainWindow

    points = args.points
    if args.screenshot and points is None:
        from maizeviz.resources import example_points

        points = str(example_points())
    if args.screenshot:
        from maizeviz.errors import MaizevizError
        from maizeviz.io.outputs import check_run_paths

        try:                                    # before any work: a folder that is not there
            check_run_paths([("the screenshot", args.screenshot)], [("the input", points)])
        except MaizevizError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 1
    window = MainWindow(points, DEFAULT_TILE if args.tile is None else args.tile)
    if args.workspace:
        window.workspaces.show(args.workspace)
    code = {"value": 0}
    if args.screenshot:
        window.resize(*args.size)
        # nothing to save: without this the unsaved-results question waited, unanswered,
        # until the flow's 300 s timeout (and the exit code was 1)
        window.confirm_unsaved = False
        if args.workspace == "digitize":
            _digitize_screenshot_flow(app, window, args.screenshot, code)
        else:
            _screenshot_flow(app, window, args.screenshot, code)
    window.show()
    app.exec()
    return code["value"]


def _ends(app, window, path: str, code: dict, before=None):
    """A screenshot flow's two ends: ``shoot`` (grab, save, quit; ``before()`` first) and
    ``fail(message)`` (exit code 1); both close the window. A flow fails after 300 s."""
    from PySide6.QtCore import QTimer

    def shoot() -> None:
        if not window.grab().save(path):
            fail(f"{path}: the screenshot could not be written")
            return
        print(f"saved {path}")
        if before is not None:
            before()
        window.close()
        app.quit()

    def fail(msg: str) -> None:
        print(f"error: {msg}", file=sys.stderr)
        code["value"] = 1
        window.close()
        app.quit()

    QTimer.singleShot(300_000, lambda: fail("timed out"))
    return shoot, fail


def _screenshot_flow(app, window, path: str, code: dict) -> None:
    """Canopy -> light -> a frame coloured by light -> grab -> quit."""
    from PySide6.QtCore import QTimer

    state = {"lit": False}
    shoot, fail = _ends(app, window, path, code)

    def on_canopy(_label: str) -> None:
        if not state["lit"]:
            state["lit"] = True
            window.model.compute_light()

    window.canopy_shown.connect(on_canopy)
    window.light_shown.connect(lambda: QTimer.singleShot(800, shoot))
    window.failed.connect(fail)


def _digitize_screenshot_flow(app, window, path: str, code: dict, points: int = 26) -> None:
    """The Demo records ``points`` presses into a temporary file, then pauses (the presses
    that follow are refused), the leaves are meshed -> grab -> quit."""
    import tempfile

    from PySide6.QtCore import QTimer

    folder = tempfile.mkdtemp(prefix="maizeviz-screenshot-")

    def stop_demo() -> None:
        window.digitizer.stopped.disconnect(stopped)
        window.digitizer.stop("screenshot", wait=True)

    shoot, fail = _ends(app, window, path, code, before=stop_demo)

    def recorded(n: int) -> None:
        panel = window.digitizer
        if n >= points and not panel.paused:    # (two points can show in one tick)
            panel.toggle_pause()
            panel.plant.wait()
            QTimer.singleShot(1500, shoot)

    def start() -> None:
        panel = window.digitizer
        panel.out_edit.setText(f"{folder}/session.csv")
        panel.cols.setValue(5)
        panel.demo_pace = 0.1
        panel.recorded.connect(recorded)
        panel.stopped.connect(stopped)
        panel.start(demo=True)

    def stopped(why: str) -> None:
        fail(f"the demo stopped ({why})")

    window.ready.connect(start)


if __name__ == "__main__":
    sys.exit(run())
