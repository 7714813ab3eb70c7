"""Sky and day specs in the core: what a project stores of a sky or day result reads back as
the same specs, for the app, the command line and notebooks alike."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import maizeviz as mv
from maizeviz.io.archive import ProjectError
from maizeviz.light.specs import DaySpec, SkySpec
from maizeviz.project.settings import run_settings, settings_doc
from maizeviz.project.study import StoredResult

days = st.builds(
    DaySpec, date=st.dates().map(lambda d: d.isoformat()),
    lat=st.floats(-89, 89), lon=st.floats(-180, 180),
    tz=st.sampled_from(["UTC", "Asia/Shanghai", "Europe/Paris"]),
    step_min=st.floats(1, 120), start=st.none() | st.just("06:00"),
    end=st.none() | st.just("18:00"), linke=st.floats(1, 7), par_factor=st.floats(1, 3),
    weather=st.none() | st.just("w.csv"))
skies = st.builds(SkySpec, kind=st.sampled_from(["soc", "uoc"]),
                  directions=st.sampled_from([16, 46, 145, 30]),
                  split=st.sampled_from(["auto", "equal"]))


@settings(max_examples=60, deadline=None)
@given(days, skies)
def test_day_and_sky_specs_round_trip_through_a_project_document(day, sky):
    import json

    doc = json.loads(json.dumps(settings_doc("day", (day, sky))))
    assert run_settings("day", None, doc, "p.maizeviz") == (day, sky)
    doc = json.loads(json.dumps(settings_doc("sky", sky)))
    assert run_settings("sky", None, doc, "p.maizeviz") == sky
    stored = StoredResult("36 triangles", None, "day", settings_doc("day", (day, sky)))
    assert stored.specs() == (day, sky)


def test_bad_stored_specs_name_the_project():
    with pytest.raises(ProjectError, match="p.maizeviz: the sky settings"):
        run_settings("sky", None, {"sky": {"kind": 3, "directions": 46, "split": "auto"}},
                     "p.maizeviz")


def test_the_facade_offers_the_specs():
    assert mv.DaySpec is DaySpec and mv.SkySpec is SkySpec
    assert SkySpec("uoc", 16).sky().n == 16
    assert DaySpec(step_min=60.0, start="06:00", end="18:00").steps_bound() == 12
