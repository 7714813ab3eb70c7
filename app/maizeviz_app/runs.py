"""Light results the window keeps: one per mesh level and light (sun, sky, day), compared in
one table and one plot while they share their sampling. Qt-free (the model holds them)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from maizeviz.mesh.levels import COMPLEXITY_STOPS, parse_level

#: The lights the app computes, in the order of the buttons, the table and the plot.
MODES = ("sun", "sky", "day")
#: Skies: kind -> (what the light panel's combo says, how a result is named in the table).
SKIES = {"soc": ("standard overcast (SOC): brightness (1 + 2 cos θ)/3", "overcast sky"),
         "uoc": ("uniform overcast (UOC)", "uniform sky")}


def level_order(label: str) -> int:
    """Fine-to-coarse rank of a level label (``K=4`` ... ``4 triangles``), for sorting."""
    for k, stop in enumerate(COMPLEXITY_STOPS):
        if parse_level(stop).label == label.split(",")[0]:
            return k
    return len(COMPLEXITY_STOPS)


@dataclass
class Run:
    """One light result: the level it was traced on (``label``), the canopy it belongs to
    (``signature``), the light (``kind``: sun, sky or day) and, for a sun, each leaf
    triangle's light class (F,) int8 (None until computed); for a sky or a day ``extra``
    holds what the light process made of it (per-leaf and per-plant rows, per-triangle
    values: :class:`maizeviz_app.jobs.Diffuse`)."""

    label: str
    signature: tuple
    result: Any
    classes: np.ndarray | None = None
    kind: str = "sun"
    extra: Any = None

    @property
    def name(self) -> str:
        """The run's column in the table and curve in the plot."""
        if self.kind == "sky":
            return f"{self.label}, {SKIES.get(self.result.sky.kind, ('', 'sky'))[1]}"
        if self.kind == "day":
            return f"{self.label}, day: PAR transmitted"
        return self.label

    @property
    def transmission(self) -> np.ndarray:
        """(H,) the fraction of the light reaching each height (for a day: of its PAR)."""
        if self.kind == "day":
            return np.asarray(self.result.transmission_by_height)
        return np.asarray(self.result.transmission)


class LightRuns:
    """The last light result per mesh level and light, sampled the same way."""

    def __init__(self) -> None:
        self.runs: dict[str, Run] = {}
        self.settings: dict[str, Any] = {}          # each light's own settings
        self.sampling: Any = None                   # heights, density, periodic field
        self.last: Run | None = None
        self._order: dict[int, int] = {}            # id(run) -> when it was added
        self._added = 0

    def add(self, run: Run, settings: Any, sampling: Any = None) -> bool:
        """Keep ``run``; True if it replaced results traced with other settings (another
        ``sampling``: every result; other ``settings`` of the run's light: that light's)."""
        dropped = False
        if self.runs and sampling != self.sampling:
            self.runs.clear()
            self.settings.clear()
            dropped = True
        elif run.kind in self.settings and settings != self.settings[run.kind]:
            kept = {k: r for k, r in self.runs.items() if r.kind != run.kind}
            dropped = len(kept) != len(self.runs)
            self.runs = kept
        self.sampling = sampling
        self.settings[run.kind] = settings
        self.runs[run.name] = run
        self.runs = dict(sorted(self.runs.items(),
                                key=lambda kv: (MODES.index(kv[1].kind),
                                                level_order(kv[1].label))))
        self._added += 1
        self._order[id(run)] = self._added
        self._order = {id(r): self._order.get(id(r), 0) for r in self.runs.values()}
        self.last = run
        return dropped

    def copy(self) -> LightRuns:
        """A shallow copy (the runs are shared), to preview a result in a worker."""
        other = LightRuns()
        other.runs, other.settings = dict(self.runs), dict(self.settings)
        other.sampling, other.last = self.sampling, self.last
        other._order, other._added = dict(self._order), self._added
        return other

    def clear(self) -> None:
        self.runs.clear()
        self.settings.clear()
        self.sampling = None
        self.last = None
        self._order.clear()

    def for_signature(self, signature: tuple, kind: str = "sun") -> Run | None:
        """The ``kind`` result of a canopy."""
        for run in self.runs.values():
            if run.signature == signature and run.kind == kind:
                return run
        return None

    def latest(self, signature: tuple | None = None, kinds: Sequence[str] = MODES) -> Run | None:
        """The result added last (of a canopy, of the ``kinds`` given)."""
        runs = [r for r in self.runs.values() if r.kind in kinds and
                (signature is None or r.signature == signature)]
        return max(runs, key=lambda r: self._order.get(id(r), 0)) if runs else None

    def in_order(self) -> list[Run]:
        """The runs in the order they were added (the last one is :attr:`last`)."""
        return sorted(self.runs.values(), key=lambda r: self._order.get(id(r), 0))

    def of_kind(self, kind: str) -> Run | None:
        return self.latest(None, (kind,))

    def heights(self) -> tuple[float, ...]:
        if self.last is None:
            return ()
        return tuple(float(h) for h in self.last.result.heights_cm)

    def curves(self):
        from maizeviz_app.plots import Curve

        return [Curve(r.name, tuple(map(float, r.result.heights_cm)),
                      tuple(map(float, r.transmission)), r.kind, r.label)
                for r in self.runs.values()]

    def table(self) -> tuple[list[str], list[list[str]]]:
        """Header and rows (one per height) of the results table."""
        names = list(self.runs)
        header = ["height cm"] + names
        rows = []
        for i, h in enumerate(self.heights()):
            row = [f"{h:g}"]
            for name in names:
                t = self.runs[name].transmission
                row.append(f"{t[i]:.3f}" if i < len(t) and np.isfinite(t[i]) else "")
            rows.append(row)
        return header, rows
