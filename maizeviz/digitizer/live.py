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
up is the answer: the frames held before it are presses. When the window closes with only
switch-down frames held, one of them was the answer (the button was held when the poll
came): the first is taken as the answer and the rest are presses. Either way a press is
never dropped and a poll never becomes a point; a press that comes while a window is open is
reported when the window resolves (at most :attr:`PollSorter.window` later, usually within
milliseconds when the answer has the switch up). Outside windows every frame is a press, as
without polling. The one case this cannot sort is a poll's answer that arrives garbled: a
press in the same window is then taken for the answer (counted in :attr:`PollSorter.unsure`).
"""

from __future__ import annotations

from dataclasses import dataclass

from maizeviz.digitizer.protocol import Record

#: Seconds a poll's answer may take beyond its transmission time.
ANSWER_SLACK_S = 0.1


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
        #: Polls whose answer never came (the window closed with nothing held).
        self.missed = 0
        #: Windows resolved by taking a switch-down frame for the answer.
        self.unsure = 0

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
        """Close a window whose time is up; returns what that releases."""
        if self._open_until is None or now < self._open_until:
            return []
        held, self._held, self._open_until = self._held, [], None
        if not held:
            self.missed += 1
            return []
        if len(held) > 1:
            self.unsure += 1
        # the first held frame came soonest after the poll: take it as the answer
        return [Live(held[0], now)] + [r for frame in held[1:] for r in frame]

    def _frame_done(self, frame: tuple[Record, ...], now: float) -> list:
        down = frame[0].stylus != 0
        if self._open_until is None:
            if down:
                return list(frame)                               # a press, as without polling
            return [Live(frame, now)]                            # a late answer: never a press
        if down:
            self._held.append(frame)                             # press or answer: wait
            return []
        held, self._held, self._open_until = self._held, [], None
        return [r for f in held for r in f] + [Live(frame, now)]
