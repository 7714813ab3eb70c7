"""``record --resume`` against a model of the recorder (hypothesis stateful testing).

The model is the recorder's own rules, kept in a few lines: a press records a point at the
current position and moves one column on (to the next row after ``cols`` columns); ``r`` ends
a row early, ``n`` starts the next leaf, ``p`` the next plant, ``u`` takes back the last point
and goes back to its place. The real recorder (:class:`Session`, writing a real file) runs the
same presses and controls, and is stopped and resumed at any moment. Between sessions the
journal is changed in every way that leaves its points as they are:

- lines the points reader skips are appended (a line of 12 fields, a plant id beyond its
  range, an unknown status, an undo of a point never recorded, the last undo written twice,
  blank lines);
- a point's status ``recorded`` is written as the docs allow (empty, ``ok``, capitals);
- the last line is cut anywhere before its line end (a crash, a full disk): the journal's
  promise is that such a line was never reported recorded, so the model forgets it;
- zero bytes are appended (a power cut: the file's length reached the disk, its data not).

After every resume the recorder must be where the model is (the same points, in the same
order, and the same next position) or refuse in one line before any press; and the points
reader must read the model's points from the file at every stop.
"""

import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from hypothesis.stateful import (
    RuleBasedStateMachine,
    initialize,
    invariant,
    precondition,
    rule,
)

from maizeviz.digitizer.protocol import Record
from maizeviz.digitizer.session import Session, SessionError
from maizeviz.errors import PointsFileError
from maizeviz.io.points import read_points


class Model:
    """The recorder's rules: positions are (plant, leaf, row, col)."""

    def __init__(self, cols: int):
        self.cols = cols
        self.pos = (1, 1, 0, 0)
        self.kept: list[tuple[tuple, tuple]] = []

    def copy(self) -> "Model":
        m = Model(self.cols)
        m.pos, m.kept = self.pos, list(self.kept)
        return m

    def press(self, xyz) -> bool:
        """Returns whether a line is written."""
        if any(k == self.pos for k, _ in self.kept):
            return False
        self.kept.append((self.pos, xyz))
        plant, leaf, row, col = self.pos
        self.pos = (plant, leaf, row + 1, 0) if col + 1 >= self.cols else \
            (plant, leaf, row, col + 1)
        return True

    def control(self, key: str) -> bool:
        plant, leaf, row, col = self.pos
        if key == "u":
            if not self.kept:
                return False
            self.pos = self.kept.pop()[0]
        elif key == "r":
            if col == 0:
                return False
            self.pos = (plant, leaf, row + 1, 0)
        elif key == "n":
            self.pos = (plant, leaf + 1, 0, 0)
        else:
            self.pos = (plant + 1, 1, 0, 0)
        return True


def _record(x: float) -> Record:
    return Record(1, " ", (x, 2.5, 100.125), (0.0, 0.0, 0.0), 1)


#: Lines the points reader skips, whatever the recording holds.
JUNK = {
    "12 fields": "1,1,0,0,1.000,2.000,3.000,recorded,1.0,1,,\r\n",
    "plant id out of range": "999999999999,1,0,0,1.000,2.000,3.000,recorded,1.0,1,\r\n",
    "unknown status": "1,1,0,0,1.000,2.000,3.000,maybe,1.0,1,\r\n",
    "undo of a point never recorded": "77,1,0,0,1.000,2.000,3.000,undone,1.0,,\r\n",
    "blank lines": "\r\n  \r\n",
}


class RecorderMachine(RuleBasedStateMachine):
    def __init__(self):
        super().__init__()
        self.dir = Path(tempfile.mkdtemp(prefix="maizeviz-resume-"))
        self.path = self.dir / "rec.csv"
        self.model: Model | None = None
        self.session: Session | None = None
        # for each line the sessions wrote, the model before it (None: a line that means
        # nothing to the model, as the junk appended or a torn line's repair)
        self.before: list[Model | None] = []
        self.x = 0.0
        self.zeros = False                   # the file ends in zero bytes (removed on resume)

    def teardown(self):
        if self.session is not None:
            self.session.close()
        shutil.rmtree(self.dir, ignore_errors=True)

    # ------------------------------------------------------------------ helpers
    def _lines(self) -> int:
        return self.path.read_bytes().count(b"\n") if self.path.exists() else 0

    def _wrote(self, before: Model, n0: int) -> None:
        """Attach the lines just written (one per press or control) to the model before."""
        new = self._lines() - n0
        assert new in (0, 1, 2, 3)           # a point, perhaps after a torn line's repair
        self.before += [None] * (new - 1) + [before] if new else []

    def _agree(self) -> None:
        s, m = self.session, self.model
        assert s is not None and m is not None
        assert (s.pos.plant, s.pos.leaf, s.pos.row, s.pos.col) == m.pos
        assert [((q.plant, q.leaf, q.row, q.col), xyz) for q, xyz in s.history] == m.kept
        assert s.cols == m.cols

    # ------------------------------------------------------------------ rules
    @initialize(cols=st.integers(1, 4))
    def start(self, cols):
        self.session = Session(self.path, cols=cols)
        self.model = Model(cols)
        self.before = [None]                                  # the header

    @precondition(lambda self: self.session is not None)
    @rule()
    def press(self):
        self.x += 1.0
        xyz = (self.x, 2.5, 100.125)
        before = self.model.copy()
        n0 = self._lines()
        said = self.session.on_event(_record(self.x))
        wrote = self.model.press(xyz)
        assert said.startswith("recorded" if wrote else "refused"), said
        self._wrote(before, n0)
        self._agree()

    @precondition(lambda self: self.session is not None)
    @rule(key=st.sampled_from("nprru"))
    def control(self, key):
        before = self.model.copy()
        n0 = self._lines()
        self.session.control(key)
        self.model.control(key)
        self._wrote(before, n0)
        self._agree()

    @precondition(lambda self: self.session is not None)
    @rule()
    def stop(self):
        self.session.close()
        self.session = None
        self._reader_agrees()

    @precondition(lambda self: self.model is not None and self.session is None
                  and not self.zeros)
    @rule(kind=st.sampled_from(sorted(JUNK)))
    def append_junk(self, kind):
        with open(self.path, "ab") as fh:
            fh.write(JUNK[kind].encode())
        self.before += [None] * JUNK[kind].count("\n")

    @precondition(lambda self: self.model is not None and self.session is None
                  and not self.zeros)
    @rule()
    def repeat_last_undo(self):
        data = self.path.read_bytes()
        last = data.rstrip(b"\r\n").rsplit(b"\n", 1)[-1]
        if b",undone," in last and data.endswith(b"\n"):
            with open(self.path, "ab") as fh:
                fh.write(last.rstrip(b"\r") + b"\r\n")
            self.before.append(None)

    @precondition(lambda self: self.model is not None and self.session is None)
    @rule(how=st.sampled_from(["", "ok", "RECORDED", " recorded "]))
    def restate_last_point(self, how):
        data = self.path.read_bytes()
        k = data.rfind(b",recorded,")
        if k >= 0:
            self.path.write_bytes(data[:k] + b"," + how.encode() + b"," + data[k + 10:])

    @precondition(lambda self: self.model is not None and self.session is None
                  and not self.zeros and self.before and self.before[-1] is not None)
    @rule(data=st.data())
    def tear_last_line(self, data):
        raw = self.path.read_bytes()
        start = raw.rstrip(b"\n").rfind(b"\n") + 1
        assert raw.endswith(b"\n")
        cut = data.draw(st.integers(start + 1, len(raw) - 1), label="cut")
        self.path.write_bytes(raw[:cut])
        self.model = self.before.pop()       # never reported recorded: the model forgets it
        self.before.append(None)             # the torn line, ended when resumed

    @precondition(lambda self: self.model is not None and self.session is None)
    @rule(n=st.sampled_from([1, 37, 4096]))
    def power_cut_zeros(self, n):
        with open(self.path, "ab") as fh:
            fh.write(b"\x00" * n)
        self.zeros = True

    @precondition(lambda self: self.model is not None and self.session is None)
    @rule(give_cols=st.booleans())
    def resume(self, give_cols):
        m = self.model
        before = self.path.read_bytes()
        n0 = self._lines()
        try:
            self.session = Session(self.path, cols=m.cols if give_cols else None, resume=True)
        except SessionError as exc:
            # only the width of a recording whose rows never ended by themselves is unknown
            assert not give_cols and exc.quantity == "cols", str(exc)
            assert "\n" not in str(exc)
            assert self.path.read_bytes() == before          # refused before anything
            return
        self.zeros = False
        if not m.kept and not give_cols and self.session.cols != m.cols:
            m.cols = self.session.cols                        # nothing recorded: a new width
        repaired = self._lines() - n0
        self.before += [None] * repaired
        self._agree()

    # ------------------------------------------------------------------ the reader
    def _reader_agrees(self):
        try:
            table = read_points(self.path)
        except PointsFileError as exc:
            assert not self.model.kept, str(exc)
            return
        got = [(tuple(int(v) for v in ids), tuple(float(v) for v in xyz))
               for ids, xyz in zip(table.ids, table.xyz)]
        assert got == self.model.kept

    @invariant()
    def one_recorder_at_most(self):
        assert self.session is None or self.session.fd is not None


RecorderMachine.TestCase.settings = settings(
    max_examples=100, stateful_step_count=40, deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
TestRecorderModel = RecorderMachine.TestCase


@pytest.mark.parametrize("junk", sorted(JUNK))
def test_a_skipped_line_after_a_row_end_changes_nothing(tmp_path, junk):
    """The issue's case: a line the reader skips after the last point of a 5-column row made
    the resumed recorder continue at col 5 of that row."""
    path = tmp_path / "rec.csv"
    with Session(path, cols=5) as s:
        for k in range(20):
            s.on_event(_record(float(k)))
    with open(path, "ab") as fh:
        fh.write(JUNK[junk].encode())
    with Session(path, resume=True) as s:
        assert (s.pos.row, s.pos.col, s.cols) == (4, 0, 5)
        assert len(s.history) == 20


def test_an_undo_written_twice_takes_back_one_point(tmp_path):
    """The issue's case: the same undo twice stepped back one more position, so the next press
    repeated the point before and the reader refused the whole leaf."""
    path = tmp_path / "rec.csv"
    with Session(path, cols=5) as s:
        for k in range(20):
            s.on_event(_record(float(k)))
        s.control("u")
    data = path.read_bytes()
    path.write_bytes(data + data.rstrip(b"\r\n").rsplit(b"\n", 1)[-1] + b"\n")
    with Session(path, resume=True) as s:
        assert (s.pos.row, s.pos.col) == (3, 4) and len(s.history) == 19
        assert any("which is not recorded" in m for m in s.messages)
        s.on_event(_record(99.0))
    table = read_points(path)
    assert len(table) == 20 and len({tuple(i) for i in table.ids}) == 20


def test_a_header_only_recording_resumes_with_the_default_width(tmp_path):
    """Found by the model: a recording stopped before its first press, resumed without
    --cols, ended in an internal error at the first press (its width was never set)."""
    path = tmp_path / "rec.csv"
    Session(path, cols=3).close()
    with Session(path, resume=True) as s:
        assert s.on_event(_record(1.0)).startswith("recorded plant 1 leaf 1 row 0 col 0")
        assert s.cols == 5


def test_an_empty_or_ok_status_is_a_point_in_a_recording_too(tmp_path):
    """docs/cli.md says an empty status, recorded or ok is a point; the reader skipped the
    first two in a recording ("unknown status")."""
    path = tmp_path / "rec.csv"
    with Session(path, cols=2) as s:
        for k in range(4):
            s.on_event(_record(float(k)))
    data = path.read_bytes().replace(b",recorded,", b",,", 1).replace(b",recorded,", b",ok,", 1)
    path.write_bytes(data)
    table = read_points(path)
    assert len(table) == 4 and not table.problems
    with Session(path, resume=True) as s:
        assert len(s.history) == 4 and (s.pos.row, s.pos.col) == (2, 0)


@pytest.mark.parametrize("zeros", [1, 4096, 100_000])
def test_a_zero_filled_tail_is_read_up_to_the_zeros_and_removed_on_resume(tmp_path, zeros):
    """A power cut can leave a file's new length without its data: zeros after intact lines.
    They were refused as binary, the whole recording with them; now the reader reads up to
    them naming how many bytes it leaves, and the recorder removes them before appending."""
    path = tmp_path / "rec.csv"
    with Session(path, cols=2) as s:
        for k in range(3):
            s.on_event(_record(float(k)))
    good = path.read_bytes()
    path.write_bytes(good + b"\x00" * zeros)
    table = read_points(path)
    assert len(table) == 3
    assert any(f"ends in {zeros:,} zero bytes" in p for p in table.problems)
    with Session(path, resume=True) as s:
        assert any(f"ended in {zeros:,} zero bytes" in m for m in s.messages)
        assert path.read_bytes() == good
        s.on_event(_record(9.0))
    assert len(read_points(path)) == 4 and b"\x00" not in path.read_bytes()


def test_a_file_of_zeros_only_is_not_text(tmp_path):
    path = tmp_path / "zeros.csv"
    path.write_bytes(b"\x00" * 100)
    with pytest.raises(PointsFileError, match="only zero bytes"):
        read_points(path)


def test_resume_refuses_where_the_next_press_would_repeat_a_point(tmp_path):
    """A hand-edited recording whose next position already holds a point: resuming would
    record it twice and the reader would refuse the whole leaf; one line, nothing written."""
    path = tmp_path / "rec.csv"
    with Session(path, cols=2) as s:
        for k in range(3):
            s.on_event(_record(float(k)))
    with open(path, "ab") as fh:                     # a point at (1, 1), then one at (1, 0)
        fh.write(b"1,1,1,1,5.000,2.500,3.000,recorded,1.0,1,\r\n"
                 b"1,1,1,0,6.000,2.500,3.000,recorded,1.0,1,\r\n")
    before = path.read_bytes()
    with pytest.raises(SessionError, match="row 1 col 1, which the recording already holds"):
        Session(path, resume=True)
    assert path.read_bytes() == before


def test_resume_refuses_to_continue_a_leaf_the_reader_refuses(tmp_path):
    path = tmp_path / "rec.csv"
    with Session(path, cols=2) as s:
        for k in range(3):
            s.on_event(_record(float(k)))
    with open(path, "ab") as fh:
        fh.write(b"1,1,1,1,abc,2.500,3.000,recorded,1.0,1,\r\n")
    with pytest.raises(SessionError, match="on a leaf the file already makes unreadable"):
        Session(path, resume=True)


def test_a_press_on_a_point_already_recorded_is_refused(tmp_path):
    """After a hand-edited recording was resumed, a press that lands on a recorded point is
    refused (the reader would refuse its whole leaf) and the technician told how to go on."""
    path = tmp_path / "rec.csv"
    with Session(path, cols=2) as s:
        s.on_event(_record(1.0))
    with open(path, "ab") as fh:                     # leaf 2 already digitized by hand
        fh.write(b"1,2,0,0,5.000,2.500,3.000,recorded,1.0,1,\r\n"
                 b"1,1,0,1,6.000,2.500,3.000,end_row,1.0,,\r\n")
    with Session(path, cols=2, resume=True) as s:
        assert (s.pos.leaf, s.pos.row, s.pos.col) == (1, 0, 1)
        assert s.control("n").startswith("next leaf")
        said = s.on_event(_record(2.0))
        assert said.startswith("refused: plant 1 leaf 2 row 0 col 0 is already recorded")
        assert s.count.refused == 1
    assert len(read_points(path)) == 2


def test_an_undo_written_twice_through_maizeviz_record(tmp_path):
    """The issue's case end to end: ``maizeviz record`` on a real pseudo-terminal against the
    simulator, an undo line doubled in the file, ``--resume``, one more press: the leaf keeps
    all its points (before, the press repeated row 3 col 3 and the reader refused the leaf)."""
    from maizeviz.digitizer.simulator import FastrakSimulator
    from tests.core.test_fastrak_record import Recorder, press

    out = tmp_path / "rec.csv"
    sim = FastrakSimulator(press_gap_s=0.0, noise_cm=0.0)
    try:
        rec = Recorder(sim.path, out, cols=5)
        rec.expect("ready")
        for k in range(20):
            press(sim, (float(k), 2.0, 3.0))
            rec.expect("recorded")
        rec.type("u")
        rec.expect("undone")
        assert rec.finish()[0] == 0
        data = out.read_bytes()
        out.write_bytes(data + data.rstrip(b"\r\n").rsplit(b"\n", 1)[-1] + b"\n")
        rec = Recorder(sim.path, out, "--resume", cols=None)
        rec.expect("ready")
        press(sim, (50.0, 2.0, 3.0))
        assert rec.expect("recorded").startswith("recorded plant 1 leaf 1 row 3 col 4")
        code, err = rec.finish()
        assert code == 0 and "next point is plant 1 leaf 1 row 3 col 4" in err
    finally:
        sim.close()
    table = read_points(out)
    assert len(table) == 20 and len({tuple(i) for i in table.ids}) == 20


# ------------------------------------------------------------------ any journal the reader reads
_POS = st.tuples(st.integers(1, 2), st.integers(1, 3), st.integers(0, 3), st.integers(0, 3))
_LINE = st.one_of(
    st.tuples(st.just("point"), _POS, st.sampled_from(["recorded", "", "ok"])),
    st.tuples(st.just("control"), _POS, st.sampled_from(["next_leaf", "next_plant",
                                                          "end_row"])),
    st.tuples(st.just("undo"), _POS, st.just("undone")),
    st.tuples(st.just("junk"), st.sampled_from(sorted(JUNK)), st.just("")),
)


def _journal(lines) -> bytes:
    out = [",".join(["plant", "leaf", "row", "col", "x", "y", "z", "status", "time",
                     "station", "error"])]
    for k, (kind, what, status) in enumerate(lines):
        if kind == "junk":
            out.append(JUNK[what].rstrip("\r\n"))
            continue
        xyz = ("", "", "") if kind == "control" else (f"{k}.000", "2.500", "100.125")
        out.append(",".join([*map(str, what), *xyz, status, "1.0",
                             "1" if kind == "point" else "", ""]))
    return ("\r\n".join(out) + "\r\n").encode()


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(_LINE, max_size=25), st.integers(1, 4), st.integers(0, 6))
# the cases, kept whatever the draws: an undo of a point never recorded, the same
# undo twice, a line the reader skips after a row's last point
@example([("point", (1, 1, 0, 0), "recorded"), ("undo", (2, 2, 1, 1), "undone")], 2, 2)
@example([("point", (1, 1, 0, 0), "recorded"), ("point", (1, 1, 0, 1), "recorded"),
          ("undo", (1, 1, 0, 1), "undone"), ("undo", (1, 1, 0, 1), "undone")], 2, 3)
@example([("point", (1, 1, 0, 0), "recorded"), ("point", (1, 1, 0, 1), "recorded"),
          ("point", (1, 1, 1, 0), "recorded"), ("point", (1, 1, 1, 1), "recorded"),
          ("junk", "unknown status", "")], 2, 3)
def test_any_journal_the_reader_accepts_resumes_without_losing_a_point(lines, cols, presses):
    """Whatever a recording holds (points anywhere, controls, undos, lines the reader skips),
    resuming it keeps the points the reader reads, in their order, and every new press lands
    where the recorder's rules put it, never on a point already held (which would make the
    reader refuse its leaf): or the resume is refused in one line with nothing written."""
    folder = Path(tempfile.mkdtemp(prefix="maizeviz-journal-"))
    try:
        path = folder / "rec.csv"
        path.write_bytes(_journal(lines))
        try:
            before = read_points(path)
            kept = [(tuple(int(v) for v in i), tuple(float(v) for v in x))
                    for i, x in zip(before.ids, before.xyz)]
        except PointsFileError:
            kept = []
        data = path.read_bytes()
        try:
            s = Session(path, cols=cols, resume=True)
        except SessionError as exc:
            assert "\n" not in str(exc) and path.read_bytes() == data
            return
        with s:
            assert [((q.plant, q.leaf, q.row, q.col), xyz) for q, xyz in s.history] == kept
            model = Model(cols)
            model.pos, model.kept = (s.pos.plant, s.pos.leaf, s.pos.row, s.pos.col), list(kept)
            assert not any(k == model.pos for k, _ in kept)      # checked when resuming
            for k in range(presses):
                xyz = (1000.0 + k, 2.5, 100.125)
                said = s.on_event(_record(xyz[0]))
                assert said.startswith("recorded" if model.press(xyz) else "refused"), said
        try:
            after = read_points(path)
            got = [(tuple(int(v) for v in i), tuple(float(v) for v in x))
                   for i, x in zip(after.ids, after.xyz)]
        except PointsFileError:                                  # no point at all
            got = []
        assert got == model.kept
        new = [k for k, _ in got[len(kept):]]                   # no new point on a held one:
        assert len(set(new)) == len(new) and not set(new) & {k for k, _ in kept}  # no leaf lost
    finally:
        shutil.rmtree(folder, ignore_errors=True)
