"""Numbers written as text, read strictly: every file and option reads them here.

Python's ``float`` and ``int`` (and numpy's conversion of text, which calls them) read forms no
data file or command line means as a number: ``1_000`` (underscores between digits, Python's
own literal syntax), ``3_4.0``, and digits of other scripts (full-width ``１２``). A points
file line ``1,1,0,0,1_000,2,3`` would give a point 10 m away instead of the clear error a
typing slip deserves. :func:`number` and :func:`whole` take only ASCII digits with an optional
sign, decimal point and exponent (and ``inf``, ``nan``, which the callers refuse with their own
messages: "y is nan"); whitespace around is allowed.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from typing import Any

#: A number as a file or a command line writes it.
NUMBER = re.compile(r"\s*[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf(?:inity)?|nan)\s*",
                    re.ASCII | re.IGNORECASE)
#: A whole number: digits with an optional sign.
WHOLE = re.compile(r"\s*[+-]?\d+\s*", re.ASCII)


def number(text: str | bytes) -> float:
    """``float(text)`` for :data:`NUMBER` text; ValueError for anything else."""
    if isinstance(text, bytes):
        text = text.decode("ascii", "replace")
    if not NUMBER.fullmatch(text):
        raise ValueError(f"could not read {text[:30]!r} as a number")
    return float(text)


def whole(text: str | bytes) -> int:
    """``int(text)`` for digits with an optional sign; ValueError for anything else."""
    if isinstance(text, bytes):
        text = text.decode("ascii", "replace")
    if not WHOLE.fullmatch(text):
        raise ValueError(f"could not read {text[:30]!r} as a whole number")
    return int(text)


def first_unplain(tokens: Sequence[str | bytes]) -> int | None:
    """Index of the first token that is not :data:`NUMBER` text, or None, for tokens that
    numpy converts in bulk (``np.array(tokens).astype(float)`` reads ``1_000`` as float
    does). On ASCII text without an underscore, float reads nothing :data:`NUMBER` does not,
    so only then are the tokens looked at one by one."""
    if not tokens:
        return None
    if isinstance(tokens[0], bytes):
        raw = b"".join(tokens)                                   # type: ignore[arg-type]
        if raw.isascii() and b"_" not in raw:
            return None
    else:
        text = "".join(tokens)                                   # type: ignore[arg-type]
        if text.isascii() and "_" not in text:
            return None
    for k, tok in enumerate(tokens):
        text = tok if isinstance(tok, str) else tok.decode("latin-1")
        if not NUMBER.fullmatch(text):
            return k
    return None


def _arg_type(parse: Callable[[str], Any], name: str) -> Callable[[str], Any]:
    """An argparse ``type`` reading with ``parse``; argparse names it in its message
    ("invalid number value: '1_000'")."""
    def read(text: str) -> Any:
        return parse(text)

    read.__name__ = name
    return read


#: argparse types of number and whole-number options: strict, where float and int read
#: ``1_000`` and full-width digits.
NUMBER_ARG = _arg_type(number, "number")
WHOLE_ARG = _arg_type(whole, "whole number")
