"""Pictures of light over a period: PAR through the day and the transmission profile by height
(matplotlib's Agg canvas: no GUI toolkit; the app can show the same figure)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from maizeviz.light.results.diffuse import PeriodLight

if TYPE_CHECKING:                                   # matplotlib is imported when drawing
    from matplotlib.figure import Figure


def day_figure(light: PeriodLight, title: str = "", width_in: float = 11.0,
               dpi: int = 110) -> Figure:
    """Two panels: PAR flux (umol/m2/s) incident (direct, diffuse, total) and intercepted by the
    leaves at each time step; and the fraction of the period's PAR reaching each height (with
    the diffuse sky's transmission beside it)."""
    from matplotlib.dates import DateFormatter
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, width_in * 0.45), dpi=dpi)
    ax, bx = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.6, 1.0]})
    p = light.period
    if light.n_steps:
        secs = p.step_s
        times = p.times.tz_localize(None)           # local clock times on the axis
        umol = 1e6 / secs                           # mol/m2 per step -> umol/m2/s
        ax.plot(times, light.step_incident_mol_m2 * umol, color="tab:orange", lw=2,
                label="incident (direct + diffuse)")
        ax.plot(times, light.step_direct_mol_m2 * umol, color="tab:red", lw=1, ls="--",
                label="incident direct")
        ax.plot(times, light.step_diffuse_mol_m2 * umol, color="tab:blue", lw=1, ls="--",
                label="incident diffuse")
        ax.plot(times, light.step_intercepted_mol_m2 * umol, color="tab:green", lw=2,
                label="intercepted by the leaves")
        ax.xaxis.set_major_formatter(DateFormatter("%H:%M"))
        ax.legend(fontsize=8, loc="upper left")
    else:
        ax.text(0.5, 0.5, "the sun never rises in this period", ha="center", va="center",
                transform=ax.transAxes)
    ax.set_xlabel(f"local time ({p.times.tz if light.n_steps else p.start.tz})")
    ax.set_ylabel("PAR (umol m-2 s-1 of ground)")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    frac = light.fraction_intercepted
    ax.set_title(f"incident {light.par_incident_mol_m2:.1f} mol/m2 (direct "
                 f"{light.par_direct_mol_m2:.1f}, diffuse {light.par_diffuse_mol_m2:.1f}); "
                 f"intercepted {light.par_intercepted_mol_m2:.1f} mol/m2"
                 + (f" ({frac:.1%})" if frac is not None else ""), fontsize=9)

    h = light.heights_cm
    order = np.argsort(h)
    t = light.transmission_by_height
    bx.plot(t[order], h[order], "o-", color="tab:green", label="PAR of the period")
    if light.sky is not None and light.diffuse is not None:
        bx.plot(light.diffuse_transmission_by_height[order], h[order], "s--",
                color="tab:blue", ms=4, label="diffuse PAR (Perez sky)")
    elif light.sky is not None:
        bx.plot(light.sky.transmission[order], h[order], "s--", color="tab:blue", ms=4,
                label="diffuse sky alone")
    for hk, tk in zip(h, t):
        if np.isfinite(tk):
            bx.annotate(f"{tk:.3f}", (tk, hk), textcoords="offset points", xytext=(6, -3),
                        fontsize=7)
    bx.set_xlim(0, 1.05)
    bx.set_ylim(bottom=0)
    bx.set_xlabel("fraction of incident PAR reaching the height")
    bx.set_ylabel("height (cm)")
    bx.grid(alpha=0.3)
    bx.legend(fontsize=8, loc="lower right")
    bx.set_title("transmission profile (sensor planes)", fontsize=9)
    if title:
        import textwrap

        fig.suptitle("\n".join(textwrap.wrap(title, 150)), fontsize=9)
    fig.tight_layout()
    return fig
