"""The stylus's live position between presses, and Pause: polls never become points, no press is
lost, paused presses are said and not recorded. The sorting is checked against a model of the
unit (property test), then end to end through a real pty and pyserial."""

import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.digitizer.geometry import euler_matrix
from maizeviz.digitizer.live import Live, PollSorter
from maizeviz.digitizer.port import FastrakPort
from maizeviz.digitizer.protocol import Record, Status
from maizeviz.digitizer.recorder import Recorder
from maizeviz.digitizer.session import Session
from maizeviz.digitizer.simulator import FastrakSimulator
from maizeviz.io.points import read_points


def _frame(stations, x, down, origin):
    """One frame as the unit sends it: station 1 (the stylus at x) first."""
    out = [Record(1, " ", (x, 0.0, 0.0), (0.0, 0.0, 0.0), int(down), {"origin": origin})]
    out += [Record(s, " ", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), None, {"origin": origin})
            for s in stations[1:]]
    return out


#: The status reply that fences each poll (the sorter reads only its type).
FENCE_REPLY = Status(1, 2, False, True, False, b"21S002\r\n")


@st.composite
def sessions(draw):
    n = draw(st.integers(0, 10))
    gaps = draw(st.lists(st.floats(0.34, 1.2), min_size=n, max_size=n))
    # the button is released before the next press (the unit ignores one within 333 ms)
    holds = [draw(st.floats(0.0, min(0.3, g - 0.03))) for g in gaps]
    # some presses at the very place of the press before (the case an answer's lateness hid)
    same = draw(st.lists(st.booleans(), min_size=n, max_size=n))
    return dict(gaps=gaps, holds=holds, same=same,
                latency=draw(st.lists(st.one_of(st.floats(0.0, 0.03), st.floats(0.1, 0.8)),
                                      min_size=1, max_size=20)),
                step=draw(st.floats(0.004, 0.02)), every=draw(st.sampled_from([0.02, 0.1, 0.3])),
                stations=draw(st.sampled_from([(1,), (1, 2)])))


@settings(max_examples=300, deadline=None)
@given(sessions())
def test_polls_never_become_points_and_no_press_is_lost(s):
    """A model of the unit: press k puts the stylus at x_k and holds the button for a while;
    between presses the stylus moves (x_k + 0.5), and some presses come back to the place of
    the press before. Each poll is answered after a latency with the button's state at that
    moment, its fence (the status reply) right behind. The reader feeds what arrives to the
    sorter and ticks it every ``step`` seconds, as the port's reader thread does. Some answers
    come late (up to 0.8 s, a unit's side starved of CPU), past presses made meanwhile: no
    press is lost to them, not even one at the place of the press before (the old rules took a
    held press for a late answer)."""
    stations, gaps, holds = s["stations"], s["gaps"], s["holds"]
    t_press = np.cumsum([0.2] + gaps[:-1]) if gaps else np.array([])
    end = (t_press[-1] if len(t_press) else 0.0) + 1.0
    xs = np.cumsum([0.0 if k and same else 1.0 for k, same in enumerate(s["same"])])

    def state(t):
        k = np.searchsorted(t_press, t, side="right") - 1
        down = k >= 0 and t <= t_press[k] + holds[k]
        return (float(xs[k]) if down else (xs[k] + 0.5 if k >= 0 else -0.5)), down

    arrivals = [(t, k, _frame(stations, float(xs[k]), True, "press"))
                for k, t in enumerate(t_press)]
    sorter = PollSorter(stations, s["every"])
    out, polls, now = [], 0, 0.0
    while now < end:
        if sorter.due(now):
            sorter.polled(now)
            lat = s["latency"][polls % len(s["latency"])]
            x, down = state(now + lat / 2)
            # one serial line: a press made after the answer was sent comes after it
            arrivals = [(max(t, now + lat + 1e-9), k, f) if k < 1e6 and t > now + lat / 2
                        else (t, k, f) for t, k, f in arrivals]
            arrivals.append((now + lat, 1e6 + polls, _frame(stations, x, down, "poll")))
            arrivals.append((now + lat, 1e6 + polls + 0.5, [FENCE_REPLY]))
            polls += 1
        arrivals.sort(key=lambda a: (a[0], a[1]))
        while arrivals and arrivals[0][0] <= now:
            for rec in arrivals.pop(0)[2]:
                out += sorter.feed(rec, now)
        out += sorter.tick(now)
        now += s["step"]
    for _, _, frame in sorted(arrivals, key=lambda a: (a[0], a[1])):   # the last answer
        for rec in frame:
            out += sorter.feed(rec, now)
    out += sorter.tick(now + 1.0)
    presses = [e for e in out if isinstance(e, Record) and e.station == 1]
    lives = [e for e in out if isinstance(e, Live)]
    assert [p.position[0] for p in presses] == list(xs)
    assert len(lives) == polls and sorter.missed == 0
    # a press frame keeps its reference record right behind it
    records = [e for e in out if isinstance(e, Record)]
    assert [r.station for r in records] == list(stations) * len(gaps)
    # the fence settles every window: nothing is left to chance
    assert sorter.unsure == 0


def test_live_position_through_the_pty_while_pressing():
    """The reader polls the simulated unit 20 times a second while a technician presses and
    holds the button: every press is one record, in order; the live answers follow the tip."""
    rng = np.random.default_rng(3)
    points = rng.uniform(-50, 50, (8, 3)).round(2)
    with FastrakSimulator(noise_cm=0.0) as sim:
        port = FastrakPort(sim.path, answer_timeout=0.5)
        port.configure()
        q = port.start_reader(live_every=0.05)
        for p in points:
            time.sleep(0.35)
            assert sim.press(p, hold_s=float(rng.uniform(0.0, 0.25)))
        time.sleep(0.5)
        port.close()
        events = []
        while not q.empty():
            events.append(q.get())
    presses = [e for e in events if isinstance(e, Record)]
    lives = [e for e in events if isinstance(e, Live)]
    assert [e.station for e in presses] == [1] * len(points)
    np.testing.assert_allclose([e.position for e in presses], points, atol=0.011)
    assert port.polls >= 40 and len(lives) >= port.polls - 1
    np.testing.assert_allclose(lives[-1].stylus.position, points[-1], atol=0.011)
    assert any(e.stylus.stylus == 1 for e in lives)          # answers during a hold
    assert sim.commands.count("P") == port.polls


def _press(x, y=0.0, z=0.0, station=1, angles=(0.0, 0.0, 0.0)):
    return Record(station, " ", (float(x), float(y), float(z)), tuple(map(float, angles)), 1)


def test_pause_says_each_press_it_does_not_record(tmp_path):
    out = tmp_path / "s.csv"
    rec = Recorder(Session(out, 3), None)
    rec.events.put(_press(1.0))
    rec.pause()
    rec.events.put(_press(2.0))
    rec.events.put(_press(3.0))
    rec.control("n")                                     # controls still act while paused
    rec.pause(False)
    rec.events.put(_press(4.0))
    updates = rec.poll()
    kinds = [u.kind for u in updates]
    assert kinds == ["recorded", "paused", "ignored", "ignored", "control", "resumed",
                     "recorded"]
    assert "NOT recorded" in updates[2].message and "2.0 0.0 0.0 cm" in updates[2].message
    assert "(2 while paused)" in updates[3].message and "resume to record" in updates[3].message
    assert "plant 1 leaf 2 row 0 col 0" in updates[5].message
    assert rec.ignored == 2 and not rec.paused
    rec.pause(False)                                     # resuming twice says nothing
    assert rec.poll() == []
    rec.close()
    pts = read_points(out)
    assert pts.xyz[:, 0].tolist() == [1.0, 4.0]
    assert pts.ids[:, 1].tolist() == [1, 2]              # the pause did not move the position


def test_pause_between_a_press_and_its_reference_record(tmp_path):
    """With a reference receiver a press is two records; a pause queued between them must not
    leave the press half paired (the next press would be refused)."""
    rec = Recorder(Session(tmp_path / "s.csv", 3, reference_station=2), None)
    rec.events.put(_press(1.0))
    rec.pause()
    rec.events.put(_press(0.0, station=2))
    rec.pause(False)
    rec.events.put(_press(2.0))
    rec.events.put(_press(0.0, station=2))
    kinds = [u.kind for u in rec.poll()]
    assert kinds == ["paused", "recorded", "resumed", "recorded"]   # paired, recorded
    rec.close()


def test_live_tip_in_the_plants_frame_and_its_distance_from_the_last_point(tmp_path):
    """Round trip: a tip placed in the plant's frame, seen through a swaying reference
    receiver, comes back in the plant's frame; its distance is from the last point kept."""
    rec = Recorder(Session(tmp_path / "s.csv", 3, reference_station=2), None)
    ref_pos, ref_ang = np.array([10.0, -5.0, 3.0]), np.array([30.0, -10.0, 5.0])
    world = ref_pos + euler_matrix(*ref_ang) @ np.array([1.0, 2.0, 3.0])
    rec.events.put(_press(*world))
    rec.events.put(_press(*ref_pos, station=2, angles=ref_ang))
    rec.poll()
    assert rec.live is None
    ref_pos2, ref_ang2 = np.array([12.0, -4.0, 3.5]), np.array([35.0, -8.0, 2.0])
    tip = np.array([4.0, 6.0, 3.0])
    world2 = ref_pos2 + euler_matrix(*ref_ang2) @ tip
    live = Live((Record(1, " ", tuple(world2), (0.0, 0.0, 0.0), 0),
                 Record(2, " ", tuple(ref_pos2), tuple(ref_ang2), None)), 1.0)
    rec.events.put(live)
    assert rec.poll() == []                              # nothing to say, nothing recorded
    np.testing.assert_allclose(rec.live.xyz, tip, atol=1e-9)
    assert rec.live.distance == pytest.approx(np.linalg.norm(tip - [1.0, 2.0, 3.0]))
    assert rec.live.trustworthy and rec.session.count.points == 1
    # out of the motion box: said with the position
    bad = Live((Record(1, "x", tuple(world2), (0.0, 0.0, 0.0), 0),
                Record(2, " ", tuple(ref_pos2), tuple(ref_ang2), None)), 2.0)
    rec.events.put(bad)
    rec.poll()
    assert not rec.live.trustworthy and "motion box" in rec.live.note
    rec.close()


def test_pause_in_maizeviz_record(tmp_path):
    """The command line pauses with 's' too, and says each press it does not record."""
    import subprocess
    import sys
    import threading

    out = tmp_path / "rec.csv"
    with FastrakSimulator(press_gap_s=0.0, noise_cm=0.0) as sim:
        proc = subprocess.Popen([sys.executable, "-m", "maizeviz", "record", "--port", sim.path,
                                 "--out", str(out), "--cols", "3", "--answer-timeout", "0.5"],
                                stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True, bufsize=1)
        lines: list[str] = []
        threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True).start()

        def expect(prefix):
            deadline = time.monotonic() + 10
            while time.monotonic() < deadline:
                hit = [ln for ln in lines if ln.startswith(prefix)]
                if hit:
                    return hit[-1]
                time.sleep(0.02)
            raise AssertionError(f"no line starting {prefix!r}: {lines}")

        def type_(text):
            proc.stdin.write(text + "\n")
            proc.stdin.flush()

        expect("ready")
        assert sim.press((1.0, 0.0, 0.0))
        expect("recorded plant 1 leaf 1 row 0 col 0")
        type_("s")
        expect("paused: presses are not recorded")
        assert sim.press((2.0, 0.0, 0.0))
        assert "NOT recorded" in expect("paused: the press at 2.0 0.0 0.0 cm")
        type_("s")
        expect("resumed: the next press is recorded at plant 1 leaf 1 row 0 col 1")
        assert sim.press((3.0, 0.0, 0.0))
        expect("recorded plant 1 leaf 1 row 0 col 1")
        type_("q")
        assert proc.wait(timeout=10) == 0
    assert read_points(out).xyz[:, 0].tolist() == [1.0, 3.0]


def test_a_press_at_the_place_of_the_last_while_an_answer_is_late_is_kept():
    """The unit answers each poll 0.3 s late (its side starved of CPU) while the technician
    presses the same point again and again (noise off: within 0.5 cm of the press before):
    every press is recorded once and no answer becomes a point. The old sorter took such a
    press for the late answer and lost it."""
    point = np.array([12.0, -30.0, 5.0])
    with FastrakSimulator(noise_cm=0.0, answer_delay_s=0.3) as sim:
        port = FastrakPort(sim.path, answer_timeout=1.0)
        port.configure()
        q = port.start_reader(live_every=0.02)
        made = 0
        for k in range(8):
            time.sleep(0.37 + 0.05 * (k % 3))
            made += sim.press(point, hold_s=0.1 * (k % 2))
        time.sleep(1.0)
        port.close()
        events = []
        while not q.empty():
            events.append(q.get())
    presses = [e for e in events if isinstance(e, Record)]
    lives = [e for e in events if isinstance(e, Live)]
    assert made == 8 and len(presses) == 8, (len(presses), port.polls)
    np.testing.assert_allclose([e.position for e in presses], [point] * 8, atol=0.011)
    assert port.polls >= 8 and len(lives) >= port.polls - 1
