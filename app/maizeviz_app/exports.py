"""Exports of the study open in the window, as work for a worker thread (no Qt here): the
canopy mesh with its light, the tables, the figures. Every file is written atomically."""

from __future__ import annotations

import csv

from maizeviz.errors import MaizevizError
from maizeviz_app.runs import day_title, plot_title
from maizeviz_app.state import StudyState


def export_job(what: str, path: str, model: StudyState, heatmap: tuple = (None, {}, None)):
    """The work writing ``what`` of the study in ``model`` to ``path`` (atomically), to run
    in a worker as ``work(job, *args)``: returns ``(work, args)``. ``heatmap``: the light
    whose map is shown, the run shown for each light, the height shown (cm).

    ``what``: canopy (mesh with each triangle's light: its class and its leaf's sunlit share
    for a sun, its leaf's light per m2 of leaf for a sky or a day), table (transmission by height),
    measures (Table 2), heatmap, plot; steps, leaves, plants, day (of a sky or a day). Nothing
    to export yet: MaizevizError saying what to do first."""
    if what == "canopy":
        return _canopy_job(path, model)
    if what == "measures":
        return _measures_job(path, model)
    if what in ("steps", "leaves", "plants", "day"):
        return _diffuse_job(what, path, model)
    if model.runs.last is None:
        raise MaizevizError("no light result to export yet: compute light first")
    if what == "table":
        return _table_job(path, model)
    if what == "heatmap":
        return _heatmap_job(path, model, heatmap)
    if what == "plot":
        return _plot_job(path, model)
    raise MaizevizError(f"unknown export '{what}'")


def _canopy_job(path: str, model: StudyState):
    """The canopy's mesh with each triangle's light (the sun's class and sunlit share, the
    sky's and the day's light per m2 of leaf)."""
    built = model.built
    if built is None:
        raise MaizevizError("no canopy to export yet")
    canopy = built.canopy
    signature = model.signature(built.label)
    # the names of `maizeviz light --export` (maizeviz.light.report.mesh_export.LIGHT_ARRAYS)
    cells = {}
    run = model.runs.for_signature(signature)
    if run is not None and run.classes is not None:
        cells["sun_class"] = run.classes.astype("int32")
    if run is not None and run.painting is not None:   # honest where triangles are small
        cells["sunlit_share"] = run.painting.share.astype("float32")
    if run is not None and getattr(run.extra, "leaf_value", None) is not None:
        cells["absorbed_w_per_m2_leaf"] = run.extra.leaf_value.astype("float64")
    if run is not None and getattr(run.extra, "gross_value", None) is not None:
        cells["gross_umol_co2_per_m2_leaf_s"] = run.extra.gross_value.astype("float64")
    for kind, name in (("sky", "diffuse_cm2_per_cm2_leaf"), ("day", "par_mol_per_m2_leaf")):
        run = model.runs.for_signature(signature, kind)
        if run is not None and run.extra is not None and run.extra.leaf_value is not None:
            cells[name] = run.extra.leaf_value.astype("float64")

    def work(job):
        from maizeviz.canopy.export import export_canopy

        export_canopy(path, canopy, cell_data=cells)
        return path
    return work, ()


def _measures_job(path: str, model: StudyState):
    """Table 2's measures of the canopies built."""
    if not model.measures_rows:
        raise MaizevizError("no canopy measures to export yet")
    rows = list(model.measures_rows.values())

    def work(job):
        from maizeviz.io.atomic import write_rows

        write_rows(path, [{k: v.replace(",", "") for k, v in r.items()} for r in rows])
        return path
    return work, ()


def _table_job(path: str, model: StudyState):
    """Transmission by height of the runs compared."""
    header, table_rows = model.runs.table()

    def work(job):
        from maizeviz.io.atomic import atomic_open

        with atomic_open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["height_cm"] + [f"transmission {h}" for h in header[1:]])
            w.writerows(table_rows)
        return path
    return work, ()


def _heatmap_job(path: str, model: StudyState, heatmap: tuple):
    """The heatmap shown (its light, run and height), as shown."""
    shown_kind, shown_runs, height = heatmap
    last = model.runs.last
    assert last is not None                       # export_job refused it before
    kind = shown_kind or last.kind
    run = shown_runs.get(kind) or last
    kind = run.kind
    if height is None:
        height = float(run.result.heights_cm[0])
    result = run.result
    from maizeviz_app.plots import Look

    look = Look.of(model.colour, shown_runs or {kind: run})    # as shown

    def work(job):
        from maizeviz.light.report.heatmap import save_figure
        from maizeviz_app.plots import heatmap_figure_of

        save_figure(heatmap_figure_of(result, height, kind, look=look), path)
        return path
    return work, ()


def _plot_job(path: str, model: StudyState):
    """The transmission curves of the runs compared."""
    from maizeviz_app import plots

    curves = model.runs.curves()
    title = plot_title(model.runs)

    def work(job):
        from maizeviz.light.report.heatmap import save_figure

        save_figure(plots.transmission_figure(curves, title, width_in=7, dpi=110), path)
        return path
    return work, ()


def _diffuse_job(what: str, path: str, model: StudyState):
    """The day's steps CSV and figure (the last day's); the per-leaf and per-plant CSV of the
    latest result with light per leaf: a sky, a day, or a sun traced with leaf optics (its
    absorbed light, and its CO2 assimilation with a leaf model)."""
    day = model.runs.of_kind("day")
    if what in ("steps", "day") and day is None:
        raise MaizevizError("no day computed yet: choose Day in the light panel and "
                            "compute the day's light first")
    run = day if what in ("steps", "day") else model.runs.with_plants()
    if run is None:
        raise MaizevizError("no light per leaf computed yet: compute a sky, a day, or a sun "
                            "with leaf optics first")
    if run.kind == "sun":
        return _absorbed_table_job(what, path, run, model)
    light, extra, label = run.result, run.extra, run.label
    if what == "steps":
        def work(job):
            from maizeviz.light.report.tables import write_steps

            write_steps(path, light)
            return path
        return work, ()
    if what == "day":
        title = day_title(light, label)

        def work(job):
            from maizeviz.light.report.heatmap import save_figure
            from maizeviz.light.report.plots import day_figure

            save_figure(day_figure(light, title), path)
            return path
        return work, ()
    if extra is None:
        raise MaizevizError(f"the light per leaf of the {run.kind} on {label} is computed "
                            f"against its canopy: show level {label} first")
    rows = [dict(r, level=label) for r in extra.leaf_rows]

    def write_table(job):
        from maizeviz.io.atomic import write_rows
        from maizeviz.light.results.per_leaf import plant_light

        write_rows(path, rows if what == "leaves" else plant_light(rows))
        return path
    return write_table, ()


def _absorbed_table_job(what: str, path: str, run, model: StudyState):
    """The light each leaf or plant absorbed in a sun traced with leaf optics, with its
    gross CO2 assimilation when a leaf model was chosen (the tables of ``maizeviz light
    --leaf-light / --plant-light``)."""
    canopy, label = model.canopy, run.label
    if canopy is None or run.signature != model.shown_signature:
        raise MaizevizError(f"the light per leaf of the sun on {label} is computed against "
                            f"its canopy: show level {label} first")
    light, assimilation = run.extra.light, run.extra.assimilation

    def work(job):
        from maizeviz.io.atomic import write_rows

        kind = "leaf" if what == "leaves" else "plant"
        frame = light.table(kind, canopy)
        if assimilation is not None:
            keys = ["instance", "plant", "leaf"] if kind == "leaf" else ["instance"]
            carbon = assimilation.table(kind, canopy)
            new = [c for c in carbon.columns if c not in frame.columns or c in keys]
            frame = frame.merge(carbon[new], on=keys, how="left")
        frame.insert(0, "level", label)
        write_rows(path, frame.to_dict("records"))
        return path
    return work, ()
