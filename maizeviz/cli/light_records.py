"""The records of ``maizeviz light``: each result (a sun, a sky, a period, absorbed light,
photosynthesis) as the dict its ``--json`` prints, and the tables printed from them.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.cli.common import fmt_table, say
from maizeviz.cli.stalk_light import stalk_line
from maizeviz.light.report.beer_lambert import BeerLambert, beer_lambert, beer_lambert_sky, clumping
from maizeviz.light.results.absorbed import AbsorbedLight
from maizeviz.light.results.diffuse import PeriodLight, SkyLight
from maizeviz.light.results.direct import LightResult
from maizeviz.light.sources.irradiance import PAR_UMOL_PER_J_PAR
from maizeviz.light.sources.perez import split_summary
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.precision import trace_until


def absorbed_record(ab: AbsorbedLight, canopy: Canopy) -> dict[str, Any]:
    """The absorbed light of a level for the JSON output (balance in W/m2 of ground)."""
    o = ab.optics
    out: dict[str, Any] = {
        "band": ab.band, "units": "W/m2 of ground",
        "optics": {"reflectance": o.reflectance, "transmittance": o.transmittance,
                   "ground_reflectance": o.ground_reflectance},
        "fraction_absorbed": ab.fraction_absorbed,
        "sunlit_lai": _sunlit_m2(ab, canopy),
        "rays": ab.rays, "directions": ab.directions, "depth": ab.depth, "seed": ab.seed,
        "scatterings": ab.events}
    se = ab.absorbed_leaves_error
    out["absorbed_leaves_se"] = se
    if ab.band == "par":
        out["absorbed_leaves_umol_m2_s"] = ab.balance.absorbed_leaves * PAR_UMOL_PER_J_PAR
        out["absorbed_leaves_umol_m2_s_se"] = None if se is None else se * PAR_UMOL_PER_J_PAR
    return out


def absorbed_period_record(ab) -> dict[str, Any]:
    """Absorbed light over a period for the JSON output (balance in MJ/m2 of ground)."""
    o = ab.optics
    out: dict[str, Any] = {
        "band": ab.band, "units": "MJ/m2 of ground",
        "optics": {"reflectance": o.reflectance, "transmittance": o.transmittance,
                   "ground_reflectance": o.ground_reflectance},
        "fraction_absorbed": ab.fraction_absorbed, "rays": ab.rays, "depth": ab.depth,
        "seed": ab.seed,
        "step_absorbed_leaves_w_m2": [float(w) for w in ab.step_absorbed_leaves_w_m2],
        "step_incident_w_m2": [float(w) for w in ab.step_incident_w_m2]}
    se = ab.absorbed_leaves_error
    out["absorbed_leaves_se"] = se
    if ab.band == "par":
        out["par_source"] = ab.period.par_source       # as the intercepted period's
        out["absorbed_leaves_mol_m2"] = ab.absorbed_leaves_mol_m2
        out["absorbed_leaves_mol_m2_se"] = None if se is None else se * PAR_UMOL_PER_J_PAR
    return out


def warn_unresolved(balance, depth: int, rec: dict[str, Any], said: set[str]) -> None:
    """Warn when more than 1 % of the incident light was left unresolved."""
    from maizeviz.light.results.absorbed import UNRESOLVED_WARN, unresolved_warning

    if balance.incident and balance.unresolved > UNRESOLVED_WARN * balance.incident:
        w = unresolved_warning(balance.unresolved / balance.incident, depth)
        rec["warnings"].append(w)
        if w not in said:
            said.add(w)
            say(f"warning: {w}")


def _percent(fraction: float) -> str:
    """A fraction as a percentage with three significant digits, however small (``:.2%``
    wrote a target of 1e-6 as "0.00%")."""
    return f"{100 * fraction:.3g}%"


def traced(trace, args: argparse.Namespace, rec: dict[str, Any], said: set[str]) -> Any:
    """``trace(density)``'s result at ``--density``, or with ``--precision`` at the density
    that meets it (recorded in ``rec["precision"]``, a warning when it cannot be)."""
    if args.precision is None:
        return trace(args.density)[0]
    result, prec = trace_until(trace, args.density, args.precision)
    rec["precision"] = prec.as_dict()
    bias = ("+" if prec.bias >= 0 else "-") + _percent(abs(prec.bias))
    say(f"precision: relative standard error {_percent(prec.achieved)}, bias from the density "
        f"{bias} at {prec.density:g} rays per cm2 after {prec.passes} "
        f"trace{'s' if prec.passes > 1 else ''}")
    problems = []
    if not prec.noise_met:
        problems.append(f"the relative standard error {_percent(prec.achieved)} is above the "
                        f"{_percent(prec.target)} asked for")
    if not prec.bias_met:
        problems.append(f"the bias from the density, {bias} +- {_percent(prec.bias_se)}, "
                        f"is above the {_percent(prec.target)} asked for")
    for problem in problems:
        w = f"{problem} at the densest tracing allowed ({prec.density:g} rays per cm2)"
        said.add(w)
        say(f"warning: {w}")
        rec["warnings"].append(w)
    return result


def assimilation_rows(canopy: Canopy, asm: Any) -> list[dict]:
    """Leaf rows of a result's leaf table (an Assimilation, PeriodAssimilation or
    AbsorbedPeriod) for the command line's leaf table."""
    frame = asm.table("leaf", canopy)
    return [] if frame.empty else frame.to_dict("records")


def merge(into: dict[int, dict[str, float]], more: dict[int, dict[str, float]]) -> None:
    for k, v in more.items():
        into.setdefault(k, {}).update(v)


def plant_errors(canopy: Canopy, result: Any) -> dict[int, dict[str, float]]:
    """Standard errors per plant (instance): columns ending ``_se`` of ``result``'s plant
    table (absorbed light or assimilation)."""
    frame = result.table("plant", canopy)
    cols = [c for c in frame.columns if c.endswith("_se")]
    return {int(r["instance"]): {c: float(r[c]) for c in cols}
            for r in frame.to_dict("records")}


def _sunlit_m2(ab: AbsorbedLight, canopy: Canopy) -> float:
    """Sunlit leaf area (m2) per m2 of sample ground: the sunlit leaf area index."""
    x0, y0, x1, y1 = ab.rect
    return float(ab.triangle_sunlit_cm2[:canopy.n_triangles].sum()) / ((x1 - x0) * (y1 - y0))


def sun_record(res: LightResult, sun: Sun, canopy: Canopy, args: argparse.Namespace,
                heights: tuple[float, ...]) -> dict[str, Any]:
    rec: dict[str, Any] = {
        "sun": {"zenith_deg": sun.zenith_deg, "azimuth_deg": sun.azimuth_deg,
                "when": sun.when or None},
        "transmission": [float(t) for t in res.transmission], "rays": res.rays,
        "density_per_cm2": res.density_per_cm2, "rect_cm": list(res.rect)}
    if args.check:
        rec["beer_lambert"] = _beer_lambert_record(beer_lambert(canopy, sun, heights))
    if res.sunlit_intercepted_fraction is not None:
        rec["sunlit_intercepted_fraction"] = res.sunlit_intercepted_fraction
    return rec


def sky_record(sky: SkyLight, canopy: Canopy, args: argparse.Namespace,
                heights: tuple[float, ...]) -> dict[str, Any]:
    x0, y0, x1, y1 = sky.rect
    rec: dict[str, Any] = {
        "sky": sky.sky.kind, "split": sky.sky.split, "directions": sky.sky.n,
        "description": sky.sky.description, "heights_cm": [float(h) for h in sky.heights_cm],
        "transmission": [float(t) for t in sky.transmission],
        "intercepted_fraction": sky.intercepted_fraction, "rays_per_direction": sky.rays,
        "density_per_cm2": sky.rays / ((x1 - x0) * (y1 - y0)), "rect_cm": list(sky.rect),
        "weights": [float(w) for w in sky.sky.weights],
        "zenith_deg": [float(z) for z in sky.sky.zenith_deg],
        "azimuth_deg": [float(a) for a in sky.sky.azimuth_deg]}
    if args.check:
        rec["beer_lambert"] = _beer_lambert_record(beer_lambert_sky(canopy, sky.sky, heights))
    return rec


def _beer_lambert_record(bl: BeerLambert) -> dict[str, Any]:
    return {"G": bl.G, "lai_above": [float(v) for v in bl.lai_above],
            "transmission": [float(v) for v in bl.transmission]}


def period_record(pl: PeriodLight, args: argparse.Namespace) -> dict[str, Any]:
    p = pl.period
    rec: dict[str, Any] = {
        "start": p.start.isoformat(), "end": p.end.isoformat(), "steps": p.n_steps,
        "step_min": None if args.weather else (30.0 if args.step is None else args.step),
        "par_umol_per_j": p.par_umol_per_j, "par_source": p.par_source,
        "shortwave_mj_m2": p.shortwave_mj_m2,
        "par_incident_mol_m2": pl.par_incident_mol_m2,
        "par_direct_mol_m2": pl.par_direct_mol_m2,
        "par_diffuse_mol_m2": pl.par_diffuse_mol_m2,
        "par_intercepted_mol_m2": pl.par_intercepted_mol_m2,
        "fraction_intercepted": pl.fraction_intercepted,
        "par_diffuse_intercepted_mol_m2": pl.par_diffuse_intercepted_mol_m2,
        "transmission_by_height": {
            "heights_cm": [float(h) for h in pl.heights_cm],
            "par_mol_m2": [float(v) for v in pl.par_transmitted_mol_m2],
            "fraction": [None if not math.isfinite(v) else float(v)
                         for v in pl.transmission_by_height],
            "diffuse_fraction": [None if not math.isfinite(v) else float(v)
                                 for v in pl.diffuse_transmission_by_height]},
        "source": p.source, "notes": list(p.notes)}
    d = pl.diffuse
    if d is not None:
        rec["diffuse_model"] = {
            "model": d.model, "description": d.description,
            "isotropic_par_mol_m2": math.fsum(pl.step_sky_mol_m2),
            "circumsolar_par_mol_m2": math.fsum(pl.step_circumsolar_mol_m2),
            "horizon_par_mol_m2": 0.0,
            "summary": split_summary(d, p)}
    if args.weather:
        rec["weather_file"] = str(args.weather)
        rec["weather"] = dict(p.parameters)
    else:
        rec["clear_sky_model"] = dict(p.parameters)
    return rec


def jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


# ------------------------------------------------------------------------------ tables
def print_tables(records: list[dict], sun: Sun | None, heights: tuple[float, ...],
                  args: argparse.Namespace) -> None:
    r0 = records[0]
    if sun is not None:
        _print_sun(records, sun, heights, args)
    if r0.get("diffuse"):
        _print_sky(records, heights, args)
    if "period" in r0:
        for r in records:
            _print_period(r, len(records) > 1)
    if "balance" in r0:
        _print_balance(records)
    line = stalk_line(records)
    if line:
        print(line)
    if r0.get("photosynthesis"):
        _print_photosynthesis(records)
    print()
    t_ref = _cost(r0)
    cols = ["level", "triangles", "canopy s", "scene s"]
    cols += ["trace s"] if sun is not None else []
    cols += ["sky s"] if "sky" in r0["seconds"] else []
    cols += ["period s"] if "period" in r0["seconds"] else []
    cols += ["absorbed s"] if "scatter" in r0["seconds"] else []
    cols += ["scene+trace vs first"]
    rows = []
    for r in records:
        sec = r["seconds"]
        row = [r["level"], r["triangles"], f"{sec['canopy']:.2f}", f"{sec['scene']:.2f}"]
        if sun is not None:
            row.append(f"{sec['trace']:.3f}")
        if "sky" in sec:
            row.append(f"{sec['sky']:.2f}")
        if "period" in sec:
            row.append(f"{sec['period']:.2f}")
        if "scatter" in r0["seconds"]:
            row.append(f"{sec.get('scatter', 0.0):.2f}")
        row.append(f"{_cost(r) / t_ref:.0%}" if t_ref > 0 else "")
        rows.append(row)
    print(fmt_table(cols, rows))


def _cost(r: dict) -> float:
    sec = r["seconds"]
    return (sec["scene"] + sec.get("trace", 0.0) + sec.get("sky", 0.0)
            + sec.get("period", 0.0) + sec.get("scatter", 0.0))


def _print_sun(records: list[dict], sun: Sun, heights: tuple[float, ...],
               args: argparse.Namespace) -> None:
    r0 = records[0]
    rc = ", ".join(f"{v:.1f}" for v in r0["rect_cm"])
    print(f"direct light: {r0['rays']:,} sensors per plane over x0,y0,x1,y1 = {rc} cm "
          f"({r0['density_per_cm2']:.2f} per cm2), sun zenith {sun.zenith_deg:.2f} deg, "
          f"azimuth {sun.azimuth_deg:.2f} deg{', periodic field' if args.periodic else ''}")
    _print_heights(heights, [(r["level"], r["transmission"]) for r in records],
                   r0["beer_lambert"] if args.check else None)
    if args.check:
        bl = r0["beer_lambert"]
        omega = clumping(r0["transmission"][0], bl["transmission"][0])
        print(f"Beer-Lambert with G = {bl['G']:.3f} and L(h) from the {r0['level']} "
              f"mesh; effective clumping at {heights[0]:g} cm: ln T / ln T_BL = {omega:.2f} "
              "(1: random foliage; below 1: clumped, T above Beer-Lambert, as in most row "
              "crops (0.7-1); above 1: more regular than random)")
    print()


def _print_sky(records: list[dict], heights: tuple[float, ...],
               args: argparse.Namespace) -> None:
    d0 = records[0]["diffuse"]
    rc = ", ".join(f"{v:.1f}" for v in d0["rect_cm"])
    part = f" (the {d0['part']}; its circumsolar part follows the sun)" if "part" in d0 else ""
    print(f"diffuse light: {d0['description']}{part}; {d0['rays_per_direction']:,} sensors per "
          f"plane and direction over x0,y0,x1,y1 = {rc} cm"
          f"{', periodic field' if args.periodic else ''}")
    _print_heights(heights, [(f"{r['level']} diffuse T", r["diffuse"]["transmission"])
                             for r in records],
                   d0["beer_lambert"] if args.check else None)
    print("leaves intercept " + ", ".join(
        f"{r['diffuse']['intercepted_fraction']:.3f}" + (f" ({r['level']})" if len(records) > 1
                                                         else "")
        for r in records) + (" of this sky's light" if "part" in d0 else " of the diffuse light")
          + " (first hits; scattering not followed)")
    if args.check:
        bl = d0["beer_lambert"]
        print(f"Beer-Lambert under the same sky: sum of w_i exp(-G_i L(h)/cos theta_i), G_i "
              f"from the {records[0]['level']} mesh (weighted mean {bl['G']:.3f})")
    print()


def _print_heights(heights: tuple[float, ...], columns: list[tuple[str, list[float]]],
                   bl: dict | None) -> None:
    """Transmission by height: a column per (name, transmission) and, when ``bl`` (a Beer-Lambert
    record) is given, Beer-Lambert's."""
    head = ["height cm"] + [name for name, _ in columns]
    head += ["Beer-Lambert"] if bl is not None else []
    rows = []
    for i, h in enumerate(heights):
        row = [f"{h:g}"] + [f"{t[i]:.3f}" for _, t in columns]
        if bl is not None:
            row.append(f"{bl['transmission'][i]:.3f}")
        rows.append(row)
    print(fmt_table(head, rows))


def _print_period(r: dict, label: bool) -> None:
    p = r["period"]
    print(f"period{' (' + r['level'] + ')' if label else ''}: {p['start']} to {p['end']}, "
          f"{p['steps']} time steps with the sun up")
    print(f"irradiance: {p['source']}")
    par = "PAR measured (the weather file's par column)" if p["par_source"] == "measured" \
        else f"PAR = {p['par_umol_per_j']:.4g} umol per J of shortwave"
    print(f"{par}; shortwave {p['shortwave_mj_m2']:.2f} MJ/m2")
    frac = p["fraction_intercepted"]
    if not p["steps"]:
        print("no sunlight in this period: incident, intercepted and transmitted PAR are 0")
        return
    inc = p["par_incident_mol_m2"]
    print(f"PAR incident {inc:.2f} mol/m2 of ground (direct {p['par_direct_mol_m2']:.2f}, "
          f"diffuse {p['par_diffuse_mol_m2']:.2f}, {p['par_diffuse_mol_m2'] / inc:.0%} "
          f"diffuse); intercepted by the leaves {p['par_intercepted_mol_m2']:.2f} mol/m2 "
          f"({frac:.1%})")
    tb = p["transmission_by_height"]
    diffuse = r.get("diffuse") or {}
    model = p.get("diffuse_model")
    if model is not None:
        print(model["summary"])
        print(f"diffuse PAR intercepted by the leaves {p['par_diffuse_intercepted_mol_m2']:.3f} "
              f"mol/m2 of {p['par_diffuse_mol_m2']:.3f}")
        dt = tb["diffuse_fraction"]
        diffuse_t = [f"{v:.3f}" if v is not None else "" for v in dt]
    else:
        diffuse_t = [f"{v:.3f}" for v in diffuse["transmission"]] if diffuse else \
            [""] * len(tb["heights_cm"])
    print(fmt_table(["height cm", "PAR mol/m2", "fraction", "diffuse T"],
                    [[f"{h:g}", f"{v:.2f}", f"{f:.3f}" if f is not None else "", diffuse_t[i]]
                     for i, (h, v, f) in enumerate(zip(tb["heights_cm"], tb["par_mol_m2"],
                                                       tb["fraction"]))]))
    print()


def _print_photosynthesis(records: list[dict]) -> None:
    """Canopy gross assimilation per level, with its Monte Carlo standard error."""
    ph = records[0]["photosynthesis"]
    period = "canopy_gross_mol_m2" in ph
    params = ", ".join(f"{k} {v:g}" for k, v in ph["parameters"].items()
                       if k in ("vmax", "alpha", "co2_ppm", "amax", "eff"))
    print(f"\ngross CO2 assimilation, {ph['label']} ({params}), per m2 of ground"
          + ("" if period else f", leaves at {ph['temperature_c']:g} C") + ":")
    rows = []
    for r in records:
        p = r["photosynthesis"]
        if period:
            se = p["canopy_gross_mol_m2_se"] or 0.0
            rows.append([r["level"], f"{p['canopy_gross_mol_m2']:.4f} +- {se:.4f}",
                         f"{p['canopy_gross_g_co2_m2']:.2f} +- {se * 44.0095:.2f}"])
        else:
            se = p["canopy_gross_umol_m2_s_se"] or 0.0
            rows.append([r["level"], f"{p['canopy_gross_umol_m2_s']:.2f} +- {se:.2f}",
                         f"{p['canopy_gross_kg_co2_ha_h']:.2f} +- "
                         f"{p['canopy_gross_kg_co2_ha_h_se'] or 0.0:.2f}"])
    print(fmt_table(["level", "mol CO2/m2" if period else "umol CO2/m2/s",
                     "g CO2/m2" if period else "kg CO2/ha/h"], rows))


def _print_balance(records: list[dict]) -> None:
    """Absorbed light with scattering: the energy balance per level, W/m2 of ground (MJ/m2
    over a period, with the PAR the leaves absorbed in mol/m2)."""
    ab = records[0]["absorbed"]
    o = ab["optics"]
    period = ab["units"].startswith("MJ")
    measured = "; PAR measured (the weather file's par column)" \
        if ab.get("par_source") == "measured" else ""
    print(f"\nabsorbed {ab['band'].upper()} with scattering (leaf reflectance "
          f"{o['reflectance']:g}, transmittance {o['transmittance']:g}, ground "
          f"{o['ground_reflectance']:g}), {ab['units']}{measured}:")
    # the stalks' share is a column of the balance when any level traced them: without it
    # the row's parts did not add up to its incident light, though its closure was 0.01 %
    stalks = any(r["balance"].get("absorbed_stalks") for r in records)
    rows = []
    for r in records:
        b = r["balance"]
        mol = r["absorbed"].get("absorbed_leaves_mol_m2")
        last = ("-" if mol is None else f"{mol:.2f}") if period else \
            f"{r['absorbed']['sunlit_lai']:.2f}"
        rows.append([r["level"], f"{b['incident']:.2f}", f"{b['absorbed_leaves']:.2f}",
                     *([f"{b.get('absorbed_stalks', 0.0):.2f}"] if stalks else []),
                     f"{b['absorbed_ground']:.2f}", f"{b['reflected_top']:.2f}",
                     f"{b['escaped_sides'] + b['unresolved']:.2f}",
                     f"{b['closure_fraction']:+.2%}", last])
    print(fmt_table(["level", "incident", "leaves", *(["stalks"] if stalks else []), "ground",
                     "reflected", "other", "closure (of incident)",
                     "PAR mol/m2" if period else "sunlit LAI"], rows))

