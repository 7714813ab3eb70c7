"""Start the desktop app: ``maizeviz`` (through the ``maizeviz.gui`` entry point) or
``python -m maizeviz_app``.

``--screenshot PNG`` builds the canopy, computes light once, saves a picture of the window and
quits: the way to look at the app on a machine without a screen (under ``xvfb-run``).
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import sys
from collections.abc import Sequence

#: What the app needs beyond the core (the ``gui`` extra); checked when the entry point loads,
#: without importing them (pyvista and VTK take seconds to import).
GUI_PACKAGES = ("PySide6", "pyvista", "pyvistaqt", "superqt")
_missing = [name for name in GUI_PACKAGES if importlib.util.find_spec(name) is None]
if _missing:
    raise ImportError(f"{', '.join(_missing)} not installed")


def run(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="maizeviz", description="The maizeviz desktop app.")
    ap.add_argument("points", nargs="?", help="points CSV (default: the bundled 3x3 block)")
    ap.add_argument("--tile", type=int, default=3, choices=(1, 3, 5))
    ap.add_argument("--screenshot", metavar="PNG", help="save the window and quit")
    args = ap.parse_args(argv)
    os.environ.setdefault("QT_API", "pyside6")
    from maizeviz.resources import example_points
    from maizeviz_app.main_window import MainWindow
    from PySide6.QtCore import QTimer
    from PySide6.QtWidgets import QApplication

    app = QApplication.instance() or QApplication([sys.argv[0]])
    app.setApplicationName("maizeviz")
    window = MainWindow(args.points or example_points(), args.tile)
    window.show()
    code = {"value": 0}
    if args.screenshot:
        def shoot() -> None:
            window.grab().save(args.screenshot)
            print(f"saved {args.screenshot}")
            window.close()
            app.quit()

        def fail(msg: str) -> None:
            print(f"error: {msg}", file=sys.stderr)
            code["value"] = 1
            window.close()
            app.quit()

        window.canopy_shown.connect(lambda _: window.compute_light())
        window.light_shown.connect(lambda: QTimer.singleShot(500, shoot))
        window.failed.connect(fail)
        QTimer.singleShot(180_000, lambda: fail("timed out"))
    app.exec()
    return code["value"]


if __name__ == "__main__":
    sys.exit(run())
