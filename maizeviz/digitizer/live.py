"""Where the stylus is now: polling the unit between presses, and telling polls from presses.

In point mode (``e1,1``) the unit sends a record only when the stylus button is pressed. To
show the tip's live position the reader also sends ``P`` (poll) a few times a second; the
unit answers each poll with one frame (a record of every active station, station 1 first).
A poll's answer looks like a press: same record type, same stations, and the stylus switch
(item 16) down whenever the button is held. What tells them apart for sure:

1. The unit answers every poll with exactly one frame, and answers its commands in the order
   they came, on one first-in first-out line.
2. A press's frame always has the switch down; a poll's answer has it up unless the button
   is held.
3. Each poll is sent with a *fence*: ``S`` right behind ``P``. Its reply is a status record,
   type ``2`` in its header where data records are type ``0``, and it comes after the
   poll's answer, however late the unit is.

So while a poll is outstanding (its *window*, from ``PS`` to the status reply), frames are
held back. A frame with the switch up is the answer: the frames held before it, and the
frames after it until the fence, are presses. When the fence arrives with only switch-down
frames held, the answer is among them (the button was held when the poll came): exactly one
of them, the one repeating the press before it (within :data:`HELD_CM`: the tip rests on the
point while the button is down); the others are presses. When several repeat the press
before them, they are all at one place, and which of them is the answer changes no point:
one fewer press is recorded at that place either way. No time limit decides anything, so
a press at the very place of the press before it, made while an answer is late (a
simulator starved of CPU), is kept: the earlier rule, which took the first held frame within
0.5 cm of the last press for the answer once the answer's expected time had passed, lost it.

Two cases are counted, never silent: a window whose fence never comes (:data:`LATE_ANSWER_S`;
a unit that stopped answering) hands its held frames on as presses (:attr:`PollSorter.unsure`,
none dropped); a fence with no frame before it is a poll never answered
(:attr:`PollSorter.missed`). Held switch-down frames of which none repeats a press are all
handed on as presses, counted in :attr:`PollSorter.unsure` (the answer then becomes a point,
the recorder's journal keeps it; no press is lost).

Outside windows every frame is a press (switch down) or a late answer (switch up, never a
press), as without polling.
"""

from __future__ import annotations

from dataclasses import dataclass

from maizeviz.digitizer.protocol import POLL, STATUS, Garbled, Record, Status

#: The fence sent right behind each poll: the status command, whose reply (a type-2 record)
#: comes after the poll's answer.
FENCE = STATUS
#: What the reader sends to poll: the poll and its fence.
POLL_WITH_FENCE = POLL + FENCE
#: Seconds a window waits for its fence (the status reply behind the poll) before handing
#: what it holds on as presses: a unit that stopped answering.
LATE_ANSWER_S = 3.0
#: Centimetres within which a switch-down frame repeats the press before it (a poll's answer
#: while the button is held): the stylus tip is pressed on the leaf, and hand tremor moves it
#: about a millimetre; two presses of a recording are centimetres apart.
HELD_CM = 0.5


@dataclass(frozen=True)
class Live:
    """The answer to a poll: every active station's record, station 1 (the stylus) first,
    positions in cm. Never a press."""

    records: tuple[Record, ...]
    time: float

    @property
    def stylus(self) -> Record:
        return self.records[0]

    def station(self, n: int) -> Record | None:
        """The record of station ``n`` in this frame, or None."""
        for r in self.records:
            if r.station == n:
                return r
        return None


class PollSorter:
    """Decides when to poll and sorts what comes back into presses and :class:`Live` frames.

    Used by the port's reader thread only (not thread-safe); times are ``time.monotonic()``.
    Each poll is sent as ``PS``: the poll and its fence (:data:`FENCE`).

    Parameters
    ----------
    stations : active stations; station 1 carries the stylus and starts every frame
    every : seconds between polls (a poll waits for the previous one's fence)
    baud, frame_bytes : kept for callers; the fence, not a time, closes a window
    """

    def __init__(self, stations, every: float, baud: int = 115200, frame_bytes: int = 47):
        self.stations = tuple(sorted(stations))
        self.every = every
        self._last_poll = -1e9
        self._open_until: float | None = None
        self._answered = False
        self._doubt = False
        self._held: list[tuple[Record, ...]] = []
        self._frame: list[Record] = []
        #: Polls whose answer never came (a fence with nothing before it).
        self.missed = 0
        #: Windows settled without knowing their answer (no fence, a garbled record in the
        #: window, or no held frame repeating a press): every frame held handed on as a press.
        self.unsure = 0
        self._last_press: tuple[float, float, float] | None = None

    @property
    def waiting(self) -> bool:
        """A poll's fence has not come back yet."""
        return self._open_until is not None

    def due(self, now: float) -> bool:
        """Time to poll: no poll outstanding and ``every`` seconds since the last one."""
        return self._open_until is None and now - self._last_poll >= self.every

    def polled(self, now: float) -> None:
        """A poll and its fence were just sent."""
        self._last_poll = now
        self._open_until = now + LATE_ANSWER_S
        self._held, self._answered, self._doubt = [], False, False

    def feed(self, event, now: float) -> list:
        """Sort one parsed event; returns what to hand on now (records, Live, others)."""
        if isinstance(event, Status):
            return self._fence(now) if self.waiting else []     # (a fence given up on)
        if isinstance(event, Garbled) and self.waiting and not self._answered:
            self._doubt = True                  # it may have been the answer
        if not isinstance(event, Record):
            return [event]
        out: list = []
        if event.station == self.stations[0] and self._frame:
            out += self._frame_done(tuple(self._frame), now)     # a frame cut short
            self._frame = []
        if event.station != self.stations[0] and not self._frame:
            return out + [event]                                  # a stray record: pass on
        self._frame.append(event)
        if len(self._frame) == len(self.stations):
            frame, self._frame = tuple(self._frame), []
            out += self._frame_done(frame, now)
        return out

    def tick(self, now: float) -> list:
        """Settle a window whose fence never came; returns what that releases."""
        if self._open_until is None or now < self._open_until:
            return []
        held, answered = self._held, self._answered
        self._close()
        if not answered:
            if held:
                self.unsure += 1
            else:
                self.missed += 1
        return self._presses(held)

    def flush(self, now: float) -> list:
        """The reader stops: frames still held are handed on as presses (none is dropped)."""
        held = self._held
        if held and not self._answered:
            self.unsure += 1
        self._close()
        return self._presses(held)

    def _close(self) -> None:
        self._held, self._open_until = [], None
        self._answered = self._doubt = False

    def _presses(self, frames) -> list:
        """Hand ``frames`` on as presses (remembering the last one's place)."""
        if frames:
            self._last_press = frames[-1][0].position
        return [r for f in frames for r in f]

    def _frame_done(self, frame: tuple[Record, ...], now: float) -> list:
        down = frame[0].stylus != 0
        if self._open_until is None or self._answered:
            if down:
                return self._presses([frame])                   # a press, as without polling
            return [Live(frame, now)]                            # a late answer: never a press
        if down:
            self._held.append(frame)                             # press or answer: wait
            return []
        held = self._held                                        # the answer: switch up
        self._held, self._answered = [], True
        return self._presses(held) + [Live(frame, now)]

    def _fence(self, now: float) -> list:
        """The status reply behind the poll: every frame sent before it has come."""
        held, answered, doubt = self._held, self._answered, self._doubt
        self._close()
        if answered:
            return self._presses(held)
        if not held:
            self.missed += 1
            return []
        if not doubt:
            for k, frame in enumerate(held):
                before = held[k - 1][0].position if k else self._last_press
                if _near(frame[0].position, before):         # the held button's answer
                    return self._presses(held[:k] + held[k + 1:]) + [Live(frame, now)]
        self.unsure += 1                # the answer is one of them, which is not known
        return self._presses(held)


def _near(a, b) -> bool:
    """Two stylus positions (cm) within :data:`HELD_CM` of each other."""
    if a is None or b is None:
        return False
    return sum((float(x) - float(y)) ** 2 for x, y in zip(a, b)) <= HELD_CM ** 2
