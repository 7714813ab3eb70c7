"""docs/tutorial.md runs as written: its Python cells in order, each printing what the text
block after it shows (numbers equal to the digits shown, words exactly), like a doctest."""

import contextlib
import io
import math
import re
from pathlib import Path

import pytest

TUTORIAL = Path(__file__).resolve().parents[2] / "docs" / "tutorial.md"
CELL = re.compile(r"```python\n(.*?)```(?:\s*```text\n(.*?)```)?", re.S)
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def cells() -> list[tuple[str, str | None]]:
    return [(code, shown) for code, shown in CELL.findall(TUTORIAL.read_text())]


def same_within_rounding(got: str, shown: str) -> str | None:
    """None when ``got`` prints what ``shown`` shows: the same words and the same numbers to
    the digits shown (one unit of the last decimal; whole numbers exactly); else what
    differs."""
    words_got, words_shown = NUMBER.split(got.strip()), NUMBER.split(shown.strip())
    if [" ".join(w.split()) for w in words_got] != [" ".join(w.split()) for w in words_shown]:
        return f"text differs:\n{got}\n-- shown --\n{shown}"
    for a, b in zip(NUMBER.findall(got), NUMBER.findall(shown)):
        digits = len(b.split(".")[1].split("e")[0].split("E")[0]) if "." in b else 0
        tol = 10.0 ** -digits if "." in b else 0.0
        if not math.isclose(float(a), float(b), rel_tol=1e-12, abs_tol=tol):
            return f"{a} is not {b} to {digits} decimals:\n{got}\n-- shown --\n{shown}"
    return None


def test_the_tutorial_has_cells_with_outputs():
    found = cells()
    assert len(found) >= 5 and sum(shown is not None and shown != "" for _, shown in found) >= 5


def test_the_tutorial_runs_and_prints_what_it_shows(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__tutorial__"}
    for k, (code, shown) in enumerate(cells(), 1):
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            exec(compile(code, f"tutorial cell {k}", "exec"), namespace)
        if shown:
            problem = same_within_rounding(out.getvalue(), shown)
            if problem:
                pytest.fail(f"tutorial cell {k}: {problem}")


@pytest.mark.parametrize("got, shown, ok", [
    ("T = 0.06327", "T = 0.0633", True),
    ("T = 0.0640", "T = 0.0633", False),
    ("T = 12", "T = 12", True),
    ("T = 13", "T = 12", False),
    ("R = 0.06", "T = 0.06", False),
])
def test_the_comparison_can_fail(got, shown, ok):
    assert (same_within_rounding(got, shown) is None) == ok
