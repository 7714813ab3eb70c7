"""A layout edit sets the light results aside, and Undo brings them back (a new user's
report: one drag emptied the Light table, the heatmaps and the colours, said so only in the
Messages tab, and Ctrl+Z restored the layout but not the light). The results are kept under
the stands they were traced on (:func:`maizeviz.canopy.layout.stands_identity`); undoing back
to those stands gives the same run objects and numbers back, nothing traced again. Driven
through the app's model, without Qt."""

from __future__ import annotations

import numpy as np
import pytest

from maizeviz.io.points import write_points
from maizeviz.leaf.synth import block_grids

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


@pytest.fixture(scope="module")
def points(tmp_path_factory):
    path = tmp_path_factory.mktemp("kept") / "four_plants.csv"
    write_points(path, block_grids(2, 2, seed=3))
    return path


@pytest.fixture
def study():
    from maizeviz_app.model import StudyModel
    from maizeviz_app.runner import InlineRunner

    runner = InlineRunner()
    model = StudyModel(tile=1, runner=runner)
    said: list[tuple[str, bool]] = []
    model.said.connect(lambda text, error, status_only: said.append((text, status_only)))
    model.said_lines = said                               # type: ignore[attr-defined]
    traced: list = []
    model.light_added.connect(traced.append)
    model.traced = traced                                 # type: ignore[attr-defined]
    yield model
    runner.shutdown()


def _sun(m):
    s = m.settings
    s.canopy.level = "36"
    s.sampling.heights, s.sampling.density = "0, 100, 200", 0.5
    s.sun.zenith_deg, s.sun.azimuth_deg = 35.0, 140.0
    s.optics.enabled = True
    assert m.compute_light()
    return m.runs.last


def test_a_drag_sets_the_light_aside_and_undo_brings_it_back(study, points):
    m = study
    m.open_points(points)
    run = _sun(m)
    numbers = run.transmission.copy()
    absorbed = run.extra.leaf_value.copy()
    table = m.runs.table()
    assert m.view.colouring == "light" and len(m.traced) == 1
    stands = m.loaded.layout
    # drag a plant 20 cm along its row, as the layout editor does
    p = m.draft.placements[1]
    assert m.draft.move(1, p.x, p.y + 20.0, snap=False)
    assert m.loaded.layout.placements != stands.placements and m.built.serial == m.serial
    # set aside, said where the user looks: the status bar's line and the light panel's text
    assert not m.runs.runs and m.view.colouring == "leaf"
    line, status_only = m.said_lines[-1]
    assert "set aside: they belong to the previous layout" in line and "Undo" in line
    assert "belong to the previous layout" in m.runs_info
    # undo: the same layout, the same results (the same objects), nothing traced again
    m.history.undo()
    assert m.loaded.layout.placements == stands.placements
    back = m.runs.last
    assert back is run and len(m.traced) == 1
    np.testing.assert_array_equal(back.transmission, numbers)
    np.testing.assert_array_equal(back.extra.leaf_value, absorbed)
    assert back.signature == m.shown_signature                  # on the canopy shown
    assert m.runs.table() == table and m.plants_run is run
    assert m.view.colouring == "light" and m.can_colour("light")
    assert "are back" in m.runs_info and "are back" in m.said_lines[-1][0]
    # redo: set aside again; a result traced on the new layout is its own
    m.history.redo()
    assert not m.runs.runs
    moved = _sun(m)
    assert moved is not run and len(m.traced) == 2
    m.history.undo()
    assert m.runs.last is run
    m.history.redo()
    assert m.runs.last is moved and len(m.traced) == 2


def test_new_points_forget_the_results_set_aside(study, points):
    m = study
    m.open_points(points)
    _sun(m)
    p = m.draft.placements[0]
    assert m.draft.move(0, p.x, p.y + 20.0, snap=False)
    assert m.runs_set_aside
    m.open_points(points)
    assert not m.runs_set_aside and not m.runs.runs
