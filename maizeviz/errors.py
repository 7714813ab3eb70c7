"""Domain errors: each names what is wrong and where, in words a technician can act on."""

from __future__ import annotations


class MaizevizError(Exception):
    """Base of every error maizeviz raises on purpose (bad input, impossible request)."""


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
