"""Leaf and soil optics per waveband: how much light a leaf reflects and transmits, and the
ground reflects, in PAR (400-700 nm) and near infrared (700-3000 nm).

Leaves and soil are Lambertian here: what they reflect or transmit leaves in a cosine
distribution about the surface normal, whatever the direction it came from. A leaf reflects
to the side the light came from and transmits to the other side; both sides alike.

Defaults (maize, from measured spectra; the same values scatter models of crops use):

========  ===========  =============  ==================  ============================
band      reflectance  transmittance  ground reflectance  share of shortwave (global)
========  ===========  =============  ==================  ============================
``par``   0.10         0.05           0.10                0.48 (``PAR_FRACTION``)
``nir``   0.45         0.40           0.25                0.52 (the rest)
========  ===========  =============  ==================  ============================

A leaf's scattering coefficient (reflectance + transmittance) is then 0.15 in PAR, the value
de Pury & Farquhar (1997) use, and 0.85 in NIR (Goudriaan 1977: about 0.8).

References
----------
Walter-Shea, E. A., Norman, J. M. & Blad, B. L. (1989). Leaf bidirectional reflectance and
transmittance in corn and soybean. Remote Sensing of Environment 29, 161-174.
Goudriaan, J. (1977). Crop Micrometeorology: a Simulation Study. Pudoc, Wageningen.
de Pury, D. G. G. & Farquhar, G. D. (1997). Simple scaling of photosynthesis from leaves to
canopies without the errors of big-leaf models. Plant, Cell & Environment 20, 537-557.
Jacquemoud, S. & Baret, F. (1990). PROSPECT: a model of leaf optical properties spectra.
Remote Sensing of Environment 34, 75-91.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from maizeviz.errors import MaizevizError
from maizeviz.light.sources.irradiance import (
    DEFAULT_PAR_UMOL_PER_J,
    PAR_FRACTION,
    PAR_UMOL_PER_J_PAR,
)
from maizeviz.numbers import number, whole

#: Wavebands traced: photosynthetically active radiation and near infrared.
BANDS = ("par", "nir")
#: Share of global shortwave irradiance in each band.
SHORTWAVE_SHARE = {"par": PAR_FRACTION, "nir": 1.0 - PAR_FRACTION}


def band_share(band: str, par_umol_per_j: float = DEFAULT_PAR_UMOL_PER_J) -> float:
    """Share of global shortwave irradiance in ``band`` when PAR brings ``par_umol_per_j``
    umol of photons per J of shortwave: PAR's share is that factor over the photons per J of
    PAR (4.57), the near infrared the rest. With the default factor these are
    :data:`SHORTWAVE_SHARE`, exactly (0.48 and 0.52).

    Parameters
    ----------
    band : {"par", "nir"}
        The waveband.
    par_umol_per_j : float
        PAR photons per joule of shortwave [umol J-1] (a period's ``par_umol_per_j``).

    Returns
    -------
    float
        The band's share of shortwave irradiance, in [0, 1].

    Raises
    ------
    MaizevizError
        A factor above 4.57 umol/J: PAR would carry more than the whole shortwave.
    """
    par = par_umol_per_j / PAR_UMOL_PER_J_PAR
    if not 0.0 < par <= 1.0:
        raise MaizevizError(f"a PAR factor of {par_umol_per_j:g} umol per J of shortwave puts "
                            f"more than the whole shortwave in PAR (at most "
                            f"{PAR_UMOL_PER_J_PAR:g}, the photons in a J of PAR)",
                            quantity="par_factor")
    return par if band == "par" else 1.0 - par


@dataclass(frozen=True)
class Optics:
    """Lambertian optics of the leaves and the ground in one band.

    Attributes
    ----------
    reflectance, transmittance : leaf, fractions in [0, 1] with a sum <= 1
    ground_reflectance : soil, fraction in [0, 1]
    band : ``"par"`` or ``"nir"`` (names the results' units)
    ranks : ((rank, reflectance, transmittance), ...): leaves of these ranks (1: the lowest
        leaf of a plant) take their own values (older, lower leaves are often paler); the
        others take ``reflectance`` and ``transmittance``; stalks too
    """

    reflectance: float
    transmittance: float
    ground_reflectance: float
    band: str = "par"
    ranks: tuple[tuple[int, float, float], ...] = ()

    def __post_init__(self) -> None:
        for name in ("reflectance", "transmittance", "ground_reflectance"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                    not math.isfinite(value) or not 0.0 <= value <= 1.0:
                raise MaizevizError(f"the {name.replace('_', ' ')} must be a number from 0 to "
                                    f"1, got {value!r}", quantity=name)
            object.__setattr__(self, name, float(value))
        if self.reflectance + self.transmittance > 1.0 + 1e-12:
            raise MaizevizError(f"a leaf cannot reflect and transmit more than it receives: "
                                f"reflectance {self.reflectance:g} + transmittance "
                                f"{self.transmittance:g} > 1", quantity="transmittance")
        if self.band not in BANDS:
            raise MaizevizError(f"unknown band '{self.band}' (known: {', '.join(BANDS)})",
                                quantity="band")
        ranks = []
        for row in self.ranks:
            if not isinstance(row, (tuple, list)) or len(row) != 3:
                raise MaizevizError(f"a row of the optics table must be (rank, reflectance, "
                                    f"transmittance), got {str(row)[:60]}",
                                    quantity="optics_table")
            rank, rho, tau = row
            if isinstance(rank, bool) or not isinstance(rank, int) or not 1 <= rank <= 10_000:
                raise MaizevizError(f"a leaf rank must be a whole number from 1 to 10000, got "
                                    f"{rank!r}", quantity="optics_table")
            leaf = Optics(rho, tau, self.ground_reflectance, self.band)    # checked alike
            ranks.append((rank, leaf.reflectance, leaf.transmittance))
        if len({r for r, _, _ in ranks}) != len(ranks):
            raise MaizevizError("a leaf rank appears twice in the optics table",
                                quantity="optics_table")
        object.__setattr__(self, "ranks", tuple(sorted(ranks)))

    def per_triangle(self, leaf_rank) -> tuple:
        """(reflectance, transmittance) of every triangle, (F,) float64 each, from its leaf's
        rank ``leaf_rank`` (F,) int (1: the lowest leaf; 0: a stalk): the ranks' table where
        it names the rank, else this optics' leaf values."""
        import numpy as np

        ranks = np.asarray(leaf_rank, dtype=np.int64)
        rho = np.full(len(ranks), self.reflectance)
        tau = np.full(len(ranks), self.transmittance)
        for rank, r, t in self.ranks:
            at = ranks == rank
            rho[at], tau[at] = r, t
        return rho, tau

    @property
    def scattering(self) -> float:
        """Leaf scattering coefficient: reflectance + transmittance."""
        return self.reflectance + self.transmittance

    @property
    def black(self) -> bool:
        """Nothing is scattered: leaves and ground absorb all they intercept."""
        return self.scattering == 0.0 and self.ground_reflectance == 0.0 and \
            all(r + t == 0.0 for _, r, t in self.ranks)


#: Maize defaults per band (module docstring).
DEFAULT_OPTICS = {"par": Optics(0.10, 0.05, 0.10, "par"),
                  "nir": Optics(0.45, 0.40, 0.25, "nir")}


def optics_for(band: str = "par", reflectance: float | None = None,
               transmittance: float | None = None,
               ground_reflectance: float | None = None) -> Optics:
    """The band's default optics with any value given replacing its default.

    Raises
    ------
    MaizevizError
        An unknown band, a value outside [0, 1] or a leaf scattering more than 1.
    """
    if band not in DEFAULT_OPTICS:
        raise MaizevizError(f"unknown band '{band}' (known: {', '.join(BANDS)})",
                            quantity="band")
    d = DEFAULT_OPTICS[band]
    return Optics(d.reflectance if reflectance is None else reflectance,
                  d.transmittance if transmittance is None else transmittance,
                  d.ground_reflectance if ground_reflectance is None else ground_reflectance,
                  band)


def read_optics_table(path, band: str) -> tuple[tuple[int, float, float], ...]:
    """Leaf optics per rank from a CSV with a header ``rank,reflectance,transmittance`` (and
    optionally ``band``: rows of other bands are left out), one row per leaf rank.

    Raises
    ------
    MaizevizError
        The file cannot be read, a column is missing, a value is not a number (naming the
        line), a rank appears twice; values are checked by :class:`Optics`.
    """
    import csv

    from maizeviz.io.inputs import read_input, refuse_zero_tail

    # utf-8-sig: a spreadsheet's "CSV UTF-8" starts with a byte-order mark
    raw = read_input(path, "optics table", max_bytes=4 * 2**20)
    text = refuse_zero_tail(raw, path, "optics table").decode("utf-8-sig", "replace")
    rows = list(csv.reader(text.splitlines()))
    if not rows:
        raise MaizevizError(f"{path}: the optics table is empty", quantity="optics_table")
    head = [h.strip().lower() for h in rows[0]]
    for need in ("rank", "reflectance", "transmittance"):
        if need not in head:
            raise MaizevizError(f"{path}: the optics table has no '{need}' column (header: "
                                "rank,reflectance,transmittance[,band])",
                                quantity="optics_table")
    col = {h: i for i, h in enumerate(head)}
    out = []
    seen: dict[int, int] = {}
    for line, row in enumerate(rows[1:], start=2):
        if not any(c.strip() for c in row):
            continue
        if len(row) != len(head):
            raise MaizevizError(f"{path}, line {line}: {len(row)} values for {len(head)} "
                                "columns", quantity="optics_table")
        if "band" in col and row[col["band"]].strip().lower() != band:
            continue
        try:
            rank = whole(row[col["rank"]])
            rho, tau = number(row[col["reflectance"]]), number(row[col["transmittance"]])
        except ValueError:
            raise MaizevizError(f"{path}, line {line}: rank, reflectance and transmittance "
                                f"must be numbers, got {', '.join(c[:20] for c in row)}",
                                quantity="optics_table") from None
        if rank in seen:
            raise MaizevizError(f"{path}, line {line}: leaf rank {rank} was given on line "
                                f"{seen[rank]} already", quantity="optics_table")
        seen[rank] = line
        try:
            Optics(0.0, 0.0, 0.0, band, ((rank, rho, tau),))       # the row alone, checked
        except MaizevizError as exc:
            raise MaizevizError(f"{path}, line {line}: {exc}",
                                quantity="optics_table") from None
        out.append((rank, rho, tau))
    if not out:
        raise MaizevizError(f"{path}: the optics table has no row for the {band.upper()} band",
                            quantity="optics_table")
    return tuple(out)
