"""The shared recording loop (no Qt, no port): what one poll does with what is queued, and the
history read back as the finished cross-sections of each leaf."""

import numpy as np

from maizeviz.digitizer.protocol import Garbled, Record
from maizeviz.digitizer.recorder import Recorder, plant_sections
from maizeviz.digitizer.session import Position, Session
from maizeviz.io.points import read_points


def _press(x, y=0.0, z=0.0, error=" "):
    return Record(1, error, (x, y, z), (0.0, 0.0, 0.0), 1)


def test_a_point_and_q_in_one_poll_both_count(tmp_path):
    rec = Recorder(Session(tmp_path / "s.csv", 3), None)
    rec.events.put(_press(1.0))
    rec.control("q")
    rec.events.put(_press(2.0))                     # after q: never handled
    kinds = [u.kind for u in rec.poll()]
    assert kinds == ["recorded", "finished"] and rec.finished
    assert rec.poll() == []
    rec.close()
    assert len(read_points(tmp_path / "s.csv")) == 1


def test_garbled_and_refused_updates_say_what_to_do(tmp_path):
    rec = Recorder(Session(tmp_path / "s.csv", 3), None)
    rec.events.put(Garbled(b"#", "noise"))
    rec.events.put(_press(1.0, error="x"))
    garbled, refused = rec.poll()
    assert garbled.kind == "garbled" and "noise" in garbled.message and "1 so far" in garbled.message
    assert refused.kind == "refused" and "press again" in refused.message
    rec.close()


def _history(*points):
    return [(Position(*p), (float(k), 0.0, 0.0)) for k, p in enumerate(points)]


def test_plant_sections_leave_out_the_row_being_digitized():
    h = _history((1, 1, 0, 0), (1, 1, 0, 1), (1, 1, 1, 0), (1, 1, 1, 1), (1, 1, 2, 0),
                 (1, 2, 0, 0), (2, 1, 0, 0))
    # row 2 of leaf 1 is in progress
    s = plant_sections(h, 1, Position(1, 1, 2, 1))
    assert sorted(s) == [1, 2] and sorted(s[1]) == [0, 1] and sorted(s[2]) == [0]
    np.testing.assert_array_equal(s[1][1][:, 0], [2.0, 3.0])
    # once the technician moved on (next leaf), the single-point row is a finished tip
    s = plant_sections(h, 1, Position(1, 3, 0, 0))
    assert sorted(s[1]) == [0, 1, 2] and s[1][2].shape == (1, 3)
    assert plant_sections(h, 3, Position(3, 1, 0, 0)) == {}
