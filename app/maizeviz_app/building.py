"""The model's actions that make a canopy: open a points file, read a canopy mesh, build at
the level the settings say (no Qt: the work goes to the model's runner).

Functions over the study's state (``study``: a :class:`maizeviz_app.state.StudyState`, whose
public changes they call); :class:`maizeviz_app.model.StudyModel` offers them as methods.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from maizeviz.errors import MaizevizError
from maizeviz_app import lighting

if TYPE_CHECKING:
    from maizeviz_app.state import StudyState

#: The level the view draws the plants around the sampled tile at, when the canopy has more
#: triangles than the view's budget (maizeviz_app.viewport.VIEW_BUDGET).
DISPLAY_LEVEL = "36"
#: The level of a canopy read from a mesh file.
MESH_LEVEL = "mesh"


def count(n: int, one: str, many: str | None = None) -> str:
    """``n`` and its noun, singular or plural ("1 plant", "2 leaves")."""
    return f"{n} {one if n == 1 else many or one + 's'}"


def open_points(study: StudyState, path: str | Path, layout: Any = None) -> None:
    """Read a points file (laid out as ``layout``, else tiled as the layout shown) in a
    job; then build it. The current canopy stays until it has loaded."""
    from maizeviz_app import jobs

    path = str(path)
    n = study.tile_n
    study.say(f"reading {path}")

    def load(job, p):
        loaded = jobs.load_points(p, (n, n), layout=layout)
        return loaded, Path(p).read_bytes()

    study.runner.run("load", f"reading {Path(path).name}", load, path,
                    on_done=lambda r: points_loaded(study, r[0], r[1], None, r[0].path),
                    on_error=lambda e: study.fail(e, "open points"))

def points_loaded(study: StudyState, loaded, points_bytes: bytes, project: str | None,
                  origin: str) -> None:
    """Points read (from a file or a project): they replace the study, then are built."""
    study.set_points(loaded, points_bytes, origin, project,
                    project is not None and study.project_layout)
    for w in loaded.warnings:
        study.say(f"note: {w}")
    for e in loaded.skipped:
        study.say(f"skipped: {e}")
    study.say(f"{count(len(loaded.leaves), 'leaf', 'leaves')} of "
             f"{count(len(loaded.plants), 'plant')}; "
             f"{len(loaded.layout.placements)} plants in the canopy")
    build(study)

def open_mesh(study: StudyState, path: str | Path, unit: str | None = None, up: str = "z",
              field: str | tuple[float, float, float, float] | None = None) -> None:
    """Read a canopy mesh in a job (:func:`maizeviz.canopy.from_mesh.read_mesh_canopy`:
    ``unit`` cm, m or mm, None: cm, refused when the size says otherwise; ``field`` x0,
    y0, x1, y1 cm, as numbers or text, None: the mesh's extent seen from above); it
    replaces the points: light, tables and exports work on it, the level and layout do
    not apply."""
    from maizeviz_app import jobs

    path = str(path)
    study.say(f"reading the canopy mesh {path}")
    runner, mesher = study.runner, study.mesher

    def work(job):
        from maizeviz.canopy.from_mesh import check_field, read_mesh_canopy
        from maizeviz.canopy.measures import TABLE2_COLUMNS, table2_row
        from maizeviz.cost import TooSlow, check, cover_cost

        t0 = time.perf_counter()
        ground = None if field is None else check_field(field)
        canopy, _mesh, notes = read_mesh_canopy(path, unit, up, ground)  # type: ignore[arg-type]
        read_s = time.perf_counter() - t0
        job.check()
        try:       # the ground cover is measured over the whole field, as for points
            check([[cover_cost(canopy.layout, jobs.APP_COVER_RESOLUTION_CM)]])
        except TooSlow as exc:
            raise MaizevizError(f"{exc.estimate}: give a smaller field",
                                quantity="field") from None
        t0 = time.perf_counter()
        m = runner.cover_process.call("measure", object(), canopy,
                                      (jobs.APP_COVER_RESOLUTION_CM,), job)
        measure_s = time.perf_counter() - t0
        mesh = mesher(job, canopy, None, True) if mesher is not None else None
        row = table2_row(m, read_s, MESH_LEVEL)
        return notes, (canopy, m, read_s, measure_s, mesh, tuple(TABLE2_COLUMNS), row)

    study.runner.run("load", f"reading {Path(path).name}", work,
                    on_done=lambda out: _mesh_read(study, path, *out),
                    on_error=lambda e: study.fail(e, "open mesh"))

def _mesh_read(study: StudyState, path: str, notes: list, parts: tuple) -> None:
    from maizeviz_app import jobs

    study.set_mesh(path)
    canopy, m, read_s, measure_s, mesh, columns, row = parts
    for note in [*notes, *canopy.layout.warnings]:         # the latter say the field
        study.say(f"note: {note}")
    _built(study, jobs.Built(MESH_LEVEL, MESH_LEVEL, canopy, m, read_s, measure_s, mesh,
                           columns, row, study.serial))

def build(study: StudyState) -> None:
    """Build the canopy at ``settings.canopy`` (level, area preservation) in a job; a
    running build is superseded. Work too large for this machine is refused; work over a
    quarter of an hour is asked about (:attr:`confirm_slow`)."""
    if study.loaded is None or study.closing:
        return
    from maizeviz.cost import cover_cost, layout_cost
    from maizeviz.mesh.levels import parse_level
    from maizeviz_app import jobs

    loaded = study.loaded
    level, preserve = study.settings.canopy.level, study.settings.canopy.preserve_area
    serial, runner, mesher = study.serial, study.runner, study.mesher
    key = object()

    def work(job):
        from maizeviz.canopy.measures import TABLE2_COLUMNS, table2_row

        canopy, build_s, label = jobs.build(loaded, level, preserve, job.report)
        job.check()
        t0 = time.perf_counter()
        m = runner.cover_process.call("measure", key, canopy,
                                      (jobs.APP_COVER_RESOLUTION_CM,), job)
        measure_s = time.perf_counter() - t0

        def coarse():
            if level == DISPLAY_LEVEL:
                return None
            return jobs.build(loaded, DISPLAY_LEVEL, preserve)[0]

        mesh = mesher(job, canopy, coarse, False) if mesher is not None else None
        return jobs.Built(level, label, canopy, m, build_s, measure_s, mesh,
                          tuple(TABLE2_COLUMNS), table2_row(m, build_s, label), serial)

    stage = [layout_cost(loaded.leaves, loaded.layout, parse_level(level)),
             cover_cost(loaded.layout, jobs.APP_COVER_RESOLUTION_CM)]
    if not study.affordable([stage], "build"):
        built = study.built
        shown = built is not None and built.serial == serial
        if built is not None and shown:     # the level shown stays the level set
            study.apply_settings("canopy", {"level": built.level})
        study.build_pending.emit("" if shown else
                                "not built: choose a coarser level or fewer plants")
        return
    study.build_pending.emit(f"building: {parse_level(level).description}…")
    study.runner.run("build", f"building {parse_level(level).label}", work,
                    on_done=lambda b: _built(study, b), on_error=lambda e: study.fail(e, "build"))

def _built(study: StudyState, built) -> None:
    if not study.show_built(built):
        return
    lighting.adopt_pending_runs(study)
    lighting.show_brought_back(study)
    lighting.complete_runs(study)
    study.view_light.emit(False)
    study.built_shown.emit(built.label)

def cancel(study: StudyState, kind: str | None = None) -> list[str]:
    """Stop the jobs of ``kind`` under way (every kind: None); what was stopped."""
    running = [j for j in study.runner.running() if kind is None or j.kind == kind]
    if not running:
        return []
    study.runner.cancel(kind)
    if kind in (None, "light"):
        study.light_running.emit("")
    if kind in (None, "build"):
        study.build_pending.emit("")
    study.say("cancelled: " + ", ".join(j.label for j in running))
    return [j.label for j in running]
