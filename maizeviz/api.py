"""The package's front door: from a points file to light tables in a few lines.

These functions are what ``import maizeviz as mv`` offers (``mv.read_points``,
``mv.build_canopy``, ...; the package loads them on first use). They call the stages of the
core with the app's and the command line's defaults; the stages themselves
(:mod:`maizeviz.leaf`, :mod:`maizeviz.canopy`, :mod:`maizeviz.light`) take every option.

The method, the 81-plant canopy and its mesh levels (Table 2) are those of the study maizeviz
implements: Guo, X., Zhao, C., Xiao, B., Lu, S. & Li, C., *Study on maize leaf morphological
modeling and mesh simplification of surface* (also in Chinese: Xiao, B., Guo, X., Wang, J.,
Zheng, W. & Wang, D. (2007), Scientia Agricultura Sinica 40(4), 693-697). docs/method.md
gives the reference in full and how far it is verified.
"""

from __future__ import annotations

from pathlib import Path

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.build import build_canopy as _build_canopy
from maizeviz.canopy.layout import CanopyLayout, layout_for
from maizeviz.canopy.measures import CanopyMeasures
from maizeviz.canopy.measures import measure_canopy as _measure_canopy
from maizeviz.leaf.fit import LeavesFromFile, read_leaves
from maizeviz.mesh.levels import parse_level
from maizeviz.progress import ProgressCallback


def example_points() -> Path:
    """The bundled example: a digitized 3 x 3 block of maize plants at silking.

    Returns
    -------
    pathlib.Path
        A points CSV (coordinates in cm) of 9 plants, 140 leaves.
    """
    from maizeviz.resources import example_points as bundled

    return bundled()


def read_points(path: str | Path, strict: bool = False,
                progress: ProgressCallback | None = None) -> LeavesFromFile:
    """Read a points file, grid each leaf's digitized points and fit its NURBS surface.

    Parameters
    ----------
    path : str or Path
        A points CSV (``plant, leaf, row, col, x, y, z`` in cm) or FASTRAK record.
    strict : bool
        Refuse the file at its first bad line or leaf instead of skipping it.
    progress : callable, optional
        ``progress(done, total)`` over the leaves; returning ``False`` cancels.

    Returns
    -------
    LeavesFromFile
        ``leaves`` (fitted surfaces, cm), ``skipped`` (leaves refused, each naming plant,
        leaf, row, col), ``problems`` and ``notes`` (lines for the user).

    Raises
    ------
    MaizevizError
        The file cannot be read (naming it), or with ``strict`` its first problem.

    References
    ----------
    Piegl, L. & Tiller, W. (1997). The NURBS Book, 2nd ed., Springer (sections 9.2 and 9.4:
    global surface interpolation). https://doi.org/10.1007/978-3-642-59223-2
    """
    return read_leaves(path, strict=strict, progress=progress)


def lay_out(plants: LeavesFromFile | list, tile: tuple[int, int] = (3, 3),
            row_spacing: float = 60.0, plant_spacing: float = 30.0,
            layout_file: str | Path | None = None) -> CanopyLayout:
    """Where the plants stand: the digitized block tiled, or a layout file.

    Parameters
    ----------
    plants : LeavesFromFile or list of Leaf
        From :func:`read_points`.
    tile : (int, int)
        Copies of the digitized block along the rows and across them (the paper's 3 x 3).
    row_spacing : float
        Distance between rows [cm], used when the block's own cannot be inferred.
    plant_spacing : float
        Distance between plants along a row [cm], likewise.
    layout_file : str or Path, optional
        A layout CSV placing each plant (overrides ``tile``).

    Returns
    -------
    CanopyLayout
        ``placements`` (plant, x, y [cm], rotation [deg]), ``bounds`` (x0, y0, x1, y1) [cm],
        ``centre_bounds`` (the central tile, where light is sampled by default).
    """
    return layout_for(_leaves(plants), tuple(tile), row_spacing, plant_spacing,  # type: ignore[arg-type]
                      layout_file=layout_file)


def build_canopy(plants: LeavesFromFile | list, layout: CanopyLayout | None = None, *,
                 tile: tuple[int, int] = (3, 3), level: str | int = "36",
                 preserve_area: bool = True,
                 progress: ProgressCallback | None = None) -> Canopy:
    """The canopy: every plant of the layout with its leaves meshed at one level.

    Parameters
    ----------
    plants : LeavesFromFile or list of Leaf
        From :func:`read_points`.
    layout : CanopyLayout, optional
        From :func:`lay_out`; else the block tiled ``tile`` times.
    tile : (int, int)
        Copies of the digitized block along and across the rows, without ``layout``.
    level : str or int
        Mesh level: a triangle budget per leaf ("36", 36), "standard" (72), or an
        interpolated level "K4".
    preserve_area : bool
        Scale each mesh to the leaf's surface area (the paper's area-preserving variant).
    progress : callable, optional
        ``progress(done, total)`` while meshing and placing; returning ``False`` cancels.

    Returns
    -------
    Canopy
        ``vertices`` (V, 3) float64 [cm], ``faces`` (F, 3) int64, ``n_triangles``, ``layout``,
        ``level`` (its label).

    Notes
    -----
    The mesh levels are Table 2's of the study maizeviz implements (Guo, Zhao, Xiao, Lu & Li,
    *Study on maize leaf morphological modeling and mesh simplification of surface*; the
    package's text gives the reference).
    """
    leaves = _leaves(plants)
    if layout is None:
        layout = layout_for(leaves, tuple(tile))  # type: ignore[arg-type]
    return _build_canopy(leaves, layout, parse_level(str(level)), preserve_area, progress)


def measure_canopy(canopy: Canopy) -> CanopyMeasures:
    """Table 2 measures of a canopy: leaf area, projected area, ground cover, LAI.

    Parameters
    ----------
    canopy : Canopy
        From :func:`build_canopy`.

    Returns
    -------
    CanopyMeasures
        Areas in m2 (``leaf_area_m2``, ``ground_cover_m2``, ...), ``lai`` (m2 of leaf per m2
        of ground); ``as_dict()`` for a record.
    """
    return _measure_canopy(canopy)


def _leaves(plants: LeavesFromFile | list) -> list:
    return list(plants.leaves) if isinstance(plants, LeavesFromFile) else list(plants)
