"""Sky and day light results in project files (maizeviz_app.project_light, no Qt): a real sky
and a real clear day traced on two plants come back with every derived output equal, their
settings too; damaged records are refused with a ProjectError naming what is wrong; projects
with sun results only open as before."""

import copy
import json
import zipfile

import numpy as np
import pytest
from maizeviz_app.jobs import DaySpec, SkySpec
from maizeviz_app.saved_state import settings_doc, stored_run

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.io.archive import ProjectError, Record, load_project, save_project
from maizeviz.io.points import write_points
from maizeviz.leaf.fit import read_leaves
from maizeviz.leaf.synth import block_grids
from maizeviz.light.report.tables import leaf_values, write_steps
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.sources.irradiance import clear_sky_period
from maizeviz.light.sources.sky import make_sky
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.beam import trace_light
from maizeviz.light.trace.directions import trace_period, trace_sky
from maizeviz.mesh.levels import parse_level
from maizeviz.project import study
from maizeviz.project.records import DAY_KIND, SKY_KIND, run_from_record, run_record

HEIGHTS = (0.0, 60.0, 150.0)
SKY_SPEC = SkySpec("soc", 16, "auto")
DAY_SPEC = DaySpec("2005-08-01", 39.9, 116.4, "Asia/Shanghai", 180.0, None, None, 3.0, 2.1936)


@pytest.fixture(scope="module")
def points(tmp_path_factory):
    path = tmp_path_factory.mktemp("projlight") / "two.csv"
    write_points(path, block_grids(1, 2, seed=3))
    return path


@pytest.fixture(scope="module")
def layout(points):
    return layout_for(read_leaves(points).leaves, (1, 1))


@pytest.fixture(scope="module")
def canopy(points, layout):
    return build_canopy(read_leaves(points).leaves, layout, parse_level("16"))


class Reopened:
    """A project read back as the window reads it: the core's results, the panel's settings."""

    def __init__(self, path, layout):
        opened = study.open_project(path)
        results, dropped = study.results_on(opened, layout)
        self.notes = opened.notes + dropped
        self.runs = [stored_run(r, str(path)) for r in results]


def window_read(rec, where):
    """A record read as the window reads it (the core's result, the panel's settings)."""
    return stored_run(study.StoredResult(*run_from_record(rec, where)), where)


def make_project(points, data, layout, runs):
    return study.make_project(points, data, None, layout, {}, {}, runs)


@pytest.fixture(scope="module")
def sampling():
    return Sampling(HEIGHTS, 0.3, None, True, 2)


@pytest.fixture(scope="module")
def sky(canopy, sampling):
    return trace_sky(canopy, make_sky("soc", 16), sampling)


@pytest.fixture(scope="module")
def day(canopy, sampling, sky):
    period = clear_sky_period("2005-08-01", 39.9, 116.4, "Asia/Shanghai", step_min=180)
    return trace_period(canopy, period, sampling, sky)


@pytest.fixture(scope="module")
def sun(canopy):
    return trace_light(canopy, LightRequest(Sun(30.0, 150.0), Sampling(HEIGHTS, 0.3, None, True)))


@pytest.fixture(scope="module")
def reopened(points, layout, sun, sky, day, tmp_path_factory):
    """The three results saved in one project file and read back."""
    path = tmp_path_factory.mktemp("projlight") / "study.maizeviz"
    runs = [("16", sun), ("16", sky, settings_doc("sky", SKY_SPEC)),
            ("16", day, settings_doc("day", (DAY_SPEC, SKY_SPEC)))]
    save_project(path, make_project(str(points), points.read_bytes(), layout, runs))
    return path, Reopened(path, layout)


def same_map(a, b, height):
    ma, mb = a.transmission_map(height), b.transmission_map(height)
    np.testing.assert_array_equal(ma.transmission, mb.transmission)
    np.testing.assert_array_equal(ma.x_edges, mb.x_edges)
    np.testing.assert_array_equal(ma.y_edges, mb.y_edges)
    np.testing.assert_array_equal(ma.rays, mb.rays)
    assert ma.total == mb.total or (np.isnan(ma.total) and np.isnan(mb.total))


def same_sky_light(a, b):
    for name in ("kind", "split", "name", "description"):
        assert getattr(a.sky, name) == getattr(b.sky, name)
    for name in ("zenith_deg", "azimuth_deg", "solid_angle_sr", "weights", "directions"):
        np.testing.assert_array_equal(getattr(a.sky, name), getattr(b.sky, name))
    for name in ("heights_cm", "transmission", "per_direction", "per_direction_intercepted",
                 "triangle_share", "triangle_intercepted_cm2", "maps", "map_rays"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    for name in ("intercepted_fraction", "rect", "rays", "density", "level", "warnings",
                 "seconds", "periodic", "rect_area_cm2"):
        assert getattr(a, name) == getattr(b, name), name
    for h in a.heights_cm:
        same_map(a, b, h)


def test_the_file_holds_the_three_kinds_and_no_pickle(reopened):
    path, opened = reopened
    with zipfile.ZipFile(path) as zf:
        doc = json.loads(zf.read("project.json"))
    assert [r["kind"] for r in doc["results"]] == ["light", SKY_KIND, DAY_KIND]
    day = doc["results"][2]["meta"]
    assert day["period"]["tz"] == "Asia/Shanghai"
    assert day["period"]["times"][0] == "2005-08-01T07:30:00+08:00"
    assert day["period"]["start"] == "2005-08-01T00:00:00+08:00"
    assert [r.kind for r in opened.runs] == ["sun", "sky", "day"] and not opened.notes
    arrays = np.load(zipfile.ZipFile(path).open("arrays.npz"), allow_pickle=False)
    assert all(arrays[k].dtype.kind in "biuf" for k in arrays.files)


def test_a_sky_comes_back_with_every_output_and_its_settings(reopened, sky, canopy):
    _, opened = reopened
    label, back, kind, settings = opened.runs[1]
    assert (label, kind, settings) == ("16", "sky", SKY_SPEC)
    same_sky_light(sky, back)
    # the leaves' and plants' light, and the colours of the canopy
    rows, rows_back = sky.leaf_rows(canopy), back.leaf_rows(canopy)
    assert rows == rows_back
    np.testing.assert_array_equal(
        leaf_values(canopy, rows, "diffuse_intercepted_cm2", sky.rect, sky.periodic),
        leaf_values(canopy, rows_back, "diffuse_intercepted_cm2", back.rect, back.periodic))


def test_a_day_comes_back_with_every_output_and_its_settings(reopened, day, canopy, tmp_path):
    _, opened = reopened
    label, back, kind, settings = opened.runs[2]
    assert (label, kind, settings) == ("16", "day", (DAY_SPEC, SKY_SPEC))
    p, q = day.period, back.period
    assert p.times.equals(q.times) and str(q.times.tz) == "Asia/Shanghai"
    assert (p.start, p.end, p.source, dict(p.parameters), p.notes, p.par_umol_per_j) == \
        (q.start, q.end, q.source, dict(q.parameters), q.notes, q.par_umol_per_j)
    assert str(q.start.tz) == "Asia/Shanghai" and p.n_steps == q.n_steps == 4
    for name in ("step_s", "zenith_deg", "azimuth_deg", "ghi", "dni", "dhi",
                 "direct_horizontal", "step_par_mol_m2"):
        np.testing.assert_array_equal(getattr(p, name), getattr(q, name))
    for name in ("heights_cm", "step_transmission", "step_intercepted_fraction",
                 "triangle_direct_mol", "triangle_diffuse_mol", "triangle_mol", "maps",
                 "map_rays", "step_direct_mol_m2", "step_diffuse_mol_m2",
                 "step_incident_mol_m2", "step_intercepted_mol_m2", "step_transmitted_mol_m2",
                 "step_fraction_intercepted", "par_transmitted_mol_m2",
                 "transmission_by_height"):
        np.testing.assert_array_equal(getattr(day, name), getattr(back, name))
    for name in ("par_incident_mol_m2", "par_direct_mol_m2", "par_diffuse_mol_m2",
                 "par_intercepted_mol_m2", "fraction_intercepted", "rect", "rays", "level",
                 "warnings", "seconds", "periodic", "n_steps"):
        assert getattr(day, name) == getattr(back, name), name
    for h in HEIGHTS:
        same_map(day, back, h)
    same_sky_light(day.sky, back.sky)
    assert day.leaf_rows(canopy) == back.leaf_rows(canopy)
    write_steps(tmp_path / "a.csv", day)
    write_steps(tmp_path / "b.csv", back)
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text()


def test_sun_results_open_as_before_and_unknown_kinds_are_a_note(points, layout, sun, tmp_path):
    path = tmp_path / "old.maizeviz"
    proj = make_project(str(points), points.read_bytes(), layout, [("16", sun)])
    moon = Record("light_moon", {"label": "16"}, {"x": np.zeros(2)})
    save_project(path, type(proj)(proj.points_csv, proj.points_path, None, {}, {},
                                  proj.results + (moon,)))
    opened = Reopened(path, layout)
    assert len(opened.runs) == 1
    label, back, kind, settings = opened.runs[0]
    assert (label, kind, settings) == ("16", "sun", None)
    np.testing.assert_array_equal(back.transmission, sun.transmission)
    np.testing.assert_array_equal(back.first_hits, sun.first_hits)
    assert opened.notes == ["result 2 is of a kind this maizeviz does not know "
                            "('light_moon'); left out"]


def test_a_record_without_settings_takes_the_skys_own(sky, day):
    back = window_read(run_record("36", sky), "p")
    assert back.settings == SkySpec("soc", 16, "auto")
    assert window_read(run_record("36", day), "p").settings is None


# --------------------------------------------------------------------------- damaged records
def damaged(record, change):
    rec = copy.deepcopy(record)
    change(rec.meta, rec.arrays)
    return rec


def _set(obj, key, value):
    obj[key] = value


SKY_DAMAGE = [
    (lambda m, a: m.pop("transmission"), "'transmission' is missing"),
    (lambda m, a: _set(m, "rays", "many"), "'rays' must be a whole number"),
    (lambda m, a: _set(m, "heights_cm", [0, "high"]), "entry of 'heights_cm' must be a number"),
    (lambda m, a: _set(m, "transmission", [0.5]), "'transmission' must be 3 numbers"),
    (lambda m, a: _set(m, "rect", [0, 0, -5, 10]), "'rect' must be 4 numbers"),
    (lambda m, a: _set(m, "sky", "soc"), "'sky' must be an object"),
    (lambda m, a: _set(m["sky"], "kind", "cloudy"), "the stored sky cannot be used"),
    (lambda m, a: _set(m, "intercepted_fraction", 3.0), "out of range"),
    (lambda m, a: _set(m, "settings", {"sky": {"kind": "soc", "directions": "16",
                                               "split": "auto"}}),
     "'directions' must be a whole number"),
    (lambda m, a: a.pop("maps"), "no array 'maps'"),
    (lambda m, a: _set(a, "per_direction", a["per_direction"][:-1]),
     "array 'per_direction' is 15 x 3, expected 16 x 3"),
    (lambda m, a: _set(a, "triangle_share", np.where(np.arange(len(a["triangle_share"])) == 0,
                                                     np.nan, a["triangle_share"])),
     "array 'triangle_share' holds NaN"),
    (lambda m, a: _set(a, "sky_weights", a["sky_weights"] * 2), "sky weights must be >= 0 and "
                                                                "sum to 1"),
    (lambda m, a: _set(a, "sky_zenith_deg", a["sky_zenith_deg"][:5]),
     "sky zenith_deg must be 16 finite numbers"),
    (lambda m, a: _set(a, "map_rays", a["map_rays"].astype(float)), "not whole numbers"),
    (lambda m, a: _set(a, "maps", a["maps"] + 2), "values outside [0, 1"),
    (lambda m, a: _set(a, "map_x_edges", a["map_x_edges"][::-1].copy()), "not increasing"),
    (lambda m, a: _set(a, "maps", a["maps"].astype(bool)), "not numbers"),
]


@pytest.mark.parametrize("change, message", SKY_DAMAGE)
def test_damaged_sky_records_are_refused_with_what_is_wrong(sky, change, message):
    rec = damaged(run_record("16", sky, settings_doc("sky", SKY_SPEC)), change)
    with pytest.raises(ProjectError) as err:
        window_read(rec, "study.maizeviz")
    assert message in str(err.value) and str(err.value).startswith("study.maizeviz: ")
    assert "\n" not in str(err.value)


def _times(m, index, value):
    m["period"]["times"][index] = value


DAY_DAMAGE = [
    (lambda m, a: _times(m, 0, "yesterday"), "must be an ISO 8601 time with its UTC offset"),
    (lambda m, a: _times(m, 0, "2005-08-01T07:30:00"), "got \"2005-08-01T07:30:00\""),
    (lambda m, a: _times(m, 0, "2005-13-45T07:30:00+08:00"), "is not a valid ISO 8601 time"),
    (lambda m, a: _times(m, 1, 12), "time step 2 must be an ISO 8601 time"),
    (lambda m, a: _times(m, 0, "1600-01-01T00:00:00+00:00"), "years 1678 to 2261"),
    (lambda m, a: m["period"]["times"].reverse(), "not in increasing order"),
    (lambda m, a: _set(m["period"], "tz", "Mars/Olympus"), "time zone 'Mars/Olympus'"),
    (lambda m, a: _set(m["period"], "tz", "Asia"), "time zone 'Asia'"),   # a folder of the database
    (lambda m, a: _set(m["period"], "end", m["period"]["start"]), "ends before it starts"),
    (lambda m, a: m["period"].pop("source"), "'source' is missing"),
    (lambda m, a: _set(m["period"], "par_umol_per_j", 50.0), "PAR conversion factor"),
    (lambda m, a: _set(m["period"], "notes", [1]), "notes: 'n' must be text"),
    (lambda m, a: _set(a, "period_ghi", a["period_ghi"][:-1]), "array 'period_ghi' is 3"),
    (lambda m, a: _set(a, "period_ghi", a["period_ghi"] * 2), "period ghi must equal "
                                                              "direct_horizontal + dhi"),
    (lambda m, a: _set(a, "period_dhi", a["period_dhi"] * np.inf), "NaN or infinite"),
    (lambda m, a: _set(a, "step_transmission", a["step_transmission"].T.copy()),
     "array 'step_transmission' is 3 x 4, expected 4 x 3"),
    (lambda m, a: _set(a, "triangle_diffuse_mol", a["triangle_diffuse_mol"][:10]),
     "array 'triangle_diffuse_mol' is 10"),
    (lambda m, a: _set(a, "triangle_direct_mol", -a["triangle_direct_mol"] - 1),
     "values outside >= 0"),
    (lambda m, a: _set(m, "sky", None), "has no sky light"),
    (lambda m, a: _set(m["sky"], "rays", m["sky"]["rays"] + 1), "sky does not match"),
    (lambda m, a: a.pop("diffuse_per_direction"), "no array 'diffuse_per_direction'"),
    (lambda m, a: _set(m["settings"]["day"], "lat", "north"), "'lat' must be a number"),
    (lambda m, a: m["settings"].pop("day"), "'day' is missing"),
]


@pytest.mark.parametrize("change, message", DAY_DAMAGE)
def test_damaged_day_records_are_refused_with_what_is_wrong(day, change, message):
    rec = damaged(run_record("16", day, settings_doc("day", (DAY_SPEC, SKY_SPEC))), change)
    with pytest.raises(ProjectError) as err:
        window_read(rec, "study.maizeviz")
    assert message in str(err.value) and str(err.value).startswith("study.maizeviz")
    assert "\n" not in str(err.value)


def test_a_damaged_record_in_a_file_refuses_the_project(points, layout, day, tmp_path):
    path = tmp_path / "bad.maizeviz"
    rec = damaged(run_record("16", day), lambda m, a: _times(m, 2, "noon"))
    save_project(path, make_project(str(points), points.read_bytes(), layout, []))
    proj = load_project(path)
    save_project(path, type(proj)(proj.points_csv, proj.points_path, None, {}, {}, (rec,)))
    with pytest.raises(ProjectError, match="time step 3 must be an ISO 8601 time"):
        Reopened(path, layout)              # refused where the window reads the results


def test_a_fixed_offset_zone_and_utc_come_back(day):
    for zone in ("UTC", "UTC+08:00"):
        rec = damaged(run_record("16", day), lambda m, a, z=zone: _set(m["period"], "tz", z))
        back = window_read(rec, "p").result
        assert (back.period.times == day.period.times).all()          # the same instants
        assert str(back.period.times.tz) == str(back.period.start.tz) == zone
