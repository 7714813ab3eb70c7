"""What both points readers (CSV, :mod:`maizeviz.io.points`; Parquet,
:mod:`maizeviz.io.parquet`) share: the required columns, the limits on what a file may hold, the
table of points read, how text from a file is shown in a message, and which names are Parquet
files. Imported by both, importing neither.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

#: The columns a points file must have (any order, any case).
REQUIRED = ("plant", "leaf", "row", "col", "x", "y", "z")
#: Most points read from one file: 20 million is about 18,000 digitized plants of 1,100 points
#: (a 200 MB file holds about 5 million); they take 1.3 GB while reading.
MAX_POINTS = 20_000_000
#: Most lines read from one file (blank, skipped and control lines count): 50 million lines
#: take a few minutes to read.
MAX_LINES = 50_000_000
#: Largest plant or leaf id (absolute value): the largest 32-bit integer, the width the canopy
#: keeps ids in (segmenters number organs with such ids; ids are never packed together, see
#: :mod:`maizeviz.ids`).
MAX_ID = 2**31 - 1
#: Largest row or col index: a leaf has at most a few hundred cross-sections.
MAX_INDEX = 10_000


@dataclass(frozen=True)
class PointsTable:
    """All readable points of a file, one entry per CSV line.

    Attributes
    ----------
    ids : (N, 4) int64
        plant, leaf, row, col.
    xyz : (N, 3) float64, cm
        Coordinates as written (may hold NaN: the grid builder refuses those by position).
    line : (N,) int64
        1-based line number in the file, for messages.
    extra : dict[str, list[str]]
        Other columns, as text, aligned with ``ids``.
    problems : list[str]
        Lines that were skipped, with the reason.
    bad_leaves : dict[(plant, leaf), list[str]]
        Leaves with an unreadable coordinate; they are refused by the grid builder.
    source : str
        Where the table came from (file name), for messages.
    """

    ids: np.ndarray
    xyz: np.ndarray
    line: np.ndarray
    extra: dict = field(default_factory=dict)
    problems: list = field(default_factory=list)
    bad_leaves: dict = field(default_factory=dict)
    source: str = "<memory>"

    def __len__(self) -> int:
        return len(self.line)


def shown(text: str, limit: int = 30) -> str:
    """Text from a file as it may appear in a one-line message: stripped, shortened, and
    with line ends and other control characters written as escapes."""
    text = text.strip()
    cut = text[:limit]
    if not cut.isprintable():
        cut = "".join(c if c.isprintable() else repr(c)[1:-1] for c in cut)
    return cut + ("..." if len(text) > limit else "")


#: Names of points files written as Parquet.
PARQUET_SUFFIXES = (".parquet", ".pq")


def is_parquet_name(path: str | Path) -> bool:
    """Whether a points file to write at ``path`` is a Parquet file (by its name)."""
    return Path(path).suffix.lower() in PARQUET_SUFFIXES
