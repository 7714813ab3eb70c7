"""Where the stylus is now: polling the unit between presses, and telling polls from presses.

In point mode (``e1,1``) the unit sends a record only when the stylus button is pressed. To
show the tip's live position the reader also sends ``P`` (poll) a few times a second; the
unit answers each poll with one frame (a record of every active station, station 1 first).
A poll's answer looks like a press: same record type, same stations. What tells them apart:

1. The unit answers every poll with exactly one frame, within milliseconds (a frame of two
   stations is 94 bytes: 8 ms at 115200 baud, plus a USB adapter's 16 ms latency timer).
2. A press's frame always has the stylus switch (item 16) down; a poll's answer has it down
   only while the button is held.

So while a poll is unanswered (its *window*), frames are held back. A frame with the switch
up is the answer: the frames held before it are presses. A switch-down answer means the button
was held when the poll came, so its press was sent just before it, at the same place (the
stylus is still while its button is down): once the window's time is up, a held frame within
:data:`HELD_CM` of the press before it is the answer, and the other frames are presses.

A held frame that repeats no press is a press whose poll has not been answered yet: an answer
comes late when the unit's side is slow (a simulator on a busy machine), and taking the press
for the answer would lose it without a word (issue 35, item 1: the app lost 6 of 60 presses
under CPU load with the old rule, "the first held frame is the answer"). The window then
stays open for the answer, up to :data:`LATE_ANSWER_S`; if none comes, every held frame is
handed on as a press (counted in :attr:`PollSorter.unsure`). So a press is never dropped and
a poll's answer never becomes a point, except in one case: a press at the very place of the
press before it (within :data:`HELD_CM`), made while a poll's answer is late.

A press that comes while a window is open is reported when the window resolves (usually within
milliseconds, when the answer has the switch up). Outside windows every frame is a press, as
without polling.
"""

from __future__ import annotations

from dataclasses import dataclass

from maizeviz.digitizer.protocol import Record

#: Seconds a poll's answer may take beyond its transmission time.
ANSWER_SLACK_S = 0.1
#: Seconds a window holding only presses waits for a late answer before giving up on it.
LATE_ANSWER_S = 3.0
#: Centimetres within which a switch-down frame repeats the press before it (a poll's answer
#: while the button is held): the stylus tip is pressed on the leaf, and hand tremor moves it
#: about a millimetre; two presses of a recording are centimetres apart.
HELD_CM = 0.5
#: Seconds after a press within which a switch-down answer can still repeat it (a button is
#: held for a fraction of a second).
HELD_S = 2.0


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

    Parameters
    ----------
    stations : active stations; station 1 carries the stylus and starts every frame
    every : seconds between polls (a poll waits for the previous one to be answered)
    baud : the link's rate (bits per second), for how long an answer takes to arrive
    frame_bytes : bytes of one frame (a record of every active station)
    """

    def __init__(self, stations, every: float, baud: int = 115200, frame_bytes: int = 47):
        self.stations = tuple(sorted(stations))
        self.window = ANSWER_SLACK_S + 10.0 * frame_bytes / baud * 2
        self.every = every
        self._last_poll = -1e9
        self._open_until: float | None = None
        self._held: list[tuple[Record, ...]] = []
        self._frame: list[Record] = []
        #: Polls whose answer never came (nothing held for :data:`LATE_ANSWER_S`).
        self.missed = 0
        #: Windows whose answer never came while presses were held (handed on as presses).
        self.unsure = 0
        self._last_press: tuple[tuple[float, float, float] | None, float] = (None, -1e9)

    @property
    def waiting(self) -> bool:
        """A poll's answer has not been sorted out yet."""
        return self._open_until is not None

    def due(self, now: float) -> bool:
        """Time to poll: no answer outstanding and ``every`` seconds since the last poll."""
        return self._open_until is None and now - self._last_poll >= self.every

    def polled(self, now: float) -> None:
        """A poll was just sent."""
        self._last_poll = now
        self._open_until = now + self.window
        self._held = []

    def feed(self, event, now: float) -> list:
        """Sort one parsed event; returns what to hand on now (records, Live, others)."""
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
        """Settle a window whose time is up; returns what that releases."""
        if self._open_until is None or now < self._open_until:
            return []
        held = self._held
        late = now >= self._open_until + LATE_ANSWER_S
        if not held:
            if late:                            # the answer never came
                self._close()
                self.missed += 1
            return []                           # (a late answer is not taken for a press)
        last, when = self._last_press
        for k, frame in enumerate(held):
            before = held[k - 1][0].position if k else (last if now - when <= HELD_S else None)
            if _near(frame[0].position, before):                  # the held button's answer
                self._close()
                return self._presses(held[:k] + held[k + 1:], now) + [Live(frame, now)]
        if not late:
            return []                           # presses whose poll is answered late: wait
        self._close()
        self.unsure += 1
        return self._presses(held, now)

    def flush(self, now: float) -> list:
        """The reader stops: frames still held are handed on as presses (none is dropped)."""
        held = self._held
        self._close()
        return self._presses(held, now)

    def _close(self) -> None:
        self._held, self._open_until = [], None

    def _presses(self, frames, now: float) -> list:
        """Hand ``frames`` on as presses (remembering the last one's place)."""
        if frames:
            self._last_press = (frames[-1][0].position, now)
        return [r for f in frames for r in f]

    def _frame_done(self, frame: tuple[Record, ...], now: float) -> list:
        down = frame[0].stylus != 0
        if self._open_until is None:
            if down:
                return self._presses([frame], now)              # a press, as without polling
            return [Live(frame, now)]                            # a late answer: never a press
        if down:
            self._held.append(frame)                             # press or answer: wait
            return self.tick(now)                                # (a late window may settle)
        held = self._held
        self._close()
        return self._presses(held, now) + [Live(frame, now)]


def _near(a, b) -> bool:
    """Two stylus positions (cm) within :data:`HELD_CM` of each other."""
    if a is None or b is None:
        return False
    return sum((float(x) - float(y)) ** 2 for x, y in zip(a, b)) <= HELD_CM ** 2
