"""What the technician is told about the points themselves, press by press: a press far from
the point before it on the same leaf (a slipped stylus, a press on the wrong leaf), and a
cross-section with fewer points than the others that is not the leaf's tip (a row ended early
with ``r`` by mistake).

Pure functions over a session's history (``[(Position, (x, y, z) cm)]``, recorded points not
undone, in order); the app's digitizing session and the command line call them.
"""

from __future__ import annotations

import math

#: Distance (cm) from the previous point of the same leaf beyond which a press is said to be a
#: jump. On the bundled 3 x 3 block (7,650 points, 5 per cross-section) consecutive points of
#: one leaf are 2.3 cm apart at the median, 14.8 cm at the 99th percentile and 16.5 cm at most
#: (the step from a row's last margin point to the next row's first); a leaf's first point,
#: at the stalk, is 20-90 cm from the previous leaf's tip, so it is never compared. 30 cm is
#: about twice the largest step seen and half the 60-80 cm slips of issue 35.
JUMP_CM = 30.0


def jump(history: list[tuple], threshold: float = JUMP_CM) -> float | None:
    """The distance (cm) of the last point of ``history`` from the point before it, when both
    lie on the same leaf and it exceeds ``threshold``; else None."""
    if len(history) < 2:
        return None
    (p, a), (q, b) = history[-2], history[-1]
    if (p.plant, p.leaf) != (q.plant, q.leaf):
        return None
    d = math.dist(a, b)
    return d if d > threshold else None


def jump_message(history: list[tuple], distance: float, threshold: float = JUMP_CM) -> str:
    """What to tell the technician about a jump of ``distance`` cm at the last point."""
    q = history[-1][0]
    return (f"check: plant {q.plant} leaf {q.leaf} row {q.row} col {q.col} is {distance:.0f} cm "
            f"from the point before it on the same leaf (more than {threshold:.0f} cm is "
            "unusual); if the stylus slipped, press U and press again")


def short_sections(history: list[tuple], cols: int) -> list[tuple[int, int, int, int]]:
    """Cross-sections with fewer than ``cols`` points that are followed by another
    cross-section of the same leaf (so not its tip).

    Returns
    -------
    [(plant, leaf, row, points)] in recording order.
    """
    rows: dict[tuple[int, int], dict[int, int]] = {}
    for p, _ in history:
        rows.setdefault((p.plant, p.leaf), {}).setdefault(p.row, 0)
        rows[(p.plant, p.leaf)][p.row] += 1
    out = []
    for (plant, leaf), counts in rows.items():
        last = max(counts)
        out += [(plant, leaf, row, n) for row, n in sorted(counts.items())
                if row != last and n < cols]
    return out


def short_message(plant: int, leaf: int, row: int, points: int, cols: int) -> str:
    """A short cross-section in words."""
    return (f"check: plant {plant}, leaf {leaf}, section {row} has {points} point"
            f"{'' if points == 1 else 's'}, the others {cols}: a row ended early (R) before "
            "the tip? Only the tip's section may be shorter")
