"""The ``maizeviz`` command: headless subcommands; with none, the desktop app.

Exit codes: 0 all done; 1 nothing could be done (bad file, every leaf refused, bad request);
2 bad command-line usage; 3 done, but some leaves were skipped (listed on stderr).

The desktop app is not imported from here: it registers itself under the entry-point group
``maizeviz.gui`` (see pyproject.toml), so the core never depends on Qt, and a headless install
(without the ``gui`` extra) still runs every subcommand.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import traceback
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path

from maizeviz import __version__
from maizeviz.cli.common import EXIT_FAIL, EXIT_OK, EXIT_PARTIAL, EXIT_USAGE, error_line, say
from maizeviz.environment import switch
from maizeviz.errors import MaizevizError

__all__ = ["main", "build_parser", "EXIT_OK", "EXIT_FAIL", "EXIT_USAGE", "EXIT_PARTIAL"]

#: The subcommands, in the order ``--help`` lists them: name -> the module that defines it
#: (``NAME``, ``add_parser``), imported only when it runs or help lists every command.
COMMANDS = {"leaf": "maizeviz.cli.leaf", "canopy": "maizeviz.cli.canopy",
            "light": "maizeviz.cli.light", "sweep": "maizeviz.sweep.command",
            "record": "maizeviz.cli.record", "fastrak-sim": "maizeviz.cli.simulate",
            "synth": "maizeviz.cli.synth", "import-phenomenal": "maizeviz.cli.phenomenal",
            "convert": "maizeviz.cli.convert", "subplots": "maizeviz.cli.subplots",
            "instrument": "maizeviz.cli.instrument"}
#: Entry-point group under which the desktop app registers its ``run(argv) -> int``.
GUI_GROUP = "maizeviz.gui"
GUI_HINT = 'the desktop app is not installed: pip install "maizeviz[gui]"'


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The command line's parser: every subcommand, or only the one named ``only`` (the others'
    modules are then not imported: a run pays only for its own)."""
    parser = argparse.ArgumentParser(
        prog="maizeviz",
        description="Digitized maize plants: leaf surfaces, mesh complexity, canopies, light. "
                    "Without a subcommand, opens the desktop app.")
    parser.add_argument("--version", action="version", version=f"maizeviz {__version__}")
    parser.add_argument("--info", action="store_true",
                        help="print versions, the Embree library, the ray kernel in use and "
                             "why, and threads (for bug reports), then exit")
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, module in COMMANDS.items():
        if only is None or name == only:
            importlib.import_module(module).add_parser(sub)
    return parser


def has_screen() -> bool:
    """True where a window can open (an X server or Wayland, or macOS/Windows)."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def find_gui() -> tuple[Callable[[Sequence[str]], int] | None, str]:
    """The desktop app's ``run`` from its entry point, or None and why not (one line)."""
    from importlib.metadata import entry_points

    found = entry_points(group=GUI_GROUP)
    if not found:
        return None, GUI_HINT
    try:
        return next(iter(found)).load(), ""
    except ImportError as exc:                 # the gui extra is missing or broken
        return None, f"{GUI_HINT} ({exc})"


def _no_command(argv: list[str]) -> int:
    """No subcommand: the desktop app where there is a screen, else the headless report;
    the command line parsed first, as the app and the report both read it
    (:mod:`maizeviz.cli.main_job`)."""
    from maizeviz.cli.main_job import headless_report
    from maizeviz.main_command import main_parser

    rest = [a for a in argv if a != "--debug"]
    # a mistyped command, not a file to open: said before the app's own parser, which would
    # only see a second file (``maizeviz lihgt points.csv``: "unrecognized arguments")
    named = rest[0] if rest else None
    if named and not named.startswith("-") and not Path(named).exists():
        import difflib

        close = difflib.get_close_matches(named.lower(), list(COMMANDS), n=1, cutoff=0.6)
        if close:
            say(f"error: unknown command '{named}' (did you mean '{close[0]}'? "
                "maizeviz --help lists the commands)")
            return EXIT_USAGE
    main_parser().parse_args(rest)                     # a bad option: usage, exit 2
    gui, why = find_gui()
    if gui is None:
        say(f"note: {why}")
        return headless_report(rest, main, None)
    if has_screen():
        try:
            return gui(rest)
        except ImportError as exc:              # Qt present but unusable (a missing libxcb...)
            say(f"note: the desktop app cannot start ({exc}); the headless report follows")
            return headless_report(rest, main, None)
    return headless_report(rest, main)


def _say_warnings(message, category, filename, lineno, file=None, line=None) -> None:
    """Python warnings (maizeviz's fallbacks, a library's deprecation) as one line each."""
    say(f"warning: {message}")


def main(argv: Sequence[str] | None = None) -> int:
    tokens = list(sys.argv[1:] if argv is None else argv)
    first = next((t for t in tokens if t != "--debug"), None)
    if first == "--info":
        from maizeviz.environment import problems
        from maizeviz.info import report

        bad = problems()                            # MAIZEVIZ_* variables it cannot read
        for line in bad:
            say(f"error: {line}")
        if not bad:
            print(report())
        return EXIT_FAIL if bad else EXIT_OK
    if first not in COMMANDS and first not in ("-h", "--help", "--version"):
        return _no_command(tokens)                 # the app, with its own options
    args = build_parser(first if first in COMMANDS else None).parse_args(tokens)
    try:
        debug = args.debug or switch("MAIZEVIZ_DEBUG")
    except MaizevizError as exc:
        say(error_line(exc))
        return EXIT_FAIL
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _say_warnings
            return int(args.run(args))
    except MaizevizError as exc:
        say(error_line(exc))
        return EXIT_FAIL
    except KeyboardInterrupt:
        say("interrupted")
        return 130
    except BrokenPipeError:
        return EXIT_OK
    except Exception as exc:  # noqa: BLE001 - a bug: one line unless asked for the traceback
        if debug:
            traceback.print_exc()
        else:
            say(f"internal error: {type(exc).__name__}: {exc} (run with --debug and report it)")
        return EXIT_FAIL
