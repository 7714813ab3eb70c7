"""The model's light actions: compute the light the settings choose (sun, sky or day) on the
canopy shown, sun angles from a place and time, the heatmap of another height, and the results
of a project made whole against their canopy (no Qt: the work goes to the model's runner, the
Embree work to its light process).

Functions over the study's state (``study``: a :class:`maizeviz_app.state.StudyState`, whose
public changes they call); :class:`maizeviz_app.model.StudyModel` offers them as methods.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from maizeviz.errors import MaizevizError
from maizeviz_app.runs import MODES, Run, day_summary, plot_title, run_info, run_warnings
from maizeviz_app.settings import InputProblem

if TYPE_CHECKING:
    from maizeviz_app.jobs import Built
    from maizeviz_app.state import StudyState

#: What a light computation is called while it runs, per light.
RUNNING_TEXT = {"sun": "computing direct light", "sky": "computing diffuse light",
                "day": "computing the day's light"}


def light_job(study: StudyState) -> tuple[str, str, tuple, Any, Any, Any]:
    """What a light computation of the settings would trace: (light, core op, its
    arguments (the last: whether the stalks take light), the settings results are compared
    by, heights, optics or None).

    Raises
    ------
    InputProblem, MaizevizError
        A setting that cannot be used, naming it (``quantity``).
    """
    s = study.settings
    mode, stalks = s.light.mode, s.light.stalks
    optics = None
    if mode == "sun":
        request = s.sun_request()
        optics = s.optics_spec()
        compared = (round(request.sun.zenith_deg, 6), round(request.sun.azimuth_deg, 6),
                    optics)
        return mode, "light", (request, stalks), compared, request.heights_cm, optics
    sampling = s.sampling_spec()
    sky = s.sky_spec()
    if mode == "sky":
        return mode, "sky", (sampling, sky, stalks), sky, sampling.heights_cm, None
    day = s.day_spec()
    return mode, "period", (sampling, sky, day, stalks), (day, sky), sampling.heights_cm, None

def compute_light(study: StudyState) -> bool:
    """Compute the light the settings choose (sun, sky or day) on the canopy shown, in the
    light process (which keeps the canopy's Embree scene); False if it did not start."""
    if study.closing:
        return False
    if study.canopy is None or study.built is None:
        study.say("error: no canopy yet: open a points file first", error=True)
        return False
    mode = study.settings.light.mode
    try:
        mode, op, args, compared, heights, optics = light_job(study)
    except (InputProblem, MaizevizError) as exc:
        study.fail(exc, "light", mode)
        return False
    if not study.affordable([_light_costs(study.built, mode, args, heights, optics)], "light"):
        return False
    canopy, label = study.canopy, study.built.label
    signature = study.signature(label)
    sampling_key = study.settings.sampling_key(heights)
    key, runner = study.canopy_key, study.runner

    def work(job):
        out = runner.light_process.call(op, key, canopy, args, job)
        job.check()
        if mode == "sun":
            from maizeviz.light.results.painting import sun_painting

            absorbed = None
            if optics is not None:              # leaves with optics: absorbed light too
                absorbed = runner.light_process.call("absorbed", key, canopy,
                                                     (args[0], optics, args[-1]), job)
                job.check()
            painting = sun_painting(canopy, out)
            run = Run(label, signature, out, painting.classes, extra=absorbed,
                      painting=painting, stalks=args[-1])
        else:
            run = Run(label, signature, out.light, None, mode, out, stalks=args[-1])
        return run, compared, sampling_key

    study.light_running.emit(f"{RUNNING_TEXT[mode]} on {label}…")
    study.runner.run("light", f"{mode} light on {label}", work,
                     on_done=lambda out: _lit(study, out),
                     on_error=lambda e: _light_failed(study, e, mode))
    return True

def _light_costs(built: Built, mode: str, args: tuple, heights, optics=None) -> list:
    """What a light run of ``mode`` on the canopy ``built`` will cost (``maizeviz.cost``): its
    rays (times the directions: the sun, the sky's, a day's steps; with leaf optics, the
    absorbed light's beams and their scattering) and its heatmaps."""
    from maizeviz.cost import light_costs
    from maizeviz_app.plots import HEATMAP_BIN_CM

    rect = args[0].rect or built.canopy.layout.centre_bounds
    directions = 1
    if optics is not None:                          # the beams, each scattered ~3 times
        directions += 3 * (1 + (46 if optics.diffuse_w_m2 > 0 else 0))
    if mode != "sun":
        directions = max(args[1].directions, 1)
        if mode == "day":
            directions += args[2].steps_bound()
    return light_costs(rect, args[0].density, len(heights), directions, 1, HEATMAP_BIN_CM,
                       built.measures.triangles)

def _light_failed(study: StudyState, exc: BaseException, mode: str = "sun") -> None:
    study.light_running.emit("")
    study.fail(exc, "light", mode)

def _lit(study: StudyState, out) -> None:
    """A light result: table, summary, plants and colours change together, then its figures
    (when drawn, :attr:`StudyState.draw_figures`); nothing shown is dropped unless a new
    comparison starts."""
    run, compared, sampling_key = out
    study.light_running.emit("")
    if run.signature[0] != study.serial:
        return
    if study.add_run(run, compared, sampling_key, run_info(run)):
        study.say("note: the light settings changed; the comparison starts again")
    r = run.result
    summary = ""
    if run.kind == "day":
        summary = day_summary(r)
        study.set_summary(summary)
    elif study.runs.of_kind("day") is None:
        study.set_summary("")
    if run.kind != "sun" or run.extra is not None:
        study.set_plants_run(run)
    elif study.runs.of_kind("sky") is None and study.runs.of_kind("day") is None:
        study.set_plants_run(None)
    f = study.figures
    f.keep_only({k for k in f.shown_for if study.runs.of_kind(k) is not None} | {run.kind})
    for w in run_warnings(run):
        study.say(f"{'note' if 'sun never rises' in w else 'warning'}: {w}")
    if study.shown_signature == run.signature:
        study.view_light.emit(True)
    study.light_added.emit(run)
    if run.kind == "day":
        study.say(summary.replace("\n", "; "), status_only=True)
    else:
        study.say(f"{run.name}: transmission "
                 + ", ".join(f"{t:.3f}" for t in run.transmission) + " at "
                 + ", ".join(f"{h:g}" for h in r.heights_cm) + " cm", status_only=True)
    if study.draw_figures:
        draw_figures(study, run)                # light_shown once they are drawn
    else:
        study.light_shown.emit()


def draw_figures(study: StudyState, run: Run) -> None:
    """The figures of a new light result, drawn in a job of their own (matplotlib, 0.3-1 s a
    figure): its heatmap at the height shown (the others when asked for,
    :func:`draw_heatmap`) and the transmission plot of every result compared; then
    ``light_shown``. Only where they are shown (:attr:`StudyState.draw_figures`)."""
    from maizeviz_app import plots

    f = study.figures
    first = max(f.shown_index, 0)
    look = plots.Look.of(study.colour, f.shown_for).sharing(run.kind, run.result)
    curves, title = study.runs.curves(), plot_title(study.runs)

    canvas, plot_canvas = f.canvases.get("heatmap"), f.canvases.get("plot")

    def work(job):
        maps = plots.heatmap_images(run.result, first=first, check=job.check, kind=run.kind,
                                    look=look, canvas=canvas)
        return maps, plots.rgba(plots.transmission_figure(curves, title, canvas=plot_canvas))

    def done(out) -> None:
        maps, plot = out
        if study.runs.of_kind(run.kind) is run:         # else: a newer result has its own
            f.set_maps(run.kind, run, maps)
            if study.colour.shared:             # the others' scale includes this run
                f.restyle(keep=run.kind)
            f.set_plot(plot)
        study.light_shown.emit()

    study.runner.run("figures", "drawing the light figures", work, on_done=done,
                     on_error=lambda e: study.fail(e, "light"))


def draw_heatmap(study: StudyState, kind: str, index: int) -> None:
    """The heatmap of another height of a result shown, drawn in a job."""
    run = study.figures.shown_for.get(kind)
    if run is None:
        return
    from maizeviz_app import plots

    result = run.result
    height = float(result.heights_cm[index])
    look = plots.Look.of(study.colour, study.figures.shown_for)
    canvas = study.figures.canvases.get("heatmap")

    def done(rgba) -> None:
        study.figures.set_map(kind, run, index, rgba)

    study.runner.run("heatmap", f"drawing the heatmap at {height:g} cm",
                     lambda job: plots.heatmap_image(result, height, kind=kind, look=look,
                                                     canvas=canvas),
                     on_done=done, on_error=lambda e: study.fail(e, "light"))


def refit_figures(study: StudyState, which: str) -> None:
    """Where the ``heatmap`` or the ``plot`` is shown changed size: the maps are drawn again
    when shown (the one shown at once), the plot in a job, each for its new canvas."""
    f = study.figures
    if which == "heatmap":
        if f.maps:
            f.restyle(keep=None, hold=True)     # the old size shown until the new drawn
        return
    if f.plot is None or not study.runs.runs:
        return
    from maizeviz_app import plots

    curves, title, canvas = study.runs.curves(), plot_title(study.runs), f.canvases.get("plot")
    study.runner.run("plot", "drawing the transmission plot",
                     lambda job: plots.rgba(plots.transmission_figure(curves, title,
                                                                      canvas=canvas)),
                     on_done=f.set_plot, on_error=lambda e: study.fail(e, "light"))

def sun_from_place(study: StudyState) -> None:
    """Sun angles from the date, time and place of ``settings.sun.place`` (pvlib, in a
    job); they become the sun's settings."""
    text = study.settings.sun.place

    def work(job, t):
        from maizeviz.light.sources.sun import sun_at

        parts = t.split()
        if len(parts) != 5:
            raise MaizevizError("write the place as: YYYY-MM-DD HH:MM latitude longitude "
                                "time zone", quantity="place")
        date, clock, lat, lon, tz = parts
        try:
            la, lo = float(lat), float(lon)
        except ValueError:
            raise MaizevizError(f"latitude and longitude must be numbers, got '{lat}' "
                                f"'{lon}'", quantity="place") from None
        return sun_at(date, clock, la, lo, tz)

    study.runner.run("sun", "sun position", work, text, on_done=lambda sun: _sun_found(study, sun),
                    on_error=lambda e: study.fail(e, "sun", "sun"))

def _sun_found(study: StudyState, sun) -> None:
    # the sun's range (what its widget offers) holds a risen sun
    study.settings.set("sun", {"zenith_deg": round(min(sun.zenith_deg, 89.9), 2),
                              "azimuth_deg": round(sun.azimuth_deg % 360.0, 2)})
    study.say(f"sun at {sun.when}: zenith {sun.zenith_deg:.2f}°, azimuth "
             f"{sun.azimuth_deg:.2f}°")

def offset_zone(hours: float | None) -> str | None:
    """The IANA zone of a fixed UTC offset of whole hours ("Etc/GMT-1" is UTC+01:00: the
    Etc names count west), "UTC" for 0; None for no offset or one of part hours (no IANA
    name holds it)."""
    if hours is None or hours != int(hours) or not -14 <= hours <= 12:
        return None
    h = int(hours)
    return "UTC" if h == 0 else f"Etc/GMT{-h:+d}"


def choose_weather(study: StudyState, path: str) -> None:
    """A weather file chosen: the day's source becomes it and, when its header names a place
    (EPW, TMY3, PSM), the day's latitude and longitude become that place, and its time zone
    the file's own (the fixed offset its times are written in), in one step of the undo
    history (read in a job: pvlib's first import takes seconds). A sun traced away from
    where the file was measured would not match its irradiance, and dates and clock times
    are read in the file's zone."""
    def work(job, p):
        from maizeviz.io.weather_files import weather_place

        return weather_place(p)

    def done(place: dict) -> None:
        values: dict[str, Any] = {"weather": path, "source": "weather"}
        lat, lon = place.get("latitude"), place.get("longitude")
        if lat is not None and lon is not None and -90 <= lat <= 90 and -180 <= lon <= 180:
            values.update(latitude=float(lat), longitude=float(lon))
            named = f", {place['name']}" if place.get("name") else ""
            zone = offset_zone(place.get("utc_offset_h"))
            if zone is not None:
                values["tz"] = zone
            clock = f", time zone {zone}" if zone is not None else ""
            study.say(f"place: latitude {lat:g}, longitude {lon:g}{named}{clock} (the header "
                      f"of {Path(path).name})")
        with study.history.step(f"weather file {Path(path).name}"):
            study.settings.set("day", values)

    study.runner.run("weather", f"reading the place of {Path(path).name}", work, path,
                     on_done=done, on_error=lambda e: study.fail(e, "weather", "day"))

# ------------------------------------------------------------------ a project's results
def adopt_pending_runs(study: StudyState) -> None:
    """Light results of an opened project (sun, sky and day) join the comparison once its
    canopy is built, shown as after a fresh run: table, plot, heatmaps, the day's summary,
    the plants' light and the canopy's colours (those of the results traced on the canopy
    shown are computed against it, the others' when their level is shown)."""
    if not study.pending_runs or study.built is None:
        return
    from maizeviz_app import jobs

    pending, study.pending_runs = study.pending_runs, []
    absorbed = {s.label: s for s in pending if s.kind == "absorbed"}
    pending = [s for s in pending if s.kind != "absorbed"]
    for stored in pending:
        label, result, kind, compared = stored
        extra = None
        if kind == "sun":
            kept = absorbed.get(label)
            compared = (round(result.sun.zenith_deg, 6), round(result.sun.azimuth_deg, 6),
                        kept.settings if kept is not None else None)
            if kept is not None:                # computed against the canopy later
                extra = jobs.Absorbed(kept.result, None, None)
            density = result.density
        elif kind == "sky":
            density = result.density
        else:
            density = result.sky.density if result.sky is not None else \
                study.settings.sampling.density
        stalks = traced_stalks(result, kind, _leaf_triangles(study, label))
        sampling = (tuple(float(h) for h in result.heights_cm), density,
                    bool(getattr(result, "periodic", study.settings.sampling.periodic)),
                    stalks)
        study.add_run(Run(label, study.signature(label), result, None, kind, extra,
                          stalks=stalks),
                     compared, sampling, f"{len(pending)} light result(s) from the project",
                     saved=True)
    show_kept_runs(study)


def show_brought_back(study: StudyState) -> None:
    """Light results set aside by a layout edit and back with their stands (Undo): once the
    canopy is built on them, shown whole as before the edit (table, plot, heatmaps, the
    day's summary, the plants' light, the canopy's colours), nothing traced again."""
    if not study.brought_back or study.built is None:
        return
    study.brought_back = False
    show_kept_runs(study)


def show_kept_runs(study: StudyState) -> None:
    """The results the study holds (a project's, or some brought back) shown as after a
    fresh run, with the canopy shown."""
    if study.built is None:
        return
    here = study.signature(study.built.label)
    shown = {}
    for kind in MODES:
        run = study.runs.for_signature(here, kind) or study.runs.of_kind(kind)
        if run is not None:
            shown[kind] = run
    if not shown:
        return
    day = shown.get("day")
    study.set_summary(day_summary(day.result) if day is not None else "")
    study.set_plants_run(light_per_plant_run(study))
    latest = study.runs.latest(here) or study.runs.last
    order = sorted(shown, key=lambda k: latest is not None and k == latest.kind)
    curves = study.runs.curves()
    title = plot_title(study.runs)
    study.figures.shown_for = dict(shown)
    study.view_light.emit(True)
    restore_colouring(study)
    if study.draw_figures:
        _draw_project_figures(study, shown, order, curves, title)
    elif study.runner.current("complete") is None:
        study.light_shown.emit()


def _draw_project_figures(study: StudyState, shown: dict, order: list, curves, title: str
                          ) -> None:
    """The heatmaps of a project's results shown (``shown``: light -> run, drawn in
    ``order``) and the transmission plot, in a job; then ``light_shown``."""
    from maizeviz_app import plots

    results = [(k, shown[k].result) for k in order]
    look = plots.Look.of(study.colour, shown)
    canvas = study.figures.canvases.get("heatmap")
    plot_canvas = study.figures.canvases.get("plot")

    def work(job):
        maps = [(k, plots.heatmap_images(r, check=job.check, kind=k, look=look, canvas=canvas))
                for k, r in results]
        plot = plots.rgba(plots.transmission_figure(curves, title, canvas=plot_canvas))
        return maps, plot

    def done(out):
        for kind, maps in out[0]:
            if study.figures.shown_for.get(kind) is shown[kind]:
                study.figures.set_maps(kind, shown[kind], maps)
        study.figures.set_plot(out[1])
        if study.runner.current("complete") is None:        # else: once it is done
            study.light_shown.emit()

    study.runner.run("figures", "drawing the light figures", work, on_done=done,
                     on_error=lambda e: study.fail(e, "light"))


def _leaf_triangles(study: StudyState, label: str) -> int | None:
    """The leaf triangles of the study's canopy at the level ``label`` (None: unknown)."""
    if study.built is not None and study.built.label == label:
        return study.built.canopy.n_triangles
    if study.loaded is None:
        return None
    from maizeviz.project.study import canopy_triangles

    counts = canopy_triangles(study.loaded.leaves, study.loaded.layout, label)
    return counts[0] if counts is not None else None


def traced_stalks(result: Any, kind: str, n_leaf_triangles: int | None) -> bool:
    """Whether a light result (a sun's ``LightResult``, a ``SkyLight`` or a day's
    ``PeriodLight``, ``kind`` sun, sky or day) was traced with its canopy's stalks: its
    per-triangle light runs past the canopy's ``n_leaf_triangles`` (the leaves then the
    stalks). Where either is unknown, the stalks' absorbed light in its balance says it,
    else it counts as traced (the app's default)."""
    if kind == "sun":
        per = result.first_hits
    elif kind == "sky":
        per = getattr(result, "triangle_share", None)
    else:
        per = getattr(result, "triangle_direct_mol", None)
    if per is not None and n_leaf_triangles is not None:
        return len(per) > n_leaf_triangles
    balance = getattr(result, "balance", None)
    return balance is None or bool(balance.absorbed_stalks)


def light_per_plant_run(study: StudyState) -> Run | None:
    """The latest result with light per plant to show (:meth:`LightRuns.with_plants`)."""
    return study.runs.with_plants()

def complete_runs(study: StudyState) -> None:
    """Results read from a project that were traced on the canopy shown get what the
    window shows of them, computed against it in a job: a sun's light class per
    triangle (and its absorbed light per leaf, with the CO2 assimilation of the leaf model
    its optics were stored with), a sky's or day's light per leaf and plant; then the
    plants' light and the canopy's colours follow."""
    if study.built is None or study.canopy is None:
        return
    here, canopy = study.shown_signature, study.canopy
    todo = runs_to_complete(study.runs.runs.values(), here, canopy.n_triangles)
    if not todo:
        return
    sun = study.runs.settings.get("sun")            # (zenith, azimuth, OpticsSpec or None)
    spec = sun[2] if isinstance(sun, tuple) and len(sun) == 3 else None

    def work(job):
        from maizeviz.light.results.painting import sun_painting
        from maizeviz_app import jobs

        done: list[Any] = []
        for run in todo:
            job.check()
            if run.kind == "sun":
                absorbed = None if run.extra is None else \
                    jobs.absorbed_of(canopy, run.extra.light, spec)
                done.append((sun_painting(canopy, run.result), absorbed))
            else:
                done.append(jobs.diffuse_of(canopy, run.result, run.kind))
        return done

    def adopt(done):
        for run, value in zip(todo, done):
            if run.kind == "sun":
                run.painting, absorbed = value
                run.classes = run.painting.classes
                if absorbed is not None:
                    run.extra = absorbed
            else:
                run.extra = value
        if study.shown_signature == here:
            study.set_plants_run(light_per_plant_run(study))
            # the results table gains what was computed here (a sun's CO2 row), its text kept
            study.runs_changed.emit(study.runs, study.runs_info)
            study.view_light.emit(True)
            restore_colouring(study)
            if study.runner.current("figures") is None:     # else: when they are drawn
                study.light_shown.emit()

    study.runner.run("complete", "light per leaf of the project's results", work,
                    on_done=adopt, on_error=lambda e: study.fail(e, "light"))


def restore_colouring(study: StudyState) -> None:
    """The 3D view coloured as it was when the project was saved (``colouring`` in its view
    settings), once what it shows is computed: a CO2 colouring waits for the assimilation."""
    from maizeviz_app.options import COLOURINGS

    wanted = study.colouring_to_restore
    if wanted not in COLOURINGS:
        return
    last = study.runs.latest(study.shown_signature, ("sun",))
    if wanted == "assimilation" and getattr(getattr(last, "extra", None), "assimilation",
                                            None) is None:
        return
    study.colouring_to_restore = None
    study.view.colouring = wanted


def runs_to_complete(runs, here, n: int) -> list:
    """The runs traced on the canopy of signature ``here`` (of ``n`` leaf triangles) that
    lack what the window shows of them: a sun's light classes (or its absorbed light's per
    leaf), a sky's or a day's light per leaf; runs holding light for fewer triangles than
    the canopy are left alone."""
    todo = []
    for run in runs:
        if run.signature != here:
            continue
        r = run.result
        if run.kind == "sun" and (run.classes is None or run.extra is not None
                                  and run.extra.leaf_value is None):
            if r.first_hits is not None and len(r.first_hits) >= n:
                todo.append(run)
        elif run.kind != "sun" and run.extra is None:
            per_triangle = r.triangle_share if run.kind == "sky" else r.triangle_direct_mol
            if len(per_triangle) >= n:
                todo.append(run)
    return todo
