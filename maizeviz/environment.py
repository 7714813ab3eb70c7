"""The environment variables maizeviz reads, each parsed here with the checks its options get.

Every ``MAIZEVIZ_*`` variable the code reads is listed in :data:`VARIABLES` and read through
:func:`switch`, :func:`whole_number` or :func:`word`, when it is used (not at import: a module imported
for something else does not fail on a variable it never uses). A value that is not what the
variable takes is refused in one line naming the variable, its value and what it takes, as
an option's value is (``MAIZEVIZ_FIELD_POINTS=1e3`` was ``int('1e3')``'s traceback at
import).

=========================  ===========================================================
``MAIZEVIZ_FIELD_POINTS``  records above which a Parquet points file is read as a field,
                           plant chunk by plant chunk (a whole number >= 0; 4,000,000)
``MAIZEVIZ_PACKET_WIDTH``  rays per Embree packet (4, 8 or 16; 8)
``MAIZEVIZ_PACKETS``       0 turns the ray-packet kernel off (embreex's single rays)
``MAIZEVIZ_LOOPS``         0 turns the compiled loops off (numpy does their work)
``MAIZEVIZ_DEBUG``         1 shows the traceback of an internal error on the command line
``MAIZEVIZ_EMBREE_ISA``    the instruction set Embree traces with (sse2, sse4.2, avx, avx2,
                           avx512; unset or empty: the CPU's best)
=========================  ===========================================================

A switch takes 0 or 1 (and no, off, false, yes, on, true, any case); unset or empty is its
default.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from maizeviz.errors import MaizevizError
from maizeviz.numbers import whole


class EnvironmentVariableError(MaizevizError):
    """A ``MAIZEVIZ_*`` environment variable holds a value it does not take; its
    ``quantity`` is the variable's name."""


@dataclass(frozen=True)
class Variable:
    """One environment variable: what it takes and its default.

    Attributes
    ----------
    kind : {"switch", "whole", "word"}
    default : bool, int or None
    meaning : str
        What it sets, in words.
    low : int
        Smallest whole number taken.
    choices : tuple of int
        The only whole numbers taken (empty: any from ``low`` on).
    words : dict of str to str
        A word variable's words, any case, each to the value it stands for.
    """

    kind: str
    default: bool | int | None
    meaning: str
    low: int = 0
    choices: tuple[int, ...] = ()
    words: dict[str, str] | None = None


#: Every environment variable maizeviz reads.
VARIABLES: dict[str, Variable] = {
    "MAIZEVIZ_FIELD_POINTS": Variable(
        "whole", 4_000_000, "records above which a Parquet points file is read plant chunk "
        "by plant chunk"),
    "MAIZEVIZ_PACKET_WIDTH": Variable("whole", 8, "rays per Embree packet",
                                      choices=(4, 8, 16)),
    "MAIZEVIZ_PACKETS": Variable("switch", True, "the ray-packet kernel"),
    "MAIZEVIZ_LOOPS": Variable("switch", True, "the compiled loops"),
    "MAIZEVIZ_DEBUG": Variable("switch", False, "tracebacks of internal errors"),
    "MAIZEVIZ_EMBREE_ISA": Variable(
        "word", None, "the instruction set Embree traces with",
        words={"sse2": "sse2", "sse4.2": "sse4.2", "sse42": "sse4.2", "avx": "avx",
               "avx2": "avx2", "avx512": "avx512", "avx-512": "avx512"}),
}

_ON = ("1", "yes", "on", "true")
_OFF = ("0", "no", "off", "false")


def _variable(name: str, kind: str) -> Variable:
    var = VARIABLES.get(name)
    if var is None or var.kind != kind:              # a programming error, not an input
        raise KeyError(f"{name} is not a {kind} environment variable of maizeviz")
    return var


def _refuse(name: str, raw: str, takes: str) -> EnvironmentVariableError:
    return EnvironmentVariableError(f"{name}='{raw[:40]}' in the environment: {takes} "
                                    f"({VARIABLES[name].meaning}); unset it for the default",
                                    quantity=name)


def switch(name: str) -> bool:
    """The value of a switch variable: its default when unset or empty.

    Raises
    ------
    EnvironmentVariableError
        A value other than 0/1, no/yes, off/on or false/true.
    """
    var = _variable(name, "switch")
    raw = os.environ.get(name, "")
    text = raw.strip().lower()
    if not text:
        return bool(var.default)
    if text in _ON:
        return True
    if text in _OFF:
        return False
    raise _refuse(name, raw, "takes 0 or 1")


def whole_number(name: str) -> int:
    """The value of a whole-number variable (digits, as options read them: not ``1e3``,
    ``1_000`` or ``4.0``): its default when unset.

    Raises
    ------
    EnvironmentVariableError
        Empty, not a whole number, below the variable's least or not one of its choices.
    """
    var = _variable(name, "whole")
    if name not in os.environ:
        return int(var.default or 0)
    raw = os.environ[name]
    takes = f"takes one of {', '.join(map(str, var.choices))}" if var.choices else \
        f"takes a whole number >= {var.low:,} (digits only)"
    try:
        value = whole(raw)
    except ValueError:
        raise _refuse(name, raw, takes) from None
    if (var.choices and value not in var.choices) or value < var.low:
        raise _refuse(name, raw, takes)
    return value


def word(name: str) -> str | None:
    """The value of a word variable (any case, blanks around ignored): the value its word
    stands for; None when unset or empty.

    Raises
    ------
    EnvironmentVariableError
        A word the variable does not take.
    """
    var = _variable(name, "word")
    raw = os.environ.get(name, "")
    if not raw.strip():
        return None
    words = var.words or {}
    value = words.get(raw.strip().lower())
    if value is None:
        raise _refuse(name, raw, f"takes one of {', '.join(sorted(set(words.values())))}")
    return value


#: The reader of each kind of variable.
READERS = {"switch": switch, "whole": whole_number, "word": word}


def problems() -> list[str]:
    """One line for each ``MAIZEVIZ_*`` variable set to a value it does not take (for
    ``--info``)."""
    out = []
    for name, var in VARIABLES.items():
        try:
            READERS[var.kind](name)
        except EnvironmentVariableError as exc:
            out.append(str(exc))
    return out
