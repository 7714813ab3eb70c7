"""The study's undo history without Qt: a script's steps are the steps it names, reactions join
the edit they react to, nothing depends on an event loop; a stateful test runs random edits,
named blocks, undos and redos against a plain list of the study's states."""

from __future__ import annotations

import subprocess
import sys

import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, rule

from maizeviz.canopy.layout import tiled_layout

BASES = {1: (30.0, 15.0), 2: (30.0, 45.0)}
VALUES = {("sun", "zenith_deg"): [10.0, 22.34, 45.5],
          ("sun", "azimuth_deg"): [90.0, 180.0],
          ("light", "mode"): ["sun", "sky", "day"],
          ("optics", "band"): ["par", "nir"],
          ("optics", "reflectance"): [0.1, 0.25],
          ("view colours", "cmap"): ["inferno", "greys"]}


def _model():
    from maizeviz_app.model import StudyModel

    model = StudyModel()                               # no points: edits build nothing
    model.draft.start(tiled_layout(BASES, (1, 1)), set(BASES))
    return model


def _state(model):
    groups = model.edit_groups()
    return ({n: {f: getattr(g, f) for f in vars(g) if not f.startswith("_")}
             for n, g in groups.items()}, model.draft.snapshot())


def test_the_history_imports_without_qt():
    code = ("import sys, maizeviz_app.history, maizeviz_app.model; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('PySide6', 'pyvista', 'vtk')]; "
            "print(bad); sys.exit(1 if bad else 0)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_a_scripts_steps_are_the_steps_it_names():
    model = _model()
    h, sun = model.history, model.settings.sun
    sun.zenith_deg = 30.0                              # no block: each edit a step
    sun.zenith_deg = 40.0
    with h.step("noon sun"):                           # a block: one step, its name
        sun.zenith_deg = 10.0
        sun.azimuth_deg = 180.0
        model.draft.turn(0, 90.0)
    assert h.texts == ["sun zenith 30", "sun zenith 40", "noon sun"]
    assert h.undo_text == "noon sun"
    h.undo()
    assert (sun.zenith_deg, sun.azimuth_deg) == (40.0, 166.95)
    assert model.draft.placements[0].azimuth_deg != 90.0
    h.undo()
    assert sun.zenith_deg == 30.0 and h.redo_text == "sun zenith 40"
    h.redo()
    h.redo()
    assert (sun.zenith_deg, sun.azimuth_deg) == (10.0, 180.0)
    assert model.draft.placements[0].azimuth_deg == 90.0
    with h.step("nothing"):                           # a block that changed nothing
        sun.zenith_deg = 10.0
    assert len(h.steps) == 3 and not h.can_redo


def test_a_reaction_joins_the_edit_it_reacts_to_and_is_undone_after_it():
    """A band sets the optics to its defaults: one step, named by the band; undoing it
    brings back reflectance typed before the band, not the old band's defaults."""
    model = _model()
    o, h = model.settings.optics, model.history
    o.reflectance = 0.2
    o.band = "nir"
    assert h.texts == ["leaf reflectance 0.2", "band nir and 4 more"]
    assert o.reflectance == pytest.approx(0.45)
    h.undo()
    assert o.band == "par" and o.reflectance == pytest.approx(0.2)
    h.redo()
    assert o.band == "nir" and o.reflectance == pytest.approx(0.45)


def test_merging_by_time_is_explicit_and_typing_back_is_no_step():
    model = _model()
    h, sun = model.history, model.settings.sun
    for v in (1.0, 12.0):                              # a script: two steps
        sun.zenith_deg = v
    assert len(h.steps) == 2
    h.clear()
    h.merge_s = 3600.0                                 # the window's rule, made long
    for v in (1.0, 12.0, 12.5):
        sun.zenith_deg = v
    assert h.texts == ["sun zenith 12.5"]
    sun.zenith_deg = 12.0                              # back where it started
    assert h.texts == [] and not h.can_undo
    sun.zenith_deg = 5.0
    h.forget_merging()                                 # a gesture ended
    sun.zenith_deg = 6.0
    assert h.texts == ["sun zenith 5", "sun zenith 6"]


def test_settings_set_together_are_one_step():
    """settings.set (a weather file and its source, a sky split and its directions, the sun
    from a place) is one step; a value refused sets none of them."""
    from maizeviz_app.settings import InputProblem

    model = _model()
    model.settings.set("sun", {"zenith_deg": 12.0, "azimuth_deg": 200.0})
    assert model.history.texts == ["sun zenith 12 and 1 more"]
    with pytest.raises(InputProblem):
        model.settings.set("sun", {"zenith_deg": 13.0, "azimuth_deg": 9999.0})
    assert model.settings.sun.zenith_deg == 12.0 and len(model.history.steps) == 1
    model.history.undo()
    assert (model.settings.sun.zenith_deg, model.settings.sun.azimuth_deg) == (22.34, 166.95)


def test_the_models_own_changes_are_no_step_and_opening_clears():
    model = _model()
    model.apply_settings("sun", {"zenith_deg": 12.0})  # the model itself (a project read)
    assert model.history.steps == []
    model.settings.sun.zenith_deg = 13.0
    assert len(model.history.steps) == 1


class HistoryMachine(RuleBasedStateMachine):
    """The model's history against a list of states (``states``, ``at``)."""

    def __init__(self):
        super().__init__()
        self.model = _model()

    @initialize()
    def start(self):
        self.states = [_state(self.model)]
        self.at = 0

    def _after(self, before) -> None:
        if _state(self.model) != before:
            self.states[self.at + 1:] = [_state(self.model)]
            self.at += 1

    def _set(self, key, value) -> None:
        group, name = key
        setattr(self.model.edit_groups()[group], name, value)

    @rule(key=st.sampled_from(sorted(VALUES)), data=st.data())
    def set_a_setting(self, key, data):
        before = _state(self.model)
        self._set(key, data.draw(st.sampled_from(VALUES[key])))
        self._after(before)

    @rule(keys=st.lists(st.sampled_from(sorted(VALUES)), min_size=1, max_size=3),
          data=st.data(), turn=st.sampled_from([None, 0.0, 200.5]))
    def a_named_block(self, keys, data, turn):
        before = _state(self.model)
        with self.model.history.step("block"):
            for key in keys:
                self._set(key, data.draw(st.sampled_from(VALUES[key])))
            if turn is not None:
                self.model.draft.turn(1, turn)
        self._after(before)

    @rule(i=st.integers(0, 5), dx=st.sampled_from([-7.5, 0.0, 12.25]))
    def move(self, i, dx):
        before, d = _state(self.model), self.model.draft
        i %= len(d.placements)
        d.move(i, d.placements[i].x + dx, d.placements[i].y)
        self._after(before)

    @rule()
    def undo(self):
        if self.model.history.undo():
            self.at -= 1
        else:
            assert self.at == 0

    @rule()
    def redo(self):
        if self.model.history.redo():
            self.at += 1
        else:
            assert self.at == len(self.states) - 1

    @invariant()
    def the_study_is_where_the_history_says(self):
        h = self.model.history
        assert _state(self.model) == self.states[self.at]
        assert h.index == self.at and len(h.steps) == len(self.states) - 1


TestHistoryMachine = HistoryMachine.TestCase
TestHistoryMachine.settings = settings(max_examples=60, stateful_step_count=30, deadline=None,
                                       suppress_health_check=[HealthCheck.too_slow])
