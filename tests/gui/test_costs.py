"""The window estimates work before starting it (maizeviz.cost, as the command line does):
what would not fit in memory is refused in one line and the view keeps its canopy; what is
merely slow starts only if the user says so."""

import maizeviz.cost as cost

TIMEOUT = 120_000


def shown(qtbot, w):
    if w.model.canopy is None:
        qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT).wait()
    return w


def test_a_canopy_too_big_for_memory_is_refused_and_the_slider_goes_back(window, qtbot,
                                                                         small_points,
                                                                         monkeypatch):
    w = shown(qtbot, window(small_points, tile=1))
    level, canopy = w.model.settings.canopy.level, w.model.canopy
    monkeypatch.setattr(cost, "memory_available", lambda: 2**18)      # a 256 KiB machine
    w.step_level(-1)                                                   # finer
    qtbot.waitUntil(lambda: "memory" in w.messages.toPlainText(), timeout=5000)
    text = w.messages.toPlainText()
    assert "triangles" in text and "more than the" in text
    assert w.model.settings.canopy.level == level and w.model.canopy is canopy                    # nothing changed
    assert w.runner.current("build") is None
    assert w.canopy_panel.asked_label.text() == ""


def test_slow_light_asks_first_and_starts_only_when_confirmed(window, qtbot, small_points,
                                                               monkeypatch):
    w = shown(qtbot, window(small_points, tile=1))
    monkeypatch.setattr(cost, "SLOW_SECONDS", 1e-9)                   # anything is slow now
    asked = []
    monkeypatch.setattr(w.model, "confirm_slow", lambda estimate: asked.append(estimate) or False)
    panel = w.light_panel
    panel.set_mode("sky")
    panel.density.setValue(3.0)
    panel.compute_button.click()
    assert len(asked) == 1 and "rays per cm2" in asked[0] and "force" not in asked[0]
    assert "from 46 directions" in asked[0]                            # the sky's directions
    assert w.runner.current("light") is None and panel.compute_button.isEnabled()
    assert "not started" in w.statusBar().currentMessage()
    monkeypatch.setattr(w.model, "confirm_slow", lambda estimate: asked.append(estimate) or True)
    panel.density.setValue(0.5)
    with qtbot.waitSignal(w.light_shown, timeout=TIMEOUT):
        panel.compute_button.click()
    assert len(asked) == 2 and w.model.runs.of_kind("sky") is not None


def test_a_day_is_estimated_from_its_steps(window, qtbot, small_points, monkeypatch):
    from maizeviz_app.jobs import DaySpec

    assert DaySpec(step_min=30.0).steps_bound() == 48
    assert DaySpec(step_min=10.0, start="06:00", end="18:00").steps_bound() == 72
    assert DaySpec(step_min=30.0, start="12:00").steps_bound() == 24       # noon to midnight
    assert DaySpec(step_min=60.0, start="06:00:00", end="18:30").steps_bound() == 13
    w = shown(qtbot, window(small_points, tile=1))
    monkeypatch.setattr(cost, "SLOW_SECONDS", 1e-9)
    asked = []
    monkeypatch.setattr(w.model, "confirm_slow", lambda estimate: asked.append(estimate) or False)
    panel = w.light_panel
    panel.set_mode("day")
    panel.step.setValue(30.0)
    panel.compute_button.click()
    assert asked and "from 94 directions" in asked[0]                 # 46 sky + 48 steps
    assert w.runner.current("light") is None
