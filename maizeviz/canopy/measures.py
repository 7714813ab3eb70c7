"""Canopy measures: leaf area, projected area, ground cover, leaf area index (the paper's Table 2)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.errors import check_range
from maizeviz.mesh.raytrace import RayScene
from maizeviz.mesh.tessellate import triangle_areas_normals

#: Pixel edge (cm) of the vertical-ray grid that measures ground cover.
COVER_RESOLUTION_CM = 0.5


@dataclass(frozen=True)
class CanopyMeasures:
    """Areas in m2; LAI = leaf area / ground area."""

    level: str
    plants: int
    leaves: int
    triangles: int
    leaf_area_m2: float
    projected_area_m2: float
    ground_cover_m2: float
    ground_area_m2: float
    cover_resolution_cm: float

    @property
    def lai(self) -> float:
        return self.leaf_area_m2 / self.ground_area_m2

    def as_dict(self) -> dict[str, float | int | str]:
        d: dict[str, float | int | str] = dict(self.__dict__)
        d["lai"] = self.lai
        return d


#: The paper's Table 2 as maizeviz shows it: (key of a :func:`table2_row`, column header).
TABLE2_COLUMNS = (("level", "level"), ("triangles", "triangles"),
                  ("leaf_area_m2", "leaf area m²"), ("projected_area_m2", "projected m²"),
                  ("ground_cover_m2", "ground cover m²"), ("lai", "LAI"), ("build_s", "build s"))


def table2_row(m: CanopyMeasures, build_s: float, label: str | None = None) -> dict[str, str]:
    """One row of Table 2, formatted for people (areas to 0.01 m2, seconds to 0.01 s)."""
    return {"level": label or m.level, "triangles": f"{m.triangles:,}",
            "leaf_area_m2": f"{m.leaf_area_m2:.2f}", "projected_area_m2": f"{m.projected_area_m2:.2f}",
            "ground_cover_m2": f"{m.ground_cover_m2:.2f}", "lai": f"{m.lai:.2f}",
            "build_s": f"{build_s:.2f}"}


#: The ground-cover pixel side, cm, is refused outside these bounds: below, the vertical rays
#: outnumber any memory; above, a pixel is wider than any plot.
COVER_RESOLUTION_RANGE_CM = (1e-3, 1e4)


def check_cover_resolution(resolution: float) -> None:
    """Refuse a ground-cover pixel side (cm) outside :data:`COVER_RESOLUTION_RANGE_CM`."""
    check_range(resolution, "the ground-cover pixel", *COVER_RESOLUTION_RANGE_CM,
                "cover_resolution", unit="cm")


def ground_cover(canopy: Canopy, resolution: float = COVER_RESOLUTION_CM,
                 scene: RayScene | None = None) -> float:
    """Area (cm2) of the ground covered by the union of the leaves' vertical shadows.

    Measured by vertical rays, one at the centre of each ``resolution`` x ``resolution`` cm
    pixel of the ground cells (the plot), so it can never exceed the ground area; shadows that
    fall outside the plot are not counted. The error is about one pixel row along each
    shadow's outline.
    """
    check_cover_resolution(resolution)
    if canopy.n_triangles == 0:
        return 0.0
    scene = scene or RayScene(canopy.vertices, canopy.faces)
    top = float(canopy.vertices[:, 2].max()) + 10.0
    covered = 0
    x0, y0, x1, y1 = canopy.layout.bounds
    xs = np.arange(x0 + resolution / 2, x1, resolution)
    ys = np.arange(y0 + resolution / 2, y1, resolution)
    cells = canopy.layout.cells
    chunk = max(1, 2_000_000 // max(len(ys), 1))
    for a in range(0, len(xs), chunk):
        gx, gy = np.meshgrid(xs[a:a + chunk], ys, indexing="ij")
        gx, gy = gx.ravel(), gy.ravel()
        inside = np.zeros(len(gx), dtype=bool)
        for cx0, cy0, cx1, cy1 in cells:
            inside |= (gx > cx0) & (gx < cx1) & (gy > cy0) & (gy < cy1)
        gx, gy = gx[inside], gy[inside]
        if not len(gx):
            continue
        org = np.column_stack([gx, gy, np.full(len(gx), top)])
        dirs = np.broadcast_to([0.0, 0.0, -1.0], org.shape)
        covered += int(scene.occluded(org, dirs, top + 1.0).sum())
    return covered * resolution**2


def measure_canopy(canopy: Canopy, cover_resolution: float = COVER_RESOLUTION_CM,
                   with_stalks: bool = False, scene: RayScene | None = None) -> CanopyMeasures:
    """Table 2 measures of a canopy; the stalks shade the ground in the cover only
    ``with_stalks``.

    A stalk is not leaf area: the leaf area, its projection and the LAI are the leaves' in
    both cases (with ``with_stalks`` they counted the stalks' surface too, about 11 m2 for the
    paper's 81 plants).

    ``scene`` is the canopy's plain Embree scene (the leaves, and the stalks when
    ``with_stalks``; not a periodic one), to spare building it again for the ground cover.
    """
    area, normals = triangle_areas_normals(canopy.vertices, canopy.faces)
    cover_src = canopy
    if with_stalks:
        cover_src = _with(canopy, np.vstack([canopy.vertices, canopy.stalk_vertices]),
                          np.vstack([canopy.faces,
                                     canopy.stalk_faces + len(canopy.vertices)]))
    return CanopyMeasures(
        level=canopy.level, plants=canopy.n_plants, leaves=canopy.n_leaves,
        triangles=canopy.n_triangles, leaf_area_m2=float(area.sum()) / 1e4,
        projected_area_m2=float((area * np.abs(normals[:, 2])).sum()) / 1e4,
        ground_cover_m2=ground_cover(cover_src, cover_resolution, scene) / 1e4,
        ground_area_m2=canopy.layout.ground_area_cm2 / 1e4,
        cover_resolution_cm=cover_resolution)


def _with(canopy: Canopy, verts: np.ndarray, faces: np.ndarray) -> Canopy:
    return replace(canopy, vertices=verts, faces=faces)
