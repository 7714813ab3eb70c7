"""Property-based fuzzing of every parser of outside data in these modules: points CSV,
layout JSON, FASTRAK records, and the recording a resume replays.

Each parser, given arbitrary bytes or values, either returns or raises a MaizevizError whose
message is one line, never anything else, within a deadline. Cases the fuzzers found are
pinned down as plain regression tests at the end of the file.
"""

import atexit
import json
import os
import shutil
import string
import tempfile
from pathlib import Path

import numpy as np
import pytest
import scipy.spatial  # noqa: F401 - imported once here, not inside the first timed example
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from maizeviz.canopy.layout import layout_from_dict, load_layout
from maizeviz.digitizer.protocol import (
    STYLUS_ITEMS,
    Garbled,
    Record,
    RecordParser,
    ascii_length,
    binary_length,
)
from maizeviz.digitizer.session import COLUMNS, Session
from maizeviz.errors import MaizevizError
from maizeviz.io.points import parse_points, read_points
from maizeviz.leaf.grid import build_grids

#: MAIZEVIZ_FUZZ_EXAMPLES=5000 runs a long, random search (the default run is short and the
#: same every time, so CI stays under a minute and never flips).
_LONG = int(os.environ.get("MAIZEVIZ_FUZZ_EXAMPLES", "0"))
#: A deadline catches runaway inputs; 5 s leaves room for a loaded machine (a case takes ms).
FUZZ = settings(max_examples=_LONG or 120, deadline=5000, derandomize=not _LONG,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
FEW = settings(FUZZ, max_examples=_LONG or 50)

_DIR = tempfile.mkdtemp(prefix="maizeviz-fuzz-")
atexit.register(shutil.rmtree, _DIR, True)


def scratch(name: str) -> Path:
    return Path(_DIR) / name


def one_line(exc: BaseException) -> None:
    msg = str(exc)
    assert isinstance(exc, MaizevizError), f"{type(exc).__name__}: {msg}"
    assert msg and len(msg.splitlines()) == 1, msg
    assert len(msg) < 2000 and "Traceback" not in msg


def only_own_errors(fn, *args, **kw):
    """Call ``fn``; anything raised must be a MaizevizError with a one-line message."""
    try:
        return fn(*args, **kw)
    except Exception as exc:  # noqa: BLE001 - that is what is being tested
        one_line(exc)
        return None


# ------------------------------------------------------------------------------- points
HEADER = st.sampled_from(["plant,leaf,row,col,x,y,z", ",".join(COLUMNS),
                          "Plant;Leaf;Row;Col;X;Y;Z", "x,y,z,plant,leaf,row,col,time",
                          "plant,leaf,row,col,x,y,z,status", "plant\tleaf\trow\tcol\tx\ty\tz"])
TOKEN = st.one_of(
    st.integers(-3, 30).map(str),
    st.sampled_from(["", " ", "1e300", "-1e300", "1e9", "1e999", "nan", "inf", "-0", "3.0",
                     "2.5", "1_0", '"', '"1"', '"a,b"', '"x\ny"', "\r", "recorded", "undone",
                     "discarded", "next_leaf", "reco", "\x00", "é", "\u2028", "9" * 40]),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.text(alphabet=string.printable, max_size=6),
)
LINE = st.lists(TOKEN, min_size=0, max_size=13).map(",".join)
ENDING = st.sampled_from(["\n", "\r\n", "\r\n", "\n\n", ""])


@st.composite
def points_text(draw):
    lines = [draw(HEADER)] + draw(st.lists(LINE, max_size=25))
    return "".join(line + draw(ENDING) for line in lines)


def check_table(table):
    n = len(table)
    assert table.ids.shape == (n, 4) and table.xyz.shape == (n, 3) and table.line.shape == (n,)
    assert table.ids.dtype == np.int64 and table.xyz.dtype == np.float64
    assert all(len(v) == n for v in table.extra.values())
    for p in table.problems:
        assert len(p.splitlines()) == 1, p
    for msgs in table.bad_leaves.values():
        for m in msgs:
            assert len(m.splitlines()) == 1, m
    _, errors = build_grids(table)                    # what every reader of a table does next
    for e in errors:
        one_line(e)


@FUZZ
@given(points_text())
def test_points_text_fuzz(text):
    table = only_own_errors(parse_points, text)
    if table is not None:
        check_table(table)


@FUZZ
@given(st.binary(max_size=600))
@example(b"plant,leaf,row,col,x,y,z\n\"a\nb")
@example(b"\"a\nb\",leaf\n")
def test_points_bytes_fuzz(data):
    path = scratch("bytes.csv")
    path.write_bytes(data)
    table = only_own_errors(read_points, path)
    if table is not None:
        check_table(table)


def same_table(a, b):
    assert np.array_equal(a.ids, b.ids) and np.array_equal(a.line, b.line)
    assert np.array_equal(a.xyz, b.xyz, equal_nan=True)
    assert a.problems == b.problems and a.bad_leaves == b.bad_leaves and a.extra == b.extra


NUMERIC = st.one_of(st.integers(-5, 12).map(str), st.sampled_from(["1e3", "2.0", "0.5", "-",
                                                                   "", "1e12", "+3", ".5", "1.",
                                                                   "1e999", " 4 ", "e5"]),
                    st.floats(-1e6, 1e6).map(lambda v: f"{v:.3f}"))


@FUZZ
@given(st.lists(st.lists(NUMERIC, min_size=6, max_size=8).map(",".join), max_size=40),
       st.sampled_from(["\n", "\r\n"]), st.booleans(), st.booleans())
def test_block_and_line_readers_agree(lines, end, last_end, columnar):
    """The block parsers (numpy's, and pyarrow's for large files) give exactly what reading
    line by line gives."""
    import maizeviz.io.points as points

    text = "plant,leaf,row,col,x,y,z" + end + end.join(lines) + (end if last_end else "")
    old = points.COLUMNAR_BYTES
    points.COLUMNAR_BYTES = 0 if columnar else old
    try:
        _readers_agree(text)
    finally:
        points.COLUMNAR_BYTES = old


@FUZZ
@given(st.lists(st.text("0123456789+-.eE ", max_size=12), min_size=1, max_size=30))
def test_block_numbers_are_pythons_floats(fields):
    """pyarrow's and numpy's block parsers read a field as Python's float() does, or refuse
    the block (then read line by line): never another number."""
    from maizeviz.io.points import _numbers

    block = "".join(f"1,{f}\n" for f in fields).encode()
    for columnar in (True, False):
        got = _numbers(block, ",", 2, columnar)
        if got is None:
            continue
        assert len(got) == 2 and len(got[1]) == len(fields)
        for value, text in zip(got[1], fields):
            try:
                expected = float(text)
            except ValueError:
                assert np.isnan(value) and not text.strip(), (text, value)   # an empty field
                continue
            assert value == expected or (np.isnan(value) and np.isnan(expected)), (text, value)
            assert np.signbit(value) == np.signbit(expected)


@FUZZ
@given(st.lists(st.floats(allow_nan=False, allow_infinity=False), min_size=1, max_size=30),
       st.sampled_from(["{!r}", "{:.3f}", "{:.17g}", "{:e}"]))
def test_block_numbers_round_as_python(values, fmt):
    from maizeviz.io.points import _numbers

    texts = [fmt.format(v) for v in values]
    block = "".join(f"1,{t}\n" for t in texts).encode()
    for columnar in (True, False):
        got = _numbers(block, ",", 2, columnar)
        assert got is not None
        assert [float(t) for t in texts] == got[1].tolist()


def _readers_agree(text):
    path = scratch("agree.csv")
    path.write_text(text, newline="")
    try:
        by_line = parse_points(text)
    except MaizevizError as exc:
        with pytest.raises(MaizevizError) as again:
            read_points(path)
        assert str(again.value).split(": ", 1)[1] == str(exc).split(": ", 1)[1]
        return
    same_table(read_points(path), by_line)


# ------------------------------------------------------------------------------ layouts
JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(
        st.sampled_from(["x", "y", "plant", "plants", "rows", "field", "x0", "y0", "x1", "y1",
                         "seed", "jitter_cm", "azimuth_deg", "row_spacing", "plant_spacing",
                         "north_deg", "maizeviz_layout"]) | st.text(max_size=4),
        children, max_size=6),
    max_leaves=25)

NUMBER = st.one_of(st.integers(), st.floats(), st.sampled_from([0, 1, 60, 30, -1, 1e-300,
                                                                1e300, 10**400, 2**32]))


@st.composite
def layout_doc(draw):
    """A plausible layout with any of its values replaced by anything."""
    def val(good):
        return draw(st.one_of(st.just(good), NUMBER, JSON)) if draw(st.booleans()) else good

    rows = []
    for i in range(draw(st.integers(0, 3))):
        plants = [{"y": val(30.0 * j), "plant": val(1), "azimuth_deg": val(0),
                   "jitter_cm": val(1)} for j in range(draw(st.integers(0, 3)))]
        rows.append({"x": val(60.0 * i), "plants": val(plants)})
    return {"maizeviz_layout": val(1), "row_spacing": val(60), "plant_spacing": val(30),
            "north_deg": val(0), "seed": val(0),
            "field": val({"x0": val(0), "y0": val(0), "x1": val(200), "y1": val(100)}),
            "rows": val(rows)}


@FUZZ
@given(JSON)
def test_layout_from_arbitrary_json(data):
    only_own_errors(layout_from_dict, data, {1, 2})


@FUZZ
@given(layout_doc(), st.sampled_from([None, {1}, {1, 2, 3}]))
def test_layout_from_mutated_documents(doc, plants):
    lay = only_own_errors(layout_from_dict, doc, plants)
    if lay is not None:
        assert lay.placements and np.isfinite(lay.cells).all()
        assert all(np.isfinite([p.x, p.y, p.azimuth_deg]).all() for p in lay.placements)
        assert 0 < lay.ground_area_cm2 < 1e11


@FEW
@given(st.one_of(st.binary(max_size=300), layout_doc().map(lambda d: json.dumps(d).encode())))
def test_load_layout_fuzz(data):
    path = scratch("layout.json")
    path.write_bytes(data)
    only_own_errors(load_layout, path)


# ------------------------------------------------------------------------ FASTRAK records
def record_bytes(station=1, values=(1.0, 2.0, 3.0, 4.0, 5.0, 6.0), stylus=1, error=" "):
    fields = "".join(f"{v:7.2f}"[:7] for v in values)
    return f"0{station}{error}{fields} {stylus}\r\n".encode("latin-1")


STREAM = st.lists(st.one_of(
    st.binary(max_size=60),
    st.builds(record_bytes, st.integers(0, 9), st.tuples(*[st.floats(-999, 999)] * 6),
              st.sampled_from([0, 1, 7]), st.sampled_from([" ", "x", "y", "\n", "\x00"])),
    st.sampled_from([b"\r\n", b"0", b"2", b"21S", b"2 E*ERROR*x*ERROR* EC-1*PS1\r\n",
                     b"21S" + b"zz" * 30 + b"\r\n", b"21Sfff\r\n", b"0" * 5000, b"2" * 5000,
                     b"#" * 5000])), max_size=12)


@FUZZ
@given(STREAM, st.integers(1, 64), st.booleans())
def test_record_parser_takes_any_chunks(parts, chunk, binary):
    parser = RecordParser({1: STYLUS_ITEMS, 2: STYLUS_ITEMS}, binary=binary)
    data = b"".join(parts)
    events = []
    for k in range(0, len(data), chunk):
        events += parser.feed(data[k:k + chunk])       # never raises
        assert len(parser.buffer) <= 4096 + max(ascii_length(STYLUS_ITEMS),
                                                binary_length(STYLUS_ITEMS))
    for ev in events:
        if isinstance(ev, Record):
            assert 1 <= ev.station <= 4 and len(ev.error) == 1
        if isinstance(ev, Garbled):
            assert ev.data and ev.reason


def test_record_parser_whole_records_survive_any_split():
    data = b"".join(record_bytes(1, (k, -k, 2 * k, 0, 0, 0)) for k in range(20))
    for chunk in (1, 2, 3, 7, 47, 1000):
        parser = RecordParser({1: STYLUS_ITEMS})
        got = [e for k in range(0, len(data), chunk) for e in parser.feed(data[k:k + chunk])]
        assert [e.position[0] for e in got] == list(range(20))


# ---------------------------------------------------------------------- journal resume
JOURNAL_LINE = st.one_of(
    st.builds(lambda p, l, r, c, x: f"{p},{l},{r},{c},{x},2.000,3.000,recorded,1.0,1,",
              st.integers(-2, 3), st.integers(0, 3), st.integers(0, 3), st.integers(0, 3),
              st.floats(-100, 100).map(lambda v: f"{v:.3f}")),
    st.builds(lambda p, l, s: f"{p},{l},0,0,,,,{s},1.0,,",
              st.integers(1, 3), st.integers(1, 3),
              st.sampled_from(["next_leaf", "next_plant", "end_row", "undone", "bogus"])),
    st.just(",,,,,,,discarded,1.0,,"), st.just(",,,,,,,disc"), LINE)


@st.composite
def journal_bytes(draw):
    head = draw(st.sampled_from([",".join(COLUMNS), ",".join(COLUMNS)[:draw(st.integers(0, 60))],
                                 "plant,leaf,row,col,x,y,z"]))
    lines = [head] + draw(st.lists(JOURNAL_LINE, max_size=12))
    text = "\r\n".join(lines)
    cut = draw(st.integers(0, 40))
    text = text[:len(text) - cut] if draw(st.booleans()) else text + "\r\n"
    return text.encode("utf-8")


@FEW
@given(st.one_of(journal_bytes(), st.binary(max_size=200)), st.booleans())
def test_resume_on_any_file_then_a_press_starts_a_clean_line(data, resume):
    path = scratch("journal.csv")
    path.write_bytes(data)
    try:
        s = Session(path, cols=3, resume=resume)
    except Exception as exc:  # noqa: BLE001
        one_line(exc)
        assert path.read_bytes() == data                # a refused file is left as it was
        return
    try:
        for m in s.messages:
            assert len(m.splitlines()) == 1, m
        said = s.on_event(Record(1, " ", (7.0, 8.0, 9.0), (0.0, 0.0, 0.0), 1))
        assert said.startswith("recorded")
    finally:
        s.close()
    after = path.read_bytes()
    assert not os.path.exists(path.with_name(f".{path.name}.lock"))
    table = read_points(path)
    assert table.xyz[-1].tolist() == [7.0, 8.0, 9.0]   # the press never ran into a torn line
    assert after.endswith(b"\r\n")


# --------------------------------------------------------------- what the fuzzers found
def test_found_quoted_line_end_in_a_header_gives_a_one_line_message():
    with pytest.raises(MaizevizError) as exc:
        parse_points('"a\nb",leaf\n1,2\n')
    one_line(exc.value)


@pytest.mark.parametrize("resume", [True, False])
def test_found_torn_line_with_an_open_quote_does_not_swallow_the_next_press(tmp_path, resume):
    """A torn last line holding a lone quote: once ended, it opened a quoted field that ran
    over the discard mark and the next press, which was lost."""
    head = ",".join(COLUMNS) + "\r\n"
    point = "0,0,0,0,0.000,2.000,3.000,recorded,1.0,1,\r\n"
    mark = ",,,,,,,discarded,1.0,,\r\n"
    for body in ((point * 3, point + mark) if resume else (point + mark,)):
        path = tmp_path / "j.csv"
        path.write_text(head + body + '"', newline="")
        with Session(path, cols=3, resume=resume) as s:
            s.on_event(Record(1, " ", (7.0, 8.0, 9.0), (0.0, 0.0, 0.0), 1))
        assert read_points(path).xyz[-1].tolist() == [7.0, 8.0, 9.0]
