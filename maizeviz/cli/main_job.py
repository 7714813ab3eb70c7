"""``maizeviz [FILE] [options]`` with no subcommand where no window can open: the headless
report, on the command line the app reads (:mod:`maizeviz.main_command`, argparse's). The
report is the canopy command's: the points' canopy at every level (``canopy FILE --tile NxN
--levels``), a canopy mesh as it is (``canopy FILE``); a project, a folder, a FIFO or a
missing file is one line, exit 1.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Callable, Sequence
from pathlib import Path

from maizeviz.cli.common import EXIT_FAIL, EXIT_USAGE, say
from maizeviz.main_command import DEFAULT_TILE, main_parser


def _not_a_file(path: str) -> str:
    """Why ``path`` cannot be opened as a file ("" when it can)."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return "no such file"
    except OSError as exc:
        return f"cannot be read ({exc.strerror or exc})"
    if stat.S_ISDIR(mode):
        return "is a folder, not a file"
    if stat.S_ISFIFO(mode):
        return "is a FIFO (a named pipe), not a file"
    if not stat.S_ISREG(mode):
        return "is not a regular file (a device or socket)"
    return ""


def headless_report(argv: Sequence[str], run: Callable[[list[str]], int],
                    why: str | None = "DISPLAY is not set") -> int:
    """The report given for ``maizeviz [FILE] [options]`` where no window can open.

    Parameters
    ----------
    argv : the command line after ``maizeviz`` (``--debug`` taken out)
    run : the command line's ``main`` (runs the canopy subcommand)
    why : why there is no screen, for the first line; None: the caller said why there is
        no window

    Returns
    -------
    int
        The canopy command's exit code; 1 for a file that cannot be opened; 2 for
        ``--screenshot``, which needs a window (argparse's own 2 for a bad option).
    """
    from maizeviz.io.mesh_canopy import is_mesh_path
    from maizeviz.resources import example_points

    ap = main_parser()
    args = ap.parse_args(list(argv))
    if args.screenshot:
        say(f"error: --screenshot needs the desktop app on a screen ({why or 'no window'})"
            f": run 'xvfb-run -a maizeviz {' '.join(argv)}'")
        return EXIT_USAGE
    path = args.points or str(example_points())
    on = args.points or "the bundled example"
    if why is not None:
        say(f"no screen ({why}): the headless report on {on} follows; for the window run "
            "'xvfb-run -a maizeviz --screenshot app.png' or use a desktop")
    if args.workspace:
        say(f"note: --workspace {args.workspace} is the window's; the report does not use it")
    problem = _not_a_file(path)
    if problem:
        say(f"error: {path}: {problem} (the app opens points, a canopy mesh or a project)")
        return EXIT_FAIL
    if Path(path).suffix.lower() == ".maizeviz":
        say(f"error: {path} is a project: it opens in the desktop app (without a screen: "
            f"xvfb-run -a maizeviz {path} --screenshot view.png)")
        return EXIT_FAIL
    if is_mesh_path(path):
        if args.tile is not None:
            say(f"error: --tile {args.tile}: a mesh file is traced as it is, its plants "
                "where they stand (no tiling)")
            return EXIT_USAGE
        command = ["canopy", path]
    else:
        n = DEFAULT_TILE if args.tile is None else args.tile
        command = ["canopy", path, "--tile", f"{n}x{n}", "--levels"]
    if args.points:
        say(f"note: the same as: maizeviz {' '.join(command)}")
    return run(command)
