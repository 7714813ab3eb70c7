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
#: Rows of the results table for the energy balance of a sun traced with leaf optics:
#: Balance field -> the row's label.
BALANCE_ROWS = (("incident", "{band} incident W/m²"),
                ("absorbed_leaves", "absorbed by leaves W/m²"),
                ("absorbed_stalks", "absorbed by stalks W/m²"),
                ("absorbed_ground", "absorbed by the ground W/m²"),
                ("reflected_top", "reflected out of the top W/m²"),
                ("escaped_sides", "out of the sides W/m²"),
                ("unresolved", "still scattering at the depth limit W/m²"))
#: The results table's row of a sun's canopy gross CO2 assimilation (with a leaf model).
ASSIMILATION_ROW = "gross CO₂ µmol/m²/s"
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
    values: :class:`maizeviz_app.jobs.Diffuse`); for a sun traced with leaf optics, the light
    absorbed with scattering (:class:`maizeviz_app.jobs.Absorbed`). A sun's ``painting``
    (:class:`maizeviz.light.results.painting.SunPainting`, made with its classes) says how its light
    can be painted honestly: per triangle or per leaf. ``stalks``: the stalks took light
    (False: the leaves alone, ``maizeviz light --leaves-only``)."""

    label: str
    signature: tuple
    result: Any
    classes: np.ndarray | None = None
    kind: str = "sun"
    extra: Any = None
    painting: Any = None
    stalks: bool = True

    @property
    def name(self) -> str:
        """The run's column in the table and curve in the plot."""
        if self.kind == "sky":
            return f"{self.label}, {SKIES.get(self.result.sky.kind, ('', 'sky'))[1]}"
        if self.kind == "day":
            return f"{self.label}, day: PAR transmitted"
        return self.label

    @property
    def balance(self) -> Any:
        """The energy balance (:class:`maizeviz.light.results.absorbed.Balance`, W/m2 of
        ground) of a sun traced with leaf optics, else None."""
        light = getattr(self.extra, "light", None) if self.kind == "sun" else None
        return getattr(light, "balance", None)

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

    def take(self, other: LightRuns) -> None:
        """Hold ``other``'s runs, settings and sampling instead of its own (the same runs)."""
        self.runs, self.settings = dict(other.runs), dict(other.settings)
        self.sampling, self.last = other.sampling, other.last
        self._order, self._added = dict(other._order), other._added

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

    def with_plants(self) -> Run | None:
        """The latest result with light per leaf and per plant: a sky's, a day's, or a sun's
        traced with leaf optics (absorbed light, and its CO2 assimilation with a leaf model)
        once computed against its canopy."""
        runs = [r for r in self.in_order()
                if r.kind != "sun" or getattr(r.extra, "plant_rows", None) is not None]
        return runs[-1] if runs else None

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
        """Header and rows (one per height) of the results table; then, when a sun was traced
        with leaf optics, its energy balance (W/m2 of ground) in rows of their own, and with a
        leaf model the canopy's gross CO2 assimilation (umol per m2 of ground per s, with its
        Monte Carlo standard error)."""
        names = list(self.runs)
        header = ["height cm"] + names
        rows = []
        for i, h in enumerate(self.heights()):
            row = [f"{h:g}"]
            for name in names:
                t = self.runs[name].transmission
                row.append(f"{t[i]:.3f}" if i < len(t) and np.isfinite(t[i]) else "")
            rows.append(row)
        balances = {name: r.balance for name, r in self.runs.items() if r.balance is not None}
        if balances:
            band = next(r.extra.light.band for r in self.runs.values()
                        if r.balance is not None).upper()
            stalks = any(self.runs[name].stalks for name in balances)
            for field, what in BALANCE_ROWS:
                if field == "absorbed_stalks" and not stalks:   # leaves only: no such row
                    continue
                # the light still travelling when the scattering stopped: a row only when it
                # shows at one decimal, so that the rows shown add up to the incident light
                if field == "unresolved" and all(round(b.unresolved, 1) == 0
                                                 for b in balances.values()):
                    continue
                row = [what.format(band=band)]
                for name in names:
                    b = balances.get(name)
                    row.append(f"{getattr(b, field):.1f}" if b is not None else "")
                rows.append(row)
        gross = {name: r.extra.assimilation for name, r in self.runs.items()
                 if r.kind == "sun" and getattr(r.extra, "assimilation", None) is not None}
        if gross:                       # the levels' carbon side by side (the paper's question)
            row = [ASSIMILATION_ROW]
            for name in names:
                g = gross.get(name)
                se = g.canopy_gross_error_umol_m2_s if g is not None else None
                row.append("" if g is None else f"{g.canopy_gross_umol_m2_s:.2f}"
                           + (f" ± {se:.2f}" if se is not None else ""))
            rows.append(row)
        return header, rows


def plot_title(runs: LightRuns) -> str:
    """What the transmission plot compares: the sun, the sky, the day; rays per cm²."""
    parts = []
    sun, sky, day = (runs.of_kind(k) for k in ("sun", "sky", "day"))
    if sun is not None:
        r = sun.result
        parts.append(f"sun zenith {r.sun.zenith_deg:.1f}°, azimuth {r.sun.azimuth_deg:.1f}°")
    diffuse = sky.result.sky if sky is not None else \
        (day.result.sky.sky if day is not None and day.result.sky is not None else None)
    if diffuse is not None:
        parts.append(f"sky {diffuse.kind.upper()}, {diffuse.n} directions")
    if day is not None:
        p = day.result.period
        parts.append(f"day {p.start:%Y-%m-%d}, {p.n_steps} steps")
    density = runs.sampling[1] if runs.sampling else None
    if density is None and runs.last is not None:
        density = getattr(runs.last.result, "density", None)
    if density is not None:
        parts.append(f"{density:g} rays/cm²")
    return "; ".join(parts)


def value_legend(run: Run) -> tuple[str, str]:
    """Colour-bar title and unit of a sky's or day's light per leaf, or a sun's absorbed
    light per leaf triangle."""
    if run.kind == "sun":
        return f"{run.extra.light.band.upper()} absorbed per leaf area", "W/m² leaf"
    if run.kind == "day":
        return "PAR intercepted per leaf over the day", "mol/m² leaf"
    return "diffuse light per leaf area (1: the sky's on open ground)", ""


def assimilation_legend(run: Run) -> tuple[str, str]:
    """Colour-bar title and unit of a sun's gross CO2 assimilation per leaf."""
    model = run.extra.assimilation.model["model"].upper()
    return f"gross CO₂ assimilation per leaf area ({model})", "µmol/m² leaf/s"


def run_info(run: Run) -> str:
    """What was traced and how long it took, for the light panel."""
    r = run.result
    secs = r.seconds
    build_s = run.extra.build_s if run.kind != "sun" and run.extra is not None \
        else secs.get("build", 0)
    build = f"{build_s:.2f} s" if build_s > 0 else "kept from the last run"
    if run.kind == "sun":
        info = (f"{r.rays:,} rays on the central tile at {r.density_per_cm2:.2f} per cm²; "
                f"level {run.label}; Embree scene {build}, tracing "
                f"{secs.get('trace', 0) + secs.get('second', 0):.2f} s")
        share = r.sunlit_intercepted_fraction
        if share is not None:
            info += f"; leaves take {share:.1%} of the direct light"
            stalk_share = r.stalk_intercepted_fraction
            if run.stalks and stalk_share is not None:
                info += f", stalks {stalk_share:.1%}"
        if run.balance is not None:
            a = run.extra.light
            b = run.balance
            info += (f"; with leaf optics (ρ {a.optics.reflectance:g}, τ "
                     f"{a.optics.transmittance:g}, soil {a.optics.ground_reflectance:g}) the "
                     f"leaves absorb {a.fraction_absorbed:.1%} of the {a.band.upper()}, "
                     + (f"the stalks {b.absorbed_stalks / b.incident:.1%}, "
                        if run.stalks and b.incident else "")
                     + f"{b.reflected_top / b.incident if b.incident else 0:.1%} is reflected "
                     f"(balance closes within {abs(b.closure):.2%}: its rows in the table "
                     f"add up to the incident; scattering "
                     f"{a.seconds.get('scatter', 0):.2f} s)")
            g = getattr(run.extra, "assimilation", None)
            if g is not None:
                se = g.canopy_gross_error_umol_m2_s
                info += (f"; gross CO₂ assimilation ({g.model['model'].upper()} leaf model, "
                         f"{g.temp_c:g} °C) {g.canopy_gross_umol_m2_s:.2f}"
                         + (f" ± {se:.2f}" if se is not None else "")
                         + f" µmol/m² of ground/s = {g.canopy_gross_kg_co2_ha_h:.1f} kg "
                         f"CO₂/ha/h (net of leaf respiration {g.canopy_net_umol_m2_s:.2f} "
                         "µmol/m²/s)")
    elif run.kind == "sky":
        info = (f"{r.sky.description}; {r.rays:,} rays per direction; level {run.label}; "
                f"Embree scene {build}, tracing {secs.get('trace', 0):.2f} s; leaves "
                f"take {r.intercepted_fraction:.1%} of the diffuse light")
    else:
        sky = r.sky.sky.description if r.sky is not None else "no sky"
        if getattr(r, "diffuse", None) is not None:
            share = float(r.step_circumsolar_mol_m2.sum()) / max(
                float(r.step_diffuse_mol_m2.sum()), 1e-12)
            sky = (f"Perez anisotropic: {share:.0%} of the diffuse light circumsolar, with the "
                   f"sun; the rest from {sky}")
        info = (f"{r.n_steps} time steps and the sky ({sky}); {r.rays:,} rays per "
                f"direction; level {run.label}; Embree scene {build}, tracing "
                f"{secs.get('trace', 0):.2f} s")
    if not run.stalks:
        info += "; leaves only (the stalks let light through)"
    return info + "".join(f"\n⚠ {w}" for w in run_warnings(run) if "sun never rises" not in w)


def run_warnings(run: Run) -> list[str]:
    """What the command line warns of a result: the light's own warnings, then those of its
    CO2 assimilation (a leaf model's, e.g. leaves outside the rays' reach on an edited
    layout, whose assimilation is understated)."""
    out = list(run.result.warnings)
    assimilation = getattr(run.extra, "assimilation", None)
    for w in getattr(assimilation, "warnings", ()):
        text = f"CO₂ assimilation: {w}"
        if text not in out:
            out.append(text)
    return out


def day_summary(light) -> str:
    """The day in two lines: PAR incident, intercepted (fraction), transmitted to the lowest
    height, mol/m² of ground; and where the irradiance came from."""
    p = light.period
    frac = light.fraction_intercepted
    h = light.heights_cm
    low = int(np.argmin(h))
    where = "the ground" if h[low] == 0 else f"{h[low]:g} cm"
    t_low = float(light.par_transmitted_mol_m2[low])
    share = f" ({light.transmission_by_height[low]:.1%})" if frac is not None else ""
    return (f"{period_span(p)}: PAR incident {light.par_incident_mol_m2:.1f} mol/m² (direct "
            f"{light.par_direct_mol_m2:.1f}, diffuse {light.par_diffuse_mol_m2:.1f}); "
            f"intercepted {light.par_intercepted_mol_m2:.1f} mol/m²"
            + (f" ({frac:.1%})" if frac is not None else "")
            + f"; transmitted to {where} {t_low:.2f} mol/m²{share}\n{p.source}")


def period_span(p) -> str:
    """A period's span in words: its date for one whole day, else its start and end (the
    end's date too when it is not the start's: a three-day weather file is "2021-07-01
    00:00 to 2021-07-04 00:00", not "to 00:00")."""
    if (p.end - p.start).total_seconds() == 86400 and p.start.hour == 0 and \
            p.start.minute == 0:
        return f"{p.start:%Y-%m-%d}"
    if p.end.date() == p.start.date():
        return f"{p.start:%Y-%m-%d %H:%M} to {p.end:%H:%M}"
    return f"{p.start:%Y-%m-%d %H:%M} to {p.end:%Y-%m-%d %H:%M}"


def day_title(light, label: str) -> str:
    p = light.period
    return (f"{p.start:%Y-%m-%d %H:%M} to {p.end:%Y-%m-%d %H:%M} ({p.start.tz}); {p.source}; "
            f"level {label}")
