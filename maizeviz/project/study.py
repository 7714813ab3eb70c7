"""A study to and from a ``.maizeviz`` project: points, layout, settings and light results.

This is what the app saves and opens, and what the command line, sweeps and notebooks read::

    opened = open_project("study.maizeviz")           # checked; the points file to read
    leaves = read_leaves(opened.points_path).leaves
    layout = project_layout(opened, leaves)            # stored, or the settings' tiling
    results, notes = results_on(opened, layout)        # those traced on these stands

Opening uses the original points file when it is still there with the same content (hashed
by streaming, never read whole), and the project's own copy otherwise: unpacked to a cache
folder, written atomically and checked against its hash every time it is used.
"""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from maizeviz.canopy.build import STALK_TRIANGLES
from maizeviz.canopy.layout import CanopyLayout
from maizeviz.cost import check, layout_cost
from maizeviz.errors import MaizevizError
from maizeviz.io.archive import Project, ProjectError, Record, get, load_project
from maizeviz.io.atomic import remove_leftovers
from maizeviz.io.hashing import checked_copy, same_content
from maizeviz.leaf.fit import Leaf
from maizeviz.mesh.levels import Level, parse_level
from maizeviz.project.records import KINDS, per_triangle, run_from_record, run_record
from maizeviz.project.stands import layout_from_parts, layout_parts, stands_identity

#: Settings groups of a project (``view``: how the app colours light, kept for the app; a
#: project without it opens with the app's defaults).
CANOPY, LIGHT, VIEW = "canopy", "light", "view"


@dataclass(frozen=True)
class StoredResult:
    """A light result read from a project.

    Attributes
    ----------
    label : the canopy (level) it was traced on, as in Table 2
    result : a ``LightResult`` (sun), ``SkyLight`` (sky) or ``PeriodLight`` (day)
    kind : ``"sun"``, ``"sky"`` or ``"day"``
    settings : the settings of a sky or day run as stored (JSON), or None
    stands : ``{"n", "sha256"}`` of the stands it was traced on
        (:func:`~maizeviz.project.stands.stands_identity`), None in older projects
    """

    label: str
    result: Any
    kind: str
    settings: dict | None = None
    stands: dict | None = None

    def specs(self, where: str = "project") -> Any:
        """How a sky or day result was traced: a :class:`~maizeviz.light.specs.SkySpec`, or
        ``(DaySpec, SkySpec)`` for a day (None for a sun, or a day of an older project);
        stored settings that do not read: ProjectError naming ``where``."""
        from maizeviz.project.settings import run_settings

        if self.kind == "sun":
            return None
        return run_settings(self.kind, self.result, self.settings, where)


@dataclass
class Opened:
    """A project read and checked: the points file to load (the original or the project's
    checked copy), notes for the user, settings and the records of its light results (read
    into results by :func:`results_on`, once the canopy they belong to is known)."""

    path: str
    project: Project
    points_path: str
    shown_name: str
    notes: list[str] = field(default_factory=list)
    canopy: dict = field(default_factory=dict)
    light: dict = field(default_factory=dict)
    records: list[Record] = field(default_factory=list)
    view: dict = field(default_factory=dict)


def make_project(points_path: str, points_bytes: bytes, layout: CanopyLayout | None,
                 stands: CanopyLayout, canopy: dict, light: dict,
                 runs: Sequence[tuple], view: dict | None = None) -> Project:
    """The project of a study.

    Parameters
    ----------
    points_path, points_bytes : the points file and its content (embedded in the project)
    layout : the layout to store, or None when it is the tiling given by ``canopy["tile"]``
    stands : the layout the ``runs`` were traced on (the one shown): each result is tagged
        with the identity of the stands it says it was traced on, else with this layout's
    canopy, light : settings (JSON objects)
    runs : (label, result) or (label, result, settings) tuples, results of any light
    view : how the app colours light (JSON object), or None
    """
    doc, arrays = layout_parts(layout) if layout is not None else (None, {})
    identity = stands_identity(stands)
    records = tuple(run_record(run[0], run[1], run[2] if len(run) > 2 else None,
                               stands=getattr(run[1], "stands", None) or identity)
                    for run in runs)
    settings = {CANOPY: canopy, LIGHT: light, **({VIEW: view} if view is not None else {})}
    return Project(points_bytes, str(points_path), doc, settings, arrays, records)


def _points_file(project: Project, cache: str | Path | None, notes: list[str]) -> str:
    original = Path(project.points_path)
    digest = project.points_sha256
    if same_content(original, digest):
        return str(original)
    folder = Path(cache) if cache else Path(tempfile.gettempdir()) / "maizeviz-projects"
    copy = checked_copy(folder, original.name or "points.csv", project.points_csv, digest,
                        ProjectError)
    why = "has changed" if original.is_file() else "is not there"
    notes.append(f"the points file {original} {why}; using the copy saved in the project")
    return str(copy)


def open_project(path: str | Path, cache: str | Path | None = None) -> Opened:
    """Read a project, decide which points file to load and read its light results.

    ``cache``: the folder for the project's copy of its points (default: a folder in the
    system's temporary folder).

    Raises
    ------
    ProjectError
        The project cannot be used (one line).
    """
    where = str(path)
    project = load_project(path)
    remove_leftovers(path)             # temporary files of saves that were killed
    notes: list[str] = []
    points_path = _points_file(project, cache, notes)
    canopy = get(project.settings, CANOPY, dict, {}, where)
    light = get(project.settings, LIGHT, dict, {}, where)
    view = get(project.settings, VIEW, dict, {}, where)
    records = []
    for i, rec in enumerate(project.results):
        if rec.kind not in KINDS:
            notes.append(f"result {i + 1} is of a kind this maizeviz does not know "
                         f"('{rec.kind}'); left out")
            continue
        stands = get(rec.meta, "stands", dict, None, f"{where}: result {i + 1}")
        if stands is not None:
            get(stands, "n", int, where=f"{where}: result {i + 1} stands")
            get(stands, "sha256", str, where=f"{where}: result {i + 1} stands")
        records.append(rec)
    shown = f"{Path(project.points_path).name} (project {Path(path).name})"
    return Opened(where, project, points_path, shown, notes, canopy, light, records, view)


def restore_layout(opened: Opened, plants: set[int]) -> CanopyLayout | None:
    """The layout the project stored (stands in their saved order), checked against the
    plants read from its points; None when the project uses the tiling of its settings."""
    p = opened.project
    if p.layout is None:
        return None
    return layout_from_parts(p.layout, p.arrays, plants, opened.path)


def project_layout(opened: Opened, leaves: Sequence[Leaf]) -> CanopyLayout:
    """The layout a project opens with: the one it stored (:func:`restore_layout`), else the
    digitized block of ``leaves`` tiled as its canopy settings say (``tile``, default 3)."""
    from maizeviz.canopy.layout import check_tile, layout_for

    stored = restore_layout(opened, {lf.plant for lf in leaves})
    if stored is not None:
        return stored
    tile = get(opened.canopy, "tile", int, 3, opened.path)
    try:
        shape = check_tile((tile, tile), len({lf.plant for lf in leaves}))
    except MaizevizError as exc:
        raise ProjectError(f"{opened.path}: {exc}", quantity="tile") from None
    return layout_for(list(leaves), shape)


def results_on(opened: Opened, layout: CanopyLayout, leaves: Sequence[Leaf] | None = None,
               exact: bool = True) -> tuple[list[StoredResult], list[str]]:
    """The light results of ``opened`` that belong to the canopy about to be shown, read.

    A result is left out, with one note each, when it was traced on other stands than those
    of ``layout`` (its per-plant light would be shown on other plants), or when it holds
    light for more triangles than the canopy of ``leaves`` on ``layout`` has at the result's
    mesh level (:func:`scene_triangles`): both are decided from the stored metadata and the
    arrays' headers, before any of its arrays is read.

    Parameters
    ----------
    opened : from :func:`open_project`
    layout : the layout the project opens with (:func:`project_layout`)
    leaves : the leaves of the project's points; None: per-triangle sizes not checked
    exact : with ``leaves``, mesh the canopy's plants at each result's level and hold every
        per-triangle array to its exact triangle count (:func:`canopy_triangles`), not only
        to the bound; the default, for :func:`read_study` and the app alike (False only
        where the plants' meshes cannot be afforded: an array of another length is then
        found only when its light is shown)

    Returns
    -------
    results : list of StoredResult, oldest first
    notes : list of str, one per result left out

    Raises
    ------
    ProjectError
        A kept result whose stored data are malformed (one line); with ``exact``, a
        per-triangle array of another length than its canopy's triangles, named.
    """
    here = stands_identity(layout)
    counts: dict[str, tuple[int, int] | None] = {}
    kept, notes = [], []
    edited = opened.project.layout is not None
    legacy_order = edited and "layout_placements" not in opened.project.arrays
    bounds: dict[str, int | None] = {}
    for rec in opened.records:
        stands = rec.meta.get("stands")
        label = str(rec.meta.get("level", ""))
        name = f"the {KINDS[rec.kind]} result on {rec.meta.get('label', label)}"
        if stands is None and legacy_order:
            notes.append(f"{name} was saved by an older maizeviz with an edited layout whose "
                         "plant order cannot be restored; left out (compute it again)")
            continue
        if stands is not None and stands != here:
            notes.append(f"{name} was traced on other stands ({stands.get('n')} plants) than "
                         f"the project's layout ({here['n']}); left out (compute it again)")
            continue
        if leaves is not None:
            if label not in bounds:
                bounds[label] = scene_triangles(leaves, layout, label)
            held, most = per_triangle(rec), bounds[label]
            if most is None:
                notes.append(f"{name}: its mesh level '{label[:40]}' is not one this maizeviz "
                             "knows; left out")
                continue
            if held > most:
                notes.append(f"{name} holds light for {held:,} triangles, but its canopy has "
                             f"at most {most:,}; left out (compute it again)")
                continue
            if exact:
                if label not in counts:
                    counts[label] = canopy_triangles(leaves, layout, label)
                check_triangle_arrays(rec, counts[label], f"{opened.path}: {name}")
        run = run_from_record(rec, opened.path)
        if run is not None:
            kept.append(StoredResult(*run, stands=stands))
    return kept, notes


def scene_triangles(leaves: Sequence[Leaf], layout: CanopyLayout, label: str) -> int | None:
    """At most how many triangles the scene of ``leaves`` on ``layout`` has at the mesh level
    labelled ``label`` (as results store it, "36 triangles, widths unscaled" included):
    leaves (:func:`maizeviz.cost.layout_cost`, an upper bound) and stalks. None for a label
    that is not a mesh level."""
    try:
        level = parse_level(label.split(",")[0])
    except MaizevizError:
        return None
    return layout_cost(leaves, layout, level).count + STALK_TRIANGLES * len(layout.placements)


def canopy_triangles(leaves: Sequence[Leaf], layout: CanopyLayout, label: str
                     ) -> tuple[int, int] | None:
    """Exactly how many (leaf, stalk) triangles the canopy of ``leaves`` on ``layout`` has at
    the mesh level labelled ``label`` ("16 triangles", "36 triangles, widths unscaled",
    "K=4"): its plants meshed (:func:`~maizeviz.canopy.build.plant_meshes`, as the canopy is
    built) and a stalk per stand. None for a label that is not a mesh level."""
    from maizeviz.canopy.build import plant_meshes

    try:
        level = parse_level(label.split(",")[0])
    except MaizevizError:
        return None
    placed = {p.plant for p in layout.placements}
    plants = plant_meshes([lf for lf in leaves if lf.grid.plant in placed], level,
                          "widths unscaled" not in label)
    return (sum(len(plants[p.plant].faces) for p in layout.placements if p.plant in plants),
            STALK_TRIANGLES * len(layout.placements))


def check_triangle_arrays(rec: Any, triangles: tuple[int, int] | None, where: str) -> None:
    """Refuse a record whose per-triangle arrays (:data:`~maizeviz.project.records.
    PER_TRIANGLE`) do not hold one value per triangle of its canopy (``triangles``: its
    leaf and stalk triangles; light is stored for the leaves, or the leaves then the stalks
    where they were traced), naming the array, its length and the ones expected (read from
    the arrays' headers: nothing is read).

    Raises
    ------
    ProjectError
        One line naming the array.
    """
    from maizeviz.project.records import PER_TRIANGLE

    if triangles is None:
        return
    leaf, stalk = triangles
    for name, a in rec.arrays.items():
        if not name.endswith(PER_TRIANGLE):
            continue
        held = int(a.shape[0]) if a.ndim == 1 else -1
        if held not in (leaf, leaf + stalk):
            size = f"{held:,} values" if held >= 0 else f"shape {tuple(a.shape)}"
            raise ProjectError(f"{where}: array '{name}' holds {size}, expected {leaf:,} (one "
                               f"per leaf triangle of its canopy) or {leaf + stalk:,} (with "
                               "its stalks); the project is damaged")


def check_canopy_fits(leaves: Sequence[Leaf], layout: CanopyLayout, level: Level,
                      where: str) -> None:
    """Refuse, before anything is built, a project whose canopy would not fit in memory
    (:func:`maizeviz.cost.check`, as the command line does).

    Raises
    ------
    ProjectError
        Naming the project, the estimate and the memory available.
    """
    try:
        check([[layout_cost(leaves, layout, level)]], force=True)
    except MaizevizError as exc:
        raise ProjectError(f"{where}: {exc}", quantity=exc.quantity) from None


@dataclass
class Study:
    """A project read whole, as the command line and notebooks use it (:func:`read_study`).

    Attributes
    ----------
    path : the project file
    plants : LeavesFromFile, the leaves fitted from the project's points (``.leaves``,
        ``.skipped``, ``.notes``)
    layout : CanopyLayout, the stands the project opens with
    level : str, the mesh level of its canopy settings ("36 triangles", "K=4")
    preserve_area : bool, the area-preserving variant of triangle budgets
    results : list of StoredResult, its light results on these stands (``.result.table()``)
    notes : list of str, what the user should know (a moved points file, results left out)
    """

    path: str
    plants: Any
    layout: CanopyLayout
    level: str
    preserve_area: bool
    results: list[StoredResult]
    notes: list[str]


def read_study(path: str | Path, cache: str | Path | None = None,
               progress: Any = None) -> Study:
    """Read a ``.maizeviz`` project: its points fitted, its layout, its settings and results.

    Parameters
    ----------
    path : str or Path
        The project file.
    cache : str or Path, optional
        Folder for the project's checked copy of its points when the original file moved or
        changed (default: the system's temporary folder).
    progress : callable, optional
        ``progress(done, total)`` over the leaves; returning False cancels.

    Returns
    -------
    Study
        The leaves, the layout, the canopy's level and the light results that belong to them.

    Raises
    ------
    ProjectError
        The project cannot be used, or its canopy would not fit in memory (one line).
    """
    from maizeviz.leaf.fit import read_leaves

    opened = open_project(path, cache)
    plants = read_leaves(opened.points_path, progress=progress)
    if not plants.leaves:
        raise ProjectError(f"{opened.path}: no leaf of its points could be reconstructed")
    layout = project_layout(opened, plants.leaves)
    text = get(opened.canopy, "level", str, "36", opened.path)
    try:
        level = parse_level(text)
    except MaizevizError as exc:
        raise ProjectError(f"{opened.path}: its canopy level: {exc}", quantity="level") from None
    check_canopy_fits(plants.leaves, layout, level, opened.path)
    results, dropped = results_on(opened, layout, plants.leaves)
    return Study(opened.path, plants, layout, level.label,
                 get(opened.canopy, "preserve_area", bool, True, opened.path), results,
                 [*opened.notes, *plants.notes, *dropped])


def save_study(path: str | Path, points: str | Path, layout: CanopyLayout,
               results: Sequence[Any] = (), level: str = "36",
               preserve_area: bool = True) -> Path:
    """Write a ``.maizeviz`` project that the app and :func:`read_study` open.

    Parameters
    ----------
    path : str or Path
        The project file to write (atomically: an existing one stays whole on failure).
    points : str or Path
        The points file the plants were read from (its bytes go into the project).
    layout : CanopyLayout
        The stands of the canopy, stored with the project.
    results : sequence of light results
        Results traced on ``layout`` (``LightResult``, ``SkyLight``, ``PeriodLight``...), each
        stored under its own mesh level.
    level : str
        The mesh level the project opens at.
    preserve_area : bool
        Area-preserving triangle budgets.

    Returns
    -------
    pathlib.Path
        The project written.

    Raises
    ------
    MaizevizError
        A result traced on other stands than ``layout``'s (its per-plant light would be read
        back on other plants), before anything is written.
    """
    from maizeviz.io.archive import MAX_MEMBER_BYTES, save_project
    from maizeviz.io.inputs import read_input

    here = stands_identity(layout)
    for k, r in enumerate(results):
        traced = getattr(r, "stands", None)
        if traced is not None and traced != here:
            raise MaizevizError(
                f"result {k + 1} ({r.level or 'light'}) was traced on other stands "
                f"({traced.get('n')} plants) than the layout given ({here['n']} plants): save "
                "it with the layout of the canopy it was traced on", quantity="results")
    chosen = parse_level(str(level))
    data = read_input(points, "points file", MAX_MEMBER_BYTES["points.csv"], ProjectError)
    stop = (str(chosen.triangles) if chosen.triangles is not None else
            "standard" if chosen.interp == 0 else f"K{chosen.interp}")   # as the app's slider
    canopy = {"tile": 1, "level": stop, "preserve_area": bool(preserve_area)}
    project = make_project(str(Path(points).resolve()), data, layout, layout, canopy, {},
                           [(str(r.level), r) for r in results])
    return save_project(path, project)
