"""Light settings typed wrong in the window (heights 'abc', '-5' or empty; a weather file
chosen with no file): one line, the field marked, never an internal error to report."""

import pytest

from maizeviz.errors import MaizevizError

TIMEOUT = 120_000


def shown(qtbot, w):
    if w.model.canopy is None:
        qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT).wait()
    return w


@pytest.mark.parametrize("mode", ["sun", "sky", "day"])
def test_bad_heights_and_a_missing_weather_file_are_the_users(window, qtbot, small_points, mode,
                                                              capsys):
    w = shown(qtbot, window(small_points, tile=1))
    panel = w.light_panel
    panel.set_mode(mode)

    def refused(field, words):
        with qtbot.waitSignal(w.failed, timeout=TIMEOUT) as err:
            panel.compute_button.click()
        text = err.args[0]
        assert "\n" not in text and words in text, text
        assert "report" not in text and "internal" not in text, text
        assert panel.problem.isVisible() and panel.problem.text() == text
        assert "d0342c" in field.styleSheet(), f"{words}: field not marked"
        assert "Traceback" not in capsys.readouterr().err
        panel.clear_problem()

    for typed, words in (("abc", "'abc' is not a number"), ("-5", "0 cm or more, got -5"),
                         ("", "give at least one height"), ("0, 1e999", "0 cm or more"),
                         ("0,,nan", "0 cm or more")):
        panel.heights.setText(typed)
        refused(panel.heights, words)
    panel.heights.setText("0, 100")
    if mode == "day":
        panel.source_weather.setChecked(True)
        panel.weather.setText("   ")
        refused(panel.weather, "choose a weather file")


def test_an_input_problem_is_a_maizeviz_error_told_without_a_bug_report():
    from maizeviz_app.messages import user_message
    from maizeviz_app.panels.light import InputProblem, parse_heights

    with pytest.raises(InputProblem) as err:
        parse_heights("abc")
    assert isinstance(err.value, MaizevizError) and err.value.quantity == "heights"
    text = user_message(err.value, "light")
    assert "report" not in text and "internal" not in text and "'abc'" in text
