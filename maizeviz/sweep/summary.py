"""The question the paper asked, for every canopy of a sweep: how coarse may the mesh be?

For each canopy (points file x arrangement x area rule x ray density x periodic setting) and
each sun, the *finest* level is the one with the most triangles; a level is *within tolerance*
when its transmission differs from the finest level's by at most ``tolerance`` at every height.
The answer is the cheapest level (fewest triangles) within tolerance, per sun and over all suns
at once ("all suns": within tolerance for every sun the finest level was computed for).

Scenarios with photosynthesis carry the paper's question on to carbon: the cheapest level whose
canopy gross assimilation is within ``assimilation_tolerance`` (1 %) of the finest level's
(``assimilation_cheapest_level``, and its relative difference).
"""

from __future__ import annotations

import csv

from maizeviz.io.atomic import atomic_open
from maizeviz.sweep.spec import arrangement_label, sun_label

DEFAULT_TOLERANCE = 0.02
#: Relative difference of canopy assimilation from the finest level's a level may have.
ASSIMILATION_TOLERANCE = 0.01

SUMMARY_COLUMNS = ("points", "arrangement", "preserve_area", "density", "periodic", "optics",
                   "sun",
                   "levels", "finest_level", "finest_triangles", "cheapest_level",
                   "cheapest_triangles", "triangle_fraction", "max_abs_difference",
                   "tolerance", "photosynthesis", "assimilation_cheapest_level",
                   "assimilation_cheapest_triangles", "assimilation_max_rel_difference",
                   "assimilation_tolerance")


def _arrangement(r: dict) -> str:
    return arrangement_label(r.get("layout"), r.get("tile"), r.get("row_spacing"),
                             r.get("plant_spacing"))


def _optics(r: dict) -> str:
    """Leaf optics in words (the result's ``optics`` column: every setting that changes the
    numbers; "black" for interception)."""
    return r.get("optics") or "black"


def _sun(r: dict) -> str:
    return sun_label(r["sun_zenith_deg"], r["sun_azimuth_deg"], r.get("sun_when"))


def summarize(rows: list[dict], tolerance: float = DEFAULT_TOLERANCE) -> list[dict]:
    """Summary rows (:data:`SUMMARY_COLUMNS`) from result rows (status "ok" only).

    ``max_abs_difference`` is the cheapest level's largest |T - T_finest| over the heights
    (and the suns, for the "all suns" row); ``triangle_fraction`` its triangles / the finest's.
    """
    # canopy -> sun -> level -> (triangles, {height: T})
    tree: dict = {}
    for r in rows:
        if r.get("status") != "ok" or r.get("transmission") is None:
            continue
        canopy = (r["points"], _arrangement(r), r["preserve_area"], r["density"], r["periodic"],
                  _optics(r), r.get("photosynthesis") or "none")
        per_level = tree.setdefault(canopy, {}).setdefault(_sun(r), {})
        tri, ts = per_level.setdefault(r["level"], (r["triangles"], {}))
        ts[r["height_cm"]] = r["transmission"]
        if r.get("canopy_gross_umol_m2_s") is not None:
            ts["assimilation"] = r["canopy_gross_umol_m2_s"]
    out = []
    for canopy, suns in tree.items():
        overall: dict[str, float] = {}          # level -> worst difference over suns
        tri_of: dict[str, int] = {}
        counted: dict[str, int] = {}
        n_suns = 0
        for sun, levels in suns.items():
            finest = max(levels, key=lambda lv: levels[lv][0])
            f_tri, f_t = levels[finest]
            diffs, carbon = {}, {}
            for lv, (tri, ts) in levels.items():
                if "assimilation" in ts and f_t.get("assimilation"):
                    carbon[lv] = abs(ts["assimilation"] / f_t["assimilation"] - 1.0)
                common = (set(ts) & set(f_t)) - {"assimilation"}
                diffs[lv] = max((abs(ts[h] - f_t[h]) for h in common), default=float("inf"))
                tri_of[lv] = tri
                overall[lv] = max(overall.get(lv, 0.0), diffs[lv])
                counted[lv] = counted.get(lv, 0) + 1
            n_suns += 1
            out.append(_row(canopy, sun, levels.keys(), finest, f_tri, diffs, tri_of, tolerance,
                            carbon))
        if n_suns > 1:
            # a level missing for some sun cannot be vouched for over all suns
            worst = {lv: d if counted[lv] == n_suns else float("inf")
                     for lv, d in overall.items()}
            finest = max(tri_of, key=lambda lv: tri_of[lv])
            out.append(_row(canopy, f"all {n_suns} suns", tri_of.keys(), finest, tri_of[finest],
                            worst, tri_of, tolerance))
    return out


def _row(canopy, sun, levels, finest, f_tri, diffs, tri_of, tolerance, carbon=None) -> dict:
    ok = [lv for lv in levels if diffs[lv] <= tolerance + 1e-12]
    cheapest = min(ok, key=lambda lv: tri_of[lv])
    points, arrangement, preserve, density, periodic, optics, photosynthesis = canopy
    c_level = c_tri = c_diff = None
    if carbon:
        c_ok = [lv for lv in carbon if carbon[lv] <= ASSIMILATION_TOLERANCE + 1e-12]
        c_level = min(c_ok, key=lambda lv: tri_of[lv])
        c_tri, c_diff = tri_of[c_level], carbon[c_level]
    return {"photosynthesis": photosynthesis, "assimilation_cheapest_level": c_level,
            "assimilation_cheapest_triangles": c_tri, "assimilation_max_rel_difference": c_diff,
            "assimilation_tolerance": ASSIMILATION_TOLERANCE if carbon else None,
            "points": points, "arrangement": arrangement, "preserve_area": preserve,
            "density": density, "periodic": periodic, "optics": optics, "sun": sun,
            "levels": len(list(levels)), "finest_level": finest, "finest_triangles": f_tri,
            "cheapest_level": cheapest, "cheapest_triangles": tri_of[cheapest],
            "triangle_fraction": tri_of[cheapest] / f_tri if f_tri else float("nan"),
            "max_abs_difference": diffs[cheapest], "tolerance": tolerance}


def format_summary(summary: list[dict]) -> str:
    """A small table: one line per canopy and sun."""
    if not summary:
        return "summary: no canopy has results to compare"
    head = ["points", "arrangement", "density", "sun", "finest", "cheapest within tol",
            "triangles", "max |dT|"]
    rows = [[s["points"], s["arrangement"] + ("" if s["preserve_area"] else ", widths unscaled")
             + (", periodic" if s["periodic"] else "")
             + ("" if s.get("optics", "black") == "black" else f", {s['optics']}"),
             f"{s['density']:g}", s["sun"],
             s["finest_level"], s["cheapest_level"],
             f"{s['cheapest_triangles']:,} ({s['triangle_fraction']:.1%})",
             f"{s['max_abs_difference']:.4f}"] for s in summary]
    if any(s.get("assimilation_cheapest_level") for s in summary):
        head.append("cheapest within 1 % of its carbon")
        for row, s in zip(rows, summary):
            lv = s.get("assimilation_cheapest_level")
            row.append("" if lv is None else
                       f"{lv} ({s['assimilation_max_rel_difference']:.2%}, {s['photosynthesis']})")
    cells = [head] + rows
    widths = [max(len(str(r[i])) for r in cells) for i in range(len(head))]
    lines = ["  ".join(str(c).ljust(w) for c, w in zip(r, widths)).rstrip() for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    tol = summary[0]["tolerance"]
    return (f"cheapest level whose transmission is within {tol:g} of the finest level's at "
            "every height:\n" + "\n".join(lines))


def write_summary(path, summary: list[dict]) -> None:
    """``summary.csv`` (atomically)."""
    with atomic_open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=SUMMARY_COLUMNS, lineterminator="\n")
        w.writeheader()
        w.writerows(summary)
