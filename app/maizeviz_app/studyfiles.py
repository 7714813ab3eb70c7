"""The model's file actions: open and save a project, export what the study holds (no Qt: the
work goes to the model's runner, files are written atomically).

Functions over the study's state (``study``: a :class:`maizeviz_app.state.StudyState`, whose
public changes they call); :class:`maizeviz_app.model.StudyModel` offers them as methods.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from maizeviz.errors import MaizevizError
from maizeviz_app import building

if TYPE_CHECKING:
    from maizeviz_app.state import StudyState


def open_project(study: StudyState, path: str | Path) -> None:
    """Read a project in a job: its points, layout, settings and light results (which
    join the comparison once the canopy is built). The current canopy stays if the
    project cannot be used."""
    from maizeviz_app import jobs, saved_state
    from maizeviz_app.settings import StudySettings

    path = str(path)
    study.say(f"opening the project {path}")
    cache = study.cache_folder

    def work(job):
        from maizeviz.mesh.levels import parse_level
        from maizeviz.project import study as stored

        opened = stored.open_project(path, cache)
        tile, level, preserve = saved_state.canopy_settings(opened)
        light = saved_state.light_settings(opened)
        StudySettings().apply_light_doc(light)      # each value checked before any change
        saved_state.view_settings(opened)
        found = jobs.load_points(opened.points_path, (tile, tile),
                                 shown_name=opened.shown_name)
        layout = stored.restore_layout(opened, found.plants) or found.layout
        stored.check_canopy_fits(found.leaves, layout, parse_level(level), path)
        results, dropped = stored.results_on(opened, layout, found.leaves)
        opened.notes.extend(dropped)
        runs = [saved_state.stored_run(r, path) for r in results]
        loaded = replace(found, layout=layout)
        return opened, loaded, (tile, level, preserve), light, runs

    study.runner.run("load", f"opening {Path(path).name}", work,
                    on_done=lambda out: _project_read(study, out),
                    on_error=lambda e: study.fail(e, "open project"))

def _project_read(study: StudyState, out) -> None:
    opened, loaded, (tile, level, preserve), light, runs = out
    for note in opened.notes:
        study.say(f"note: {note}")
    study.apply_settings("canopy", {"tile": tile, "level": level,
                                   "preserve_area": preserve})
    with study.quietly():
        study.settings.apply_light_doc(light)
        study.colour.update_from_doc(opened.view, opened.path)
    study.project_layout = opened.project.layout is not None
    study.pending_runs = list(runs)
    # what the 3D view was coloured by when saved, shown once the results are complete
    study.colouring_to_restore = opened.view.get("colouring")
    building.points_loaded(study, loaded, opened.project.points_csv, opened.path,
                       opened.project.points_path)

def save_project(study: StudyState, path: str | Path) -> bool:
    """Write the project (points, layout, settings, light results) in a job; False (and
    said why) when there is nothing a project can hold."""
    if study.mesh_path is not None:
        study.say("error: a canopy read from a mesh file is not saved in a project (a "
                 "project keeps digitized points); export its light instead", error=True)
        return False
    if study.loaded is None:
        study.say("error: nothing to save yet: open a points file first", error=True)
        return False
    from maizeviz_app import saved_state

    loaded, data, origin = study.loaded, study.points_bytes, study.points_origin
    layout = loaded.layout if study.layout_edited else None   # else: the tiling, exactly
    canopy = dict(study.settings.canopy_doc(), tile=study.tile_n)
    light = study.settings.light_doc()
    view = {**study.colour.to_doc(), "colouring": study.view.colouring}
    runs = []
    sun_settings = study.runs.settings.get("sun")
    optics = sun_settings[2] if isinstance(sun_settings, tuple) and \
        len(sun_settings) == 3 else None
    for r in study.runs.in_order():
        runs.append((r.label, r.result,
                     saved_state.settings_doc(r.kind, study.runs.settings.get(r.kind))))
        if r.balance is not None:              # the sun's absorbed light beside it
            runs.append((r.label, r.extra.light, saved_state.settings_doc("absorbed",
                                                                       optics)))
    path = str(path)

    def work(job):
        from maizeviz.io.archive import save_project
        from maizeviz.project.study import make_project

        # the runs were all traced on the layout shown (a layout edit clears them)
        proj = make_project(origin, data, layout, loaded.layout, canopy, light, runs, view)
        save_project(path, proj)
        return path

    study.runner.run("save", f"saving {Path(path).name}", work,
                     on_done=lambda p: _project_saved(study, p),
                     on_error=lambda e: study.fail(e, "save project"), supersede=False)
    return True

def _project_saved(study: StudyState, path: str) -> None:
    study.mark_saved(path)
    study.say(f"saved the project {path}")
    study.project_saved.emit(path)

def export(study: StudyState, what: str, path: str | Path) -> bool:
    """Write ``what`` (canopy, table, measures, heatmap, plot; steps, leaves, plants, day
    for a sky or a day) to ``path`` in a job, atomically; False (and said why) when there
    is nothing of it yet."""
    from maizeviz_app.exports import export_job

    path = str(path)
    f = study.figures
    try:
        work, args = export_job(what, path, study, (f.shown_kind, dict(f.shown_for),
                                                   f.shown_height))
    except MaizevizError as exc:
        study.fail(exc, "export")
        return False

    def done(p):
        study.say(f"exported {p}")
        study.exported.emit(p)

    study.runner.run("export", f"exporting {Path(path).name}", work, *args, on_done=done,
                    on_error=lambda e: study.fail(e, "export"), supersede=False)
    return True
