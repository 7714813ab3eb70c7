"""Domain errors: each names what is wrong and where, in words a technician can act on.

Core messages speak of quantities and files ("ray density must be > 0 rays per cm2"), never of
command-line flags or widgets: the core has no idea how a value reached it. An error about one
input value carries that value's name in :attr:`MaizevizError.quantity`, so the command line
can add its flag (``--density``) and the desktop app can point at its field.
"""

from __future__ import annotations

#: Characters that would break a message over lines (``str.splitlines`` splits on each), or
#: hide text, shown escaped instead: a message quoting a hostile file stays one line.
_ESCAPES = {c: repr(chr(c))[1:-1] for c in (*range(0x20), 0x7F, 0x85, 0x2028, 0x2029)}


def one_line(text: str) -> str:
    """``text`` with line breaks and other control characters escaped (``\\n``, ``\\x0b``)."""
    return str(text).translate(_ESCAPES)


class MaizevizError(Exception):
    """Base of every error maizeviz raises on purpose (bad input, impossible request).

    Parameters
    ----------
    message : str
        One line saying what is wrong and where.
    quantity : str, optional
        The input the message is about, as named in :data:`QUANTITIES` (``"density"``,
        ``"heights"``...), when it is about one input.
    """

    def __init__(self, message: str = "", quantity: str | None = None):
        super().__init__(one_line(message))
        self.quantity = quantity


class PointsFileError(MaizevizError):
    """A points file cannot be read at all (missing, empty, not CSV, a required column absent)."""


class LeafError(MaizevizError):
    """One leaf cannot be reconstructed; other leaves may still be fine.

    Parameters
    ----------
    plant, leaf : int
        Ids of the leaf.
    message : str
        What is wrong, already naming the row / col where that applies.
    """

    def __init__(self, plant: int, leaf: int, message: str):
        self.plant = plant
        self.leaf = leaf
        self.detail = message
        super().__init__(f"plant {plant}, leaf {leaf}: {message}")


def check_range(value: float, name: str, low: float, high: float, quantity: str | None = None,
                whole: bool = False, unit: str = "") -> None:
    """Refuse a value outside [low, high] (or not finite, or not whole when ``whole``), naming
    it: ``"cross-sections must be a whole number between 2 and 200, got 0"``."""
    kind = "a whole number" if whole else "a number"
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and \
        value == value and low <= value <= high and (not whole or float(value).is_integer())
    if not ok:
        units = f" {unit}" if unit else ""
        lo, hi = (f"{int(v):,}" if whole else f"{v:g}" for v in (low, high))
        raise MaizevizError(f"{name} must be {kind} between {lo} and {hi}{units}, got {value}",
                            quantity=quantity)


#: Inputs an error may be about, with what they mean; the CLI maps each to its flag.
QUANTITIES = {
    "density": "rays per cm2 of the sample rectangle",
    "heights": "heights of the sample planes, cm",
    "rect": "sample rectangle x0, y0, x1, y1, cm",
    "threads": "tracing threads",
    "heatmap_bin": "heatmap bin edge, cm",
    "cover_resolution": "pixel edge of the ground-cover grid, cm",
    "row_spacing": "distance between rows, cm",
    "plant_spacing": "distance between plants of a row, cm",
    "tile": "tiles across and along the rows",
    "layout": "layout file of plant positions",
    "block": "rows x plants per row of the digitized block",
    "level": "mesh level",
    "interp": "points interpolated between data points",
    "triangles": "triangle budget per leaf",
    "degree": "NURBS degree",
    "sun": "sun position",
    "date": "date",
    "time": "clock time",
    "place": "latitude and longitude",
    "tz": "time zone",
    "periodic": "periodic field",
    "cols": "points per cross-section",
    "plants": "rows x plants per row",
    "sections": "cross-sections of a long leaf",
    "sky": "sky radiance distribution and split",
    "sky_directions": "number of sky directions",
    "step": "time step of a period, min",
    "period": "start and end clock times of a period",
    "par_factor": "PAR photons per joule of shortwave, umol/J",
    "linke_turbidity": "Linke turbidity of the clear sky",
    "altitude": "site altitude, m",
    "weather": "weather file of irradiance (CSV)",
    "points_across": "points per cross-section of a synthetic leaf",
    "seed": "random seed",
    "band": "waveband of absorbed light (par, nir)",
    "reflectance": "leaf reflectance in a band",
    "transmittance": "leaf transmittance in a band",
    "ground_reflectance": "soil reflectance in a band",
    "irradiance": "irradiance of a band on a horizontal plane, W/m2",
    "depth": "scatterings followed per ray",
    "threshold": "share of the incident light left travelling where scattering stops",
    "photosynthesis": "leaf photosynthesis model and its parameters",
    "temperature": "air (leaf) temperature, C",
    "co2": "ambient CO2, umol/mol",
    "precision": "target standard error of the Monte Carlo estimate",
    "plant": "plant id",
    "pace": "seconds between simulated presses",
    "noise": "simulated digitizer noise, cm",
    "answer_timeout": "seconds to wait for the digitizer's replies",
    "baud": "serial baud rate",
    "at": "stalk position x, y, cm",
    "params": "data parameterisation",
    "resume": "continue an existing recording",
    "mesh": "mesh file of plants (PLY, OBJ) traced as it is",
    "mesh_unit": "length unit of a mesh file (m, cm, mm)",
    "up": "up axis of a mesh file (z, y)",
    "field": "field rectangle of a mesh canopy x0, y0, x1, y1, cm",
    "mesh_ids": "face properties holding a mesh's plant and leaf ids",
    "connect_timeout": "seconds to wait for a Dask scheduler",
}
