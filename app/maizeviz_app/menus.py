"""The menu bar: every command of the window, with its shortcut shown in the menu."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import Qt
from PySide6.QtGui import QAction, QActionGroup, QKeySequence

from maizeviz_app.options import CAMERAS, COLOURINGS

RECENT_MAX = 8
#: What each camera preset of the View menu does, in its status tip.
CAMERA_TIPS = {"top": "look straight down on the field", "front": "look along the rows",
               "side": "look across the rows", "iso": "look from the south-west corner, 45° up",
               "reset": "the view the canopy first opened in"}


def _action(window, menu, text: str, slot, shortcut=None, tip: str = "") -> QAction:
    act = QAction(text, window)
    if shortcut is not None:
        act.setShortcut(QKeySequence(shortcut))
    if tip:
        act.setStatusTip(tip)
        act.setToolTip(tip)
    act.triggered.connect(lambda _checked=False: slot())
    menu.addAction(act)
    return act


def build_menus(w) -> dict[str, QAction]:
    """Fill ``w.menuBar()``; returns the actions by name (tests and state updates use them)."""
    bar = w.menuBar()
    acts: dict[str, QAction] = {}
    f = bar.addMenu("&File")
    acts["open"] = _action(w, f, "&Open points…", w.choose_points, QKeySequence.StandardKey.Open,
                           "open a digitized points CSV")
    acts["open_project"] = _action(w, f, "Open &project…", w.choose_project, "Ctrl+Shift+O",
                                   "open a maizeviz project")
    acts["open_mesh"] = _action(w, f, "Open canopy &mesh…", w.choose_mesh, "Ctrl+Shift+M",
                                "open a canopy from elsewhere (OpenAlea, Helios, a scan): PLY "
                                "or OBJ with a plant and a leaf id per face")
    w.recent_menu = f.addMenu("Open &recent")
    w.recent_menu.menuAction().setStatusTip("the points, projects and meshes opened last")
    w.recent_menu.aboutToShow.connect(lambda: fill_recent(w))
    f.addSeparator()
    acts["save"] = _action(w, f, "&Save project", w.save_project_here,
                           QKeySequence.StandardKey.Save,
                           "save points, layout, settings and light results in one file")
    acts["save_as"] = _action(w, f, "Save project &as…", w.choose_project_target,
                              QKeySequence.StandardKey.SaveAs,
                              "save the study in a new project file (and go on in that one)")
    f.addSeparator()
    acts["export_mesh"] = _action(w, f, "&Export mesh…", lambda: w.choose_export("canopy"),
                                  "Ctrl+E", "the canopy with plant, leaf and light ids per "
                                            "triangle (PLY, VTK, OBJ, STL)")
    results = f.addMenu("Export &results")
    results.menuAction().setStatusTip("light results and canopy measures as CSV and PNG files")
    acts["export_table"] = _action(w, results, "Transmission table (CSV)…",
                                   lambda: w.choose_export("table"), "Ctrl+Shift+T",
                                   "the Light panel's transmission table (by height, level "
                                   "and light)")
    acts["export_measures"] = _action(w, results, "Canopy measures, Table 2 (CSV)…",
                                      lambda: w.choose_export("measures"), None,
                                      "triangles, leaf area and cover per mesh level built")
    acts["export_heatmap"] = _action(w, results, "Heatmap shown (PNG)…",
                                     lambda: w.choose_export("heatmap"), "Ctrl+Shift+H",
                                     "the heatmap shown, with its colour bar")
    acts["export_plot"] = _action(w, results, "Transmission vs height (PNG)…",
                                  lambda: w.choose_export("plot"), "Ctrl+Shift+G",
                                  "the transmission-height curves shown")
    acts["export_canopy"] = _action(w, results, "Canopy coloured by light (PLY/VTK)…",
                                    lambda: w.choose_export("canopy"), None,
                                    "the canopy with each triangle's light (PLY or VTK)")
    results.addSeparator()
    acts["export_steps"] = _action(w, results, "Day: time steps (CSV)…",
                                   lambda: w.choose_export("steps"), None,
                                   "the day's light at each time step")
    acts["export_leaves"] = _action(w, results, "Light per leaf (CSV)…",
                                    lambda: w.choose_export("leaves"), None,
                                    "light intercepted or absorbed by each leaf (a sky, a "
                                    "day, or a sun with leaf optics and its CO2)")
    acts["export_plants"] = _action(w, results, "Light per plant (CSV)…",
                                    lambda: w.choose_export("plants"), None,
                                    "light intercepted or absorbed by each plant (a sky, a "
                                    "day, or a sun with leaf optics and its CO2)")
    acts["export_day"] = _action(w, results, "Day figure (PNG)…",
                                 lambda: w.choose_export("day"), None,
                                 "the day's light and transmission over the hours")
    acts["window_image"] = _action(w, f, "Save &window as image…", w.choose_window_image,
                                   None, "the whole window, panels and figures as they are "
                                         "on screen, as a PNG")
    acts["view_image"] = _action(w, f, "Save view as &image…", w.view_link.choose_image,
                                 "Ctrl+Alt+S", "the 3D view as a PNG of a chosen width, with "
                                               "its colour key")
    f.addSeparator()
    acts["quit"] = _action(w, f, "&Quit", w.close, QKeySequence.StandardKey.Quit,
                           "close the window (asks first if there is unsaved work)")

    e = bar.addMenu("&Edit")
    stack = w.undo.stack
    acts["undo"] = stack.createUndoAction(w, "&Undo")
    acts["undo"].setShortcut(QKeySequence.StandardKey.Undo)
    acts["redo"] = stack.createRedoAction(w, "&Redo")
    acts["redo"].setShortcuts([QKeySequence("Ctrl+Shift+Z"), QKeySequence("Ctrl+Y")])
    acts["undo"].setStatusTip("undo the last edit of the study (layout, level, settings, "
                              "colours)")
    acts["redo"].setStatusTip("do again the edit last undone")
    for name in ("undo", "redo"):
        # from anywhere in the window (a text field keeps its own Ctrl+Z while it has focus)
        acts[name].setShortcutContext(Qt.ShortcutContext.ApplicationShortcut)
        e.addAction(acts[name])
    e.addSeparator()
    acts["history"] = _action(w, e, "Undo &history", w.show_history, "Ctrl+Alt+Z",
                              "every edit of this study, undone and redone by clicking it")

    v = bar.addMenu("&View")
    cam = v.addMenu("&Camera")
    cam.menuAction().setStatusTip("look at the canopy from the top, front, side or a corner")
    for k, (name, text) in enumerate(CAMERAS.items(), start=1):
        if name == "reset":
            cam.addSeparator()
        acts[f"camera_{name}"] = _action(w, cam, text, lambda n=name: w.camera(n),
                                         "Ctrl+0" if name == "reset" else f"Ctrl+{k}",
                                         CAMERA_TIPS[name])
    colour = v.addMenu("C&olour by")
    colour.menuAction().setStatusTip("colour the canopy by plant, leaf rank or light")
    group = QActionGroup(w)
    for k, (name, text) in enumerate(COLOURINGS.items(), start=1):
        act = _action(w, colour, text[0].upper() + text[1:], lambda n=name: w.colour_by(n),
                      f"Ctrl+Shift+{k}", f"colour the canopy by {text}")
        act.setCheckable(True)
        act.setChecked(name == "leaf")
        group.addAction(act)
        acts[f"colour_{name}"] = act
    from maizeviz_app.probe import KINDS
    from maizeviz_app.view_state import OTHERS

    v.addSeparator()
    for (kind, text), keys in zip(KINDS.items(), ("Ctrl+M", "Ctrl+Shift+M")):
        def toggle_probe(k=kind):
            probe = w.model.probe
            probe.start("" if probe.kind == k else k)
        act = _action(w, v, text, toggle_probe, keys,
                      "click two points on the canopy: their distance" if kind == "distance"
                      else "click the corners of a polygon on the canopy: its area (and its "
                           "shadow's)")
        act.setCheckable(True)
        acts[f"measure_{kind}"] = act

    others = v.addMenu("&Selection")
    others.menuAction().setStatusTip("how the other plants are drawn while one is selected")
    others_group = QActionGroup(w)
    for name, text in OTHERS.items():
        act = _action(w, others, text,
                      lambda n=name: setattr(w.model.view, "others", n), None,
                      f"while a plant is selected: {text.lower()}")
        act.setCheckable(True)
        act.setChecked(name == w.model.view.others)
        others_group.addAction(act)
        acts[f"others_{name}"] = act
    v.addSeparator()
    acts["finer"] = _action(w, v, "&Finer mesh", lambda: w.step_level(-1), "Ctrl+[",
                          "the next finer mesh level (more triangles a leaf)")
    acts["coarser"] = _action(w, v, "C&oarser mesh", lambda: w.step_level(1), "Ctrl+]",
                            "the next coarser mesh level (fewer triangles a leaf)")
    v.addSeparator()
    acts["reset_layout"] = _action(w, v, "&Reset window layout", w.reset_layout,
                                   "Ctrl+Shift+R", "docks back where they started")
    w.docks_menu = v.addMenu("&Panels")
    w.docks_menu.menuAction().setStatusTip("show or hide each panel")
    for dock in w.docks.values():
        toggle = dock.toggleViewAction()
        toggle.setStatusTip(f"show or hide the {dock.windowTitle()} panel")
        w.docks_menu.addAction(toggle)
    acts.update(w.workspaces.fill_menu(v))

    r = bar.addMenu("&Light")
    acts["compute"] = _action(w, r, "&Compute light (sun, sky or day, as chosen)",
                              w.model.compute_light, "Ctrl+L",
                              "trace the light chosen in the Light panel through the canopy")
    for k, mode in enumerate(("sun", "sky", "day"), start=1):
        acts[f"light_{mode}"] = _action(
            w, r, {"sun": "Su&n: direct light", "sky": "S&ky: diffuse light",
                   "day": "&Day: PAR over a day"}[mode],
            lambda m=mode: w.light_panel.set_mode(m), f"Alt+{k}",
            f"choose the {mode}'s light in the Light panel")
    acts["cancel"] = _action(w, r, "C&ancel", w.cancel_jobs, "Esc",
                             "stop the light computation or rebuild under way")
    acts["sun_place"] = _action(w, r, "&Sun from place", w.model.sun_from_place,
                                "Ctrl+Shift+L", "the sun's angles from the date, time and "
                                                "place typed in the Light panel")

    h = bar.addMenu("&Help")
    acts["docs"] = _action(w, h, "&Documentation", w.open_docs,
                           QKeySequence.StandardKey.HelpContents,
                           "the documentation's index: method, commands, this window, "
                           "validation")
    acts["shortcuts"] = _action(w, h, "&Keyboard shortcuts", w.show_shortcuts, None,
                                "every menu command's keys")
    acts["system_info"] = _action(w, h, "&System information", w.show_system_info, None,
                                  "what maizeviz --info prints: versions, Embree, the ray "
                                  "kernel; for a bug report")
    h.addSeparator()
    acts["about"] = _action(w, h, "&About maizeviz", w.about, None,
                            "the version, the libraries and where the documentation is")
    return acts


def fill_recent(w) -> None:
    menu = w.recent_menu
    menu.clear()
    paths = w.recent_files()
    if not paths:
        act = menu.addAction("(none yet)")
        act.setEnabled(False)
        return
    for k, path in enumerate(paths, start=1):
        act = menu.addAction(f"&{k} {Path(path).name}  —  {Path(path).parent}")
        act.setToolTip(path)
        act.triggered.connect(lambda _c=False, p=path: w.open_any(p))
    menu.addSeparator()
    menu.addAction("Clear the list").triggered.connect(lambda _c=False: w.clear_recent())
