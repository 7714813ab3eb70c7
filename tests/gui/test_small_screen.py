"""A laptop screen (1366 x 768): every panel fits its dock without scrolling sideways and
without cutting a label, a button or a field's text; every control has a tooltip and an
accessible name equal to its label, by which a test (and a screen reader) finds it."""

from __future__ import annotations

import pytest
from maizeviz_app.accessible import controls, label_text
from PySide6.QtWidgets import (
    QAbstractButton,
    QCheckBox,
    QComboBox,
    QLabel,
    QLineEdit,
    QRadioButton,
)
from test_light_modes import TIMEOUT, shown

#: The docks of the panels, raised in turn.
PANELS = ("canopy", "light", "layout", "digitizer", "colour")


def find(root, name: str, kind=None):
    """The one visible control under ``root`` whose accessible name is ``name``."""
    found = [c for c in controls(root) if c.accessibleName() == name and c.isVisible()
             and (kind is None or isinstance(c, kind))]
    assert len(found) == 1, f"{len(found)} controls named {name!r}"
    return found[0]


def _cut(widget) -> list[str]:
    """What a panel shows cut: a label, button or check box narrower than its text, a
    wrapped label lower than its lines, a field narrower than its text, a combo narrower
    than its choice."""
    cut = []
    for c in widget.findChildren(QLabel) + widget.findChildren(QAbstractButton):
        if isinstance(c, QLabel) and c.isVisible() and c.wordWrap() and c.text() and \
                c.heightForWidth(c.width()) > c.height() + 1:       # wrapped, lines cut off
            cut.append(f"QLabel {c.text()!r}: {c.height()} px high < "
                       f"{c.heightForWidth(c.width())}")
        if not c.isVisible() or (isinstance(c, QLabel) and (c.wordWrap() or c.pixmap()
                                                            and not c.pixmap().isNull())):
            continue
        if c.objectName().startswith("qt_") or not c.text():
            continue
        if c.sizeHint().width() > c.width() + 1:
            cut.append(f"{type(c).__name__} {c.text()!r}: {c.width()} < {c.sizeHint().width()}")
    for e in widget.findChildren(QLineEdit):
        if e.isVisible() and e.isEnabled() and not e.objectName().startswith("qt_") and \
                e.fontMetrics().horizontalAdvance(e.text()) + 12 > e.width():
            cut.append(f"field {e.accessibleName()!r} shows part of {e.text()!r}")
    for b in widget.findChildren(QComboBox):
        if b.isVisible() and \
                b.fontMetrics().horizontalAdvance(b.currentText()) + 30 > b.width():
            cut.append(f"combo {b.accessibleName()!r} cuts {b.currentText()!r}")
    return cut


def _labelled(control, label: str) -> bool:
    """The control's name is its label (whatever the case), or, where the same label stands
    in two groups (the colour panel's two scales), the label after its group's title."""
    from PySide6.QtWidgets import QGroupBox

    name, label = control.accessibleName().lower(), label_text(label).lower()
    if name == label:
        return True
    parent = control.parent()
    while parent is not None and not isinstance(parent, QGroupBox):
        parent = parent.parent()
    return parent is not None and name == f"{label_text(parent.title())} {label}".lower()


def _fits(w, name: str) -> list[str]:
    area = w.docks[name].widget()
    problems = [f"{name} scrolls sideways by {area.horizontalScrollBar().maximum()} px"] \
        if area.horizontalScrollBar().maximum() > 0 else []
    return problems + [f"{name}: {c}" for c in _cut(area.widget())]


@pytest.fixture
def laptop(window, qtbot, small_points):
    from PySide6.QtWidgets import QApplication

    w = shown(qtbot, window(small_points, tile=1, size=None))
    w.resize(1366, 768 - 28)                        # the screen less a panel bar
    qtbot.wait(300)
    assert QApplication.primaryScreen() is not None
    return w


def test_every_panel_fits_a_laptop_screen(laptop, qtbot):
    w = laptop
    problems = []
    checked = set()
    for workspace in ("digitize", "analyse"):       # each dock as its workspace shows it
        w.workspaces.show(workspace)
        qtbot.wait(200)
        for name in PANELS:
            if w.docks[name].isHidden():
                continue
            w.docks[name].raise_()
            qtbot.wait(150)
            assert w.docks[name].widget().isVisible(), name     # else nothing is measured
            checked.add(name)
            problems += [f"{workspace}: {p}" for p in _fits(w, name)]
    assert checked == set(PANELS)
    light = w.light_panel
    for mode in ("sky", "day"):                     # the light's other pages
        w.docks["light"].raise_()
        light.set_mode(mode)
        qtbot.wait(150)
        problems += [f"{mode}: {p}" for p in _fits(w, "light")]
    light.set_mode("sun")
    w.model.settings.optics.enabled = True          # the optics open
    qtbot.wait(150)
    problems += [f"optics: {p}" for p in _fits(w, "light")]
    assert not problems, "\n".join(problems)


def test_canopy_measures_show_every_column(laptop, qtbot):
    w = laptop
    w.docks["canopy"].raise_()
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.model.settings.canopy.level = "K4"
    table = w.canopy_panel.table
    qtbot.wait(100)
    assert table.rowCount() == 2 and table.horizontalScrollBar().maximum() == 0
    for c in range(table.columnCount()):
        assert table.columnWidth(c) >= table.horizontalHeader().sectionSizeHint(c) - 1 or c == 0


def test_every_control_has_a_tooltip_and_its_label_as_name(laptop):
    w = laptop
    unnamed, no_tip, wrong = [], [], []
    roots = [w.docks[n].widget() for n in PANELS] + [w.statusBar(), w.plots, w.history,
                                                     w.messages]
    seen = 0
    for root in roots:
        for c in controls(root):
            seen += 1
            if not c.accessibleName():
                unnamed.append(f"{type(c).__name__} in {type(root).__name__}")
            if not c.toolTip():
                no_tip.append(f"{type(c).__name__} {c.accessibleName()!r}")
            if isinstance(c, (QCheckBox, QRadioButton)) or \
                    (isinstance(c, QAbstractButton) and c.text() and len(c.text()) > 1):
                if not _labelled(c, c.text()):
                    wrong.append(f"{c.text()!r} named {c.accessibleName()!r}")
        for label in root.findChildren(QLabel):
            buddy = label.buddy()
            if buddy is not None and label.text() and not _labelled(buddy, label.text()):
                wrong.append(f"{label.text()!r} names a field {buddy.accessibleName()!r}")
    assert seen > 60
    assert not unnamed and not no_tip and not wrong, (unnamed, no_tip, wrong)


def test_a_light_run_by_the_controls_names(laptop, qtbot):
    """What a screen reader user (or a test) does: find the fields by their names."""
    w = laptop
    panel = w.docks["light"].widget()
    w.docks["light"].raise_()
    qtbot.wait(50)
    find(panel, "Sky", QAbstractButton).click()
    find(panel, "heights (cm)").setText("0, 100")
    find(panel, "ray density").setValue(0.5)
    find(panel, "directions").setCurrentIndex(0)             # 16, the turtle
    assert w.model.settings.sky.directions == 16 and w.model.settings.light.mode == "sky"
    with qtbot.waitSignal(w.light_shown, timeout=TIMEOUT):
        find(panel, "Compute diffuse light").click()
    assert w.model.runs.of_kind("sky") is not None
    table = find(panel, "transmission table")
    assert table.rowCount() == 2


def test_every_menu_entry_says_what_it_does_in_the_status_bar(laptop, qtbot):
    """Hovering a menu entry tells what it does, as the panels' tooltips do (the recent
    files' entries name their file instead)."""
    w = laptop
    silent, seen = [], 0

    def walk(menu, path):
        nonlocal seen
        for act in menu.actions():
            if act.isSeparator() or menu is w.recent_menu:
                continue
            seen += 1
            name = f"{path} > {act.text().replace('&', '')}"
            if not act.statusTip().strip():
                silent.append(name)
            if act.menu() is not None:
                walk(act.menu(), name)

    for top in w.menuBar().actions():
        walk(top.menu(), top.text().replace("&", ""))
    assert seen > 40 and not silent, silent
    # the tip is shown where the user looks: the status bar (as Qt's menus do on hover)
    act = w.menu_actions["view_image"]
    assert act.showStatusText(w)
    assert w.statusBar().currentMessage() == act.statusTip()


def test_a_long_status_line_is_shortened_in_the_middle_and_whole_in_its_tooltip(laptop, qtbot):
    from PySide6.QtGui import QFont, QFontMetrics

    w = laptop
    bar = w.statusBar()
    long = ("2005-08-01: PAR incident 61.6 mol/m² (direct 53.3, diffuse 8.3); intercepted 60.0 "
            "mol/m² (97.3%); transmitted to the ground 1.67 mol/m² (2.7%); clear sky: "
            "Ineichen-Perez with a Linke turbidity of 3.0, 14 steps of 60 min, end")
    for error in (False, True):
        w.say(("error: " if error else "") + long, status_only=True)
        shown = bar.currentMessage()
        font = QFont(bar.font())
        font.setBold(error)
        box = [c for c in bar.children() if getattr(c, "isVisible", None) and c.isVisible()
               and c.metaObject().className() == "QWidget"]
        room = min(c.geometry().left() for c in box)
        assert "…" in shown and shown.endswith(", end"), shown
        assert QFontMetrics(font).horizontalAdvance(shown) <= room, (shown, room)
        assert bar.toolTip().endswith(long)
    w.say("a short line", status_only=True)
    assert bar.currentMessage() == "a short line" and bar.toolTip() == ""


def test_the_c4_plants_table_shows_its_co2_columns_on_a_laptop(laptop, qtbot):
    """Issue 37, item 7: at 1366 x 768 the plants table of a sun with C4 hid its CO2 columns
    behind a sideways scroll; its headers now take a word a line and every column shows."""
    from test_light_modes import compute, small_light

    w = laptop
    p = w.light_panel
    small_light(p, "sun")
    p.periodic.setChecked(True)
    p.optics_box.setChecked(True)
    p.photo_model.setCurrentIndex(p.photo_model.findData("c4"))
    compute(qtbot, w)
    w.docks["light"].raise_()
    qtbot.waitUntil(lambda: p.plants.isVisible(), timeout=TIMEOUT)
    qtbot.wait(200)
    assert p.plants.columnCount() == 8
    assert p.plants.horizontalScrollBar().maximum() == 0
    assert not _cut(w.docks["light"].widget().widget())


def _cap_height_px(font_px: float) -> float:
    """The height of a capital (an H) of matplotlib's default font drawn ``font_px`` tall."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextPath

    return font_px * TextPath((0, 0), "H", size=1, prop=FontProperties()).get_extents().height


def test_the_docked_heatmaps_text_is_readable_on_a_laptop(laptop, qtbot):
    """Issue 37, item 7: at 1366 x 768 the docked heatmap's title, axis labels and colour-bar
    text were drawn at 64 dpi on a 512 px figure and shrunk into a 448 x 168 view: capitals
    2 px tall. Each light's map (a sun with C4, a sky, a day) is now drawn at the view's own
    pixels and dpi, every text at least 11 px and its capitals 8.5 px (at 96 dpi)."""
    from test_light_modes import compute, small_light

    w = laptop
    p = w.light_panel
    small_light(p, "sun")
    p.periodic.setChecked(True)
    p.optics_box.setChecked(True)
    p.photo_model.setCurrentIndex(p.photo_model.findData("c4"))
    compute(qtbot, w)
    for mode in ("sky", "day"):
        small_light(p, mode)
        compute(qtbot, w)
    plots, view = w.plots, w.plots.heatmap
    assert plots.source.count() == 3
    for i in range(3):
        plots.source.setCurrentIndex(i)
        qtbot.waitUntil(lambda: view.heatmap is not None, timeout=TIMEOUT)
        image = view.image()
        scale = min(view.width() / image.width(), view.height() / image.height())
        shown_px = view.heatmap.font_px * scale * 96 / view.logicalDpiY()
        assert shown_px >= 11 and _cap_height_px(shown_px) >= 8.5, \
            (plots.source.currentText(), view.heatmap.font_px, scale)
    # the transmission plot too is drawn at its view's pixels (not shrunk)
    plot = plots.transmission
    assert abs(plot.image().width() - plot.width()) <= 0.05 * plot.width()


def _sun_c4_sky_day(w, qtbot):
    """A sun with C4, a sky and a day computed on the laptop's window (the Day page shown)."""
    from test_light_modes import compute, small_light

    p = w.light_panel
    small_light(p, "sun")
    p.periodic.setChecked(True)
    p.optics_box.setChecked(True)
    p.photo_model.setCurrentIndex(p.photo_model.findData("c4"))
    compute(qtbot, w)
    for mode in ("sky", "day"):
        small_light(p, mode)
        compute(qtbot, w)


def test_the_day_page_takes_its_own_room_and_its_sky_shows(laptop, qtbot):
    """Issue 37, item 7: the light panel's pages stood in a stack as tall as its tallest
    page (the sun's with optics and C4, 527 px), so at 1366 x 768 the Day page (279 px) sat
    in a gap and the sky it needs was cut by the dock's bottom edge. The page shown alone
    takes room: neither squashed below its minimum nor stretched past its size, and the
    sky's group shows whole in the dock, unscrolled."""
    from PySide6.QtCore import QPoint

    w = laptop
    _sun_c4_sky_day(w, qtbot)
    p = w.light_panel
    w.docks["light"].raise_()
    p.set_mode("day")
    qtbot.wait(200)
    area = w.docks["light"].widget()
    area.verticalScrollBar().setValue(0)
    qtbot.wait(100)
    page = p.pages.currentWidget()
    assert page is p.pages.widget(1) and page.isVisible()
    assert page.minimumSizeHint().height() <= page.height() <= page.sizeHint().height() + 2, \
        (page.minimumSizeHint(), page.size(), page.sizeHint())
    bottom = p.sky_box.mapTo(area.widget(), QPoint(0, p.sky_box.height())).y()
    assert p.sky_box.isVisible() and bottom <= area.viewport().height(), \
        (bottom, area.viewport().height())
    assert not _fits(w, "light")


def test_the_layout_state_and_apply_show_in_a_laptops_dock(laptop, qtbot):
    """Issue 37, item 7: at 1366 x 768 the Layout panel asked for the height its splitter was
    given (60 % and 40 % of the panel's own, 740 px), taller than its dock (652 px): the state
    line ("1 plant edited · not applied yet") and Apply stood below the bottom edge, cut.
    They now show in the dock unscrolled; the state wraps (never cut) down to the
    narrowest dock and tells the whole of it in its tooltip."""
    from PySide6.QtCore import QPoint, Qt

    w = laptop
    _sun_c4_sky_day(w, qtbot)
    w.docks["layout"].raise_()
    w.model.layout_options.follow = False
    panel = w.layout_panel
    panel.draft.move(0, 40.0, 20.0)                     # an edit: the state says so
    qtbot.wait(300)
    assert panel.state.text() == "1 plant edited · not applied yet"
    assert "Apply" in panel.state.toolTip()
    area = w.docks["layout"].widget()
    area.verticalScrollBar().setValue(0)
    qtbot.wait(100)
    for part in (panel.state, panel.apply_button):
        bottom = part.mapTo(area.widget(), QPoint(0, part.height())).y()
        assert part.isVisible() and bottom <= area.viewport().height(), \
            (part.text(), bottom, area.viewport().height())
    for width in (480, 300):
        w.resizeDocks([w.docks["layout"]], [width], Qt.Orientation.Horizontal)
        qtbot.wait(200)
        label = panel.state
        assert label.heightForWidth(label.width()) <= label.height() + 1, \
            (width, label.size(), label.heightForWidth(label.width()))
        assert not [c for c in _cut(panel) if "edited" in c]


def test_the_docked_heatmap_is_drawn_again_for_its_new_size(laptop, qtbot):
    """A bigger window: once the resize settles, the heatmap shown is drawn again for its
    view's new pixels (its texts keep their points), the old one in view meanwhile."""
    from test_light_modes import compute, small_light

    w = laptop
    small_light(w.light_panel, "sun")
    compute(qtbot, w)
    view = w.plots.heatmap
    qtbot.waitUntil(lambda: view.heatmap is not None, timeout=TIMEOUT)
    before, font_px = view.image().size(), view.heatmap.font_px
    assert abs(before.width() - view.width()) <= 0.05 * view.width()
    emptied = []
    w.resize(1920, 1052)

    def redrawn() -> bool:
        image = view.image()
        emptied.append(image is None)
        return image is not None and image.width() > 1.2 * before.width() and \
            abs(image.width() - view.width()) <= 0.05 * view.width()

    qtbot.waitUntil(redrawn, timeout=TIMEOUT)
    assert not any(emptied) and view.heatmap.font_px == pytest.approx(font_px)
