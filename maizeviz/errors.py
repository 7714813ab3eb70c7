"""Domain errors: each names what is wrong and where, in words a technician can act on.

Core messages speak of quantities and files ("ray density must be > 0 rays per cm2"), never of
command-line flags or widgets: the core has no idea how a value reached it. An error about one
input value carries that value's name in :attr:`MaizevizError.quantity`, so the command line
can add its flag (``--density``) and the desktop app can point at its field.
"""

from __future__ import annotations


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
        super().__init__(message)
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
}
