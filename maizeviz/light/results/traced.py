"""What every traced light result shares: where it was sampled, how, and what it says.

:class:`~maizeviz.light.results.direct.LightResult` (one sun),
:class:`~maizeviz.light.results.diffuse.SkyLight` (a sky) and
:class:`~maizeviz.light.results.diffuse.PeriodLight` (a day) are :class:`TracedLight`; the last two
also carry binned maps (:class:`MappedLight`). Every result gives its numbers as a pandas
DataFrame with :meth:`TracedLight.table`: per height, or per leaf or plant of the canopy it was
traced on.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.light.results.maps import TransmissionMap
from maizeviz.light.results.on_triangles import OnCanopy
from maizeviz.light.results.per_leaf import LightRow, plant_light
from maizeviz.light.scene.rays import Rect

if TYPE_CHECKING:
    import pandas as pd

    from maizeviz.canopy.build import Canopy

#: What :meth:`TracedLight.table` tabulates.
TABLES = ("height", "leaf", "plant")
#: What a result's ``table(by=...)`` can be by: its summary (``"height"`` for a sun, a sky
#: or a period; ``"balance"`` for absorbed light; ``"canopy"`` for assimilation; None is the
#: summary), or per leaf or plant of the canopy it was traced on.
TableBy = Literal["height", "balance", "canopy", "leaf", "plant"]


def table_kind(by: str | None, summary: str, canopy: Canopy | None) -> str:
    """The table a result's ``table(by, canopy)`` makes: ``by``, or the result's ``summary``
    table when None; checked against what the result has and against the canopy.

    Parameters
    ----------
    by : str or None
        Asked for.
    summary : {"height", "balance", "canopy"}
        The result's own summary table.
    canopy : Canopy or None
        The canopy the light was traced on (per-leaf and per-plant tables need it).

    Returns
    -------
    str
        ``summary``, ``"leaf"`` or ``"plant"``.

    Raises
    ------
    MaizevizError
        Another ``by`` (quantity "by"), or no canopy for a leaf or plant table ("canopy").
    """
    kind = summary if by is None else by
    known = (summary, "leaf", "plant")
    if kind not in known:
        raise MaizevizError(f"a light table is by {', '.join(known)}, got '{by}'",
                            quantity="by")
    if kind != summary and canopy is None:
        raise MaizevizError(f"a table by {kind} needs the canopy the light was traced on: "
                            f"table('{kind}', canopy)", quantity="canopy")
    return kind


@dataclass(frozen=True, eq=False, kw_only=True)
class TracedLight(OnCanopy):
    """The fields every light result shares (keyword-only in the results' constructors).

    Attributes
    ----------
    heights_cm : (H,) float64 cm, heights of the sensor planes
    rect : (x0, y0, x1, y1) cm, the sample rectangle
    rays : int, rays per direction (and sensors per plane)
    level : str, mesh level label of the canopy
    warnings : tuple of str, what the user should know about this result
    seconds : dict, "build" (the scene), "trace", ..., s
    periodic : bool, rays and sensor paths wrapped across the plot
    stands : ``{"n", "sha256"}``, the identity of the stands of the canopy it was traced on
        (:func:`maizeviz.canopy.layout.stands_identity`), or None where not known
    canopy : Canopy or None, the canopy it was traced on (:class:`OnCanopy`): the per-leaf
        and per-plant tables use it when none is given
    """

    heights_cm: np.ndarray
    rect: Rect
    rays: int
    level: str = ""
    warnings: tuple[str, ...] = ()
    seconds: dict[str, float] = field(default_factory=dict)
    periodic: bool = False
    stands: dict | None = None

    @property
    def rect_area_cm2(self) -> float:
        """Area of the sample rectangle.

        Returns
        -------
        float
            [cm2].
        """
        x0, y0, x1, y1 = self.rect
        return (x1 - x0) * (y1 - y0)

    def height_index(self, height: float) -> int:
        """Index of a height among the traced heights.

        Parameters
        ----------
        height : float
            A traced height [cm].

        Returns
        -------
        int
            Its index in ``heights_cm``.

        Raises
        ------
        MaizevizError
            The height was not traced.
        """
        k = np.flatnonzero(np.isclose(self.heights_cm, height, rtol=0, atol=1e-9))
        if not len(k):
            raise MaizevizError(f"height {height:g} cm was not traced (traced: "
                                f"{', '.join(f'{h:g}' for h in self.heights_cm)} cm)",
                                quantity="heights")
        return int(k[0])

    def table(self, by: TableBy | None = None, canopy: Canopy | None = None) -> pd.DataFrame:
        """The result as a table.

        Parameters
        ----------
        by : {None, "height", "leaf", "plant"}
            One row per sensor height (None, the default: column ``height_cm`` [cm], then the
            result's values there), per leaf or per plant (the light each intercepts, areas
            [cm2], PAR [mol]).
        canopy : Canopy, optional
            The canopy the light was traced on (default: the result's own, ``canopy``);
            needed by leaf and plant.

        Returns
        -------
        pandas.DataFrame
            One row per height, leaf or plant.

        Raises
        ------
        MaizevizError
            Another ``by``, or a leaf or plant table without the canopy.
        """
        import pandas as pd

        canopy = self._on(canopy)
        kind = table_kind(by, "height", canopy)
        if kind == "height":
            return pd.DataFrame({"height_cm": np.asarray(self.heights_cm, dtype=np.float64),
                                 **self._height_columns()})
        assert canopy is not None
        rows = self.leaf_rows(canopy)
        return pd.DataFrame(plant_light(rows) if kind == "plant" else rows)

    def _height_columns(self) -> dict[str, Any]:
        """The per-height columns of :meth:`table`, each (H,)."""
        raise NotImplementedError

    def leaf_rows(self, canopy: Canopy) -> list[LightRow]:
        """One row per leaf that received light.

        Its plant, place, area and the light it received
        (:mod:`maizeviz.light.results.per_leaf`).

        Parameters
        ----------
        canopy : Canopy
            The canopy the light was traced on.

        Returns
        -------
        list of dict
            One row per leaf that received light: ``instance``, ``plant``, ``leaf``, ``x_cm``,
            ``y_cm``, ``leaf_area_cm2`` and the light (copies of a plant in a tile-periodic field
            reported as one); ``table("leaf", canopy)`` as dicts.
        """
        raise NotImplementedError


@dataclass(frozen=True, eq=False, kw_only=True)
class MappedLight(TracedLight):
    """A result that carries its transmission binned over each sensor plane.

    Attributes
    ----------
    maps : (H, a, b) float64, the binned value of each plane (NaN: no sensor in the bin)
    map_edges : x (a + 1,) and y (b + 1,) bin edges, cm
    map_rays : (a, b) int64, sensors per bin (ground grid)
    """

    maps: np.ndarray
    map_edges: tuple[np.ndarray, np.ndarray]
    map_rays: np.ndarray

    def _map_at(self, height: float, totals: np.ndarray) -> TransmissionMap:
        """The map of the plane at ``height`` (a traced height), ``totals`` (H,) the planes'
        whole values."""
        i = self.height_index(height)
        xe, ye = self.map_edges
        return TransmissionMap(float(self.heights_cm[i]), xe, ye, self.maps[i], self.map_rays,
                               float(totals[i]))
