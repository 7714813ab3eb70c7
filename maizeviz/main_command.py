"""The command line of ``maizeviz [FILE] [options]``, the main job without a subcommand,
parsed with argparse as the subcommands' are: the desktop app (``app/maizeviz_app/main.py``)
and the headless report given where there is no screen (:mod:`maizeviz.cli.main_job`) build
their parser here, so both take the same forms (``maizeviz --tile 1 p.csv``,
``maizeviz p.csv --tile 1`` and ``maizeviz -- p.csv`` name the same file and tiling; an
unknown option or a bad value is argparse's usage error, exit 2). Light to import (argparse
and :mod:`maizeviz.numbers`): the app parses it before its window shows.
"""

from __future__ import annotations

import argparse

from maizeviz.numbers import whole

#: The tilings the app offers (N x N copies of the digitized block).
TILES = (1, 3, 5, 7, 9)
#: The app's tiling when none is given (the paper's 81 plants).
DEFAULT_TILE = 3


def _size(text: str) -> tuple[int, int]:
    """``WxH`` in pixels, each a whole number from 200 to 10000."""
    parts = str(text).lower().split("x")
    try:
        w, h = (whole(p) for p in parts) if len(parts) == 2 else (None, None)
    except ValueError:
        w = h = None
    if w is None or h is None or not (200 <= w <= 10_000 and 200 <= h <= 10_000):
        raise argparse.ArgumentTypeError(f"'{text}' is not a window size such as 1366x768 "
                                         "(pixels, 200 to 10000 each)")
    return w, h


def _tile(text: str) -> int:
    try:
        n = whole(text)
    except ValueError:
        n = None
    if n not in TILES:
        raise argparse.ArgumentTypeError(f"'{text}' is not a tiling the app offers "
                                         f"({', '.join(map(str, TILES))})")
    return n


def main_parser() -> argparse.ArgumentParser:
    """The parser of ``maizeviz [FILE] [options]`` (no subcommand), for the app and the
    headless report alike. ``tile`` is None when not given (the app's default is
    :data:`DEFAULT_TILE`); ``size`` is ``(width, height)`` pixels."""
    ap = argparse.ArgumentParser(
        prog="maizeviz", description="The maizeviz desktop app; without a screen, the "
        "headless report on FILE (its canopy at every mesh level). Subcommands: maizeviz "
        "--help.")
    ap.add_argument("points", nargs="?", metavar="FILE",
                    help="points CSV or Parquet, .maizeviz project or canopy mesh (.ply, .obj "
                         "with plant and leaf ids, cm, z up) (default: the last one opened, "
                         "or the bundled 3x3 block)")
    ap.add_argument("--tile", type=_tile, default=None, metavar="N",
                    help=f"tiling of the digitized block, N x N, N one of "
                         f"{', '.join(map(str, TILES))} (default {DEFAULT_TILE}: the paper's "
                         "81 plants)")
    ap.add_argument("--screenshot", metavar="PNG", help="save the window and quit")
    ap.add_argument("--size", type=_size, default=(1366, 768), metavar="WxH",
                    help="window size for --screenshot (default 1366x768, a laptop screen)")
    ap.add_argument("--workspace", choices=("analyse", "digitize"),
                    help="start in this workspace (default: the one the app was closed in)")
    return ap
