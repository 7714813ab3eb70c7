"""The 3D view kept in step with the study: the canopy built is shown, coloured as the study's
view state says (:class:`maizeviz_app.view_state.ViewState`: the light last computed on it,
once there is some), pointed by the camera preset it asks for; the View menu's colourings and
cameras set that state. From the start of a
digitizing session the view is the digitizer's (the plant being digitized): a canopy built
meanwhile waits, and comes back in the Analyse workspace once the session has stopped
(:mod:`maizeviz_app.workspaces`).
"""

from __future__ import annotations

from typing import Any

from maizeviz_app.options import COLOURINGS
from maizeviz_app.runs import assimilation_legend, value_legend


class ViewLink:
    """Wires ``window.model`` to ``window.viewport`` (made later: nothing happens before)."""

    def __init__(self, window) -> None:
        self.window = window
        self.pending: tuple | None = None     # (canopy, mesh) built while digitizing
        self.away = False                     # the digitizer has the view (until Analyse)
        m = window.model
        m.canopy_changed.connect(self.show_built)
        m.view_light.connect(self.light_to_view)
        m.light_added.connect(self._painted)
        m.colour.events.painting.connect(lambda _p: self.light_to_view())
        m.view.events.colouring.connect(lambda *_: self.render_colouring())
        m.view.events.camera.connect(lambda name, *_: self._point(name))

    def attach(self, viewport) -> None:
        """The viewport made: the camera's pose goes both ways between it and the study's
        view state."""
        state = self.window.model.view
        viewport.camera_moved.connect(lambda pose: setattr(state, "pose", pose))
        state.events.pose.connect(lambda pose, *_: viewport.set_camera_pose(pose))
        viewport.set_others(state.others)
        state.events.others.connect(lambda mode, *_: self._others(mode))
        self.window.model.probe.changed.connect(self._probe)

    def _probe(self) -> None:
        """The probe's points drawn, what it measures said; the menu follows."""
        probe = self.window.model.probe
        if self.view is not None:
            self.view.show_probe(probe.points, closed=probe.kind == "area")
        text = probe.text()
        if text:
            self.window.say(text, status_only=len(probe.points) < 2)
        acts = getattr(self.window, "menu_actions", {})
        for kind in ("distance", "area"):
            act = acts.get(f"measure_{kind}")
            if act is not None:
                act.setChecked(probe.kind == kind)

    def _others(self, mode: str) -> None:
        """The others than the selection drawn as the view state says; the menu follows."""
        if self.view is not None:
            self.view.set_others(mode)
        acts = getattr(self.window, "menu_actions", {})
        for name in ("shown", "faded", "hidden"):
            act = acts.get(f"others_{name}")
            if act is not None:
                act.setChecked(mode == name)

    @property
    def view(self) -> Any:
        return self.window.viewport

    @property
    def digitizing(self) -> bool:
        """A digitizing session is recording (the view shows the plant being digitized)."""
        d = self.window.digitizer
        return d is not None and d.recording

    def show_built(self, built) -> None:
        """A canopy built: the view changes with the level label and Table 2 (their panel
        follows the study); while the digitizer records, the canopy waits."""
        say = self.window.say
        mesh = built.polydata
        if self.view is None:
            return
        if self.digitizing or self.away:
            self.pending = (built.canopy, mesh)
            say(f"{built.label} is ready; it shows in the Analyse workspace once the "
                "digitizing session stops", status_only=True)
        else:
            self.pending = None
            self.view.show_canopy(built.canopy, mesh)
        m = built.measures
        if mesh is not None and "view_note" in mesh.field_data:
            say(f"note: {built.label} has {m.triangles:,} triangles; to keep the window "
                f"responsive {mesh.field_data['view_note'][0]}")
        if not self.digitizing:
            # the light set aside by a layout edit (or back with Undo) first: the status
            # bar is where the user looks, and this line replaces the edit's
            note = self.window.model.light_note
            say((f"{note}; " if note else "")
                + f"{built.label}: {m.triangles:,} triangles, leaf area {m.leaf_area_m2:.2f} "
                f"m², LAI {m.lai:.2f}; built in {built.build_s:.2f} s, measured in "
                f"{built.measure_s:.2f} s", status_only=True)

    def light_to_view(self, colour: bool = False) -> None:
        """Colour the canopy in view by the light last computed on it (the sun's classes, or a
        sky's or day's light per leaf), unless the view is busy with the digitizer;
        ``colour``: switch the colouring to light."""
        m = self.window.model
        if self.view is None or m.built is None or self.digitizing or self.away or \
                self.pending is not None:
            return
        run = m.runs.latest(m.shown_signature)
        if run is not None and run.kind == "sun" and run.classes is not None and \
                (run.extra is None or run.extra.leaf_value is None):
            self.view.set_sun(run.painting, m.colour.painting, run.classes)
            self.window.colour_panel.show_painting(self.view.painting_note)
        elif run is not None and run.extra is not None and \
                getattr(run.extra, "leaf_value", None) is not None:
            title, unit = value_legend(run)
            self.view.set_light_values(run.extra.leaf_value, title, unit)
            self.window.colour_panel.show_painting("")      # a sun's painting is not shown
        gross = getattr(run.extra, "gross_value", None) if run is not None else None
        if gross is not None:                   # a leaf model too: its CO2 assimilation
            self.view.set_assimilation_values(gross, *assimilation_legend(run))
        else:
            self.view.set_assimilation_values(None)
        self.render_colouring()

    def render_colouring(self) -> None:
        """The view coloured as the study's view state says (once the view holds what that
        colouring needs; else as it can until then)."""
        if self.view is not None and not (self.digitizing or self.away):
            self.view.colour_by(self.window.model.view.colouring)
        self.sync_colour_actions()

    def _painted(self, run) -> None:
        """A new sun: say how the view paints it (per triangle, or per leaf where triangles
        are smaller than the ray spacing)."""
        m = self.window.model
        if run.painting is not None and self.view is not None and \
                m.shown_signature == run.signature and self.view.painting_note:
            self.window.say(f"note: the view shows {self.view.painting_note}")

    def choose_image(self) -> None:
        """File > Save view as image: ask the width and the file, then save."""
        if self.view is None:
            return
        from maizeviz_app.snapshot import ask_view_image

        chosen = ask_view_image(self.window, self.view, self.window.folder())
        if chosen is not None:
            self.save_image(*chosen)

    def save_image(self, path, width: int | None = None) -> None:
        """The 3D view as a PNG ``width`` pixels wide (None: the view's), with its colour key
        (:mod:`maizeviz_app.snapshot`)."""
        if self.view is None:
            return
        from maizeviz.errors import MaizevizError
        from maizeviz_app.snapshot import save_view_image

        try:
            written = save_view_image(self.view, path, width)
        except (MaizevizError, OSError, ValueError) as exc:
            self.window.model.fail(exc, "export")
            return
        self.window.say(f"saved the view as {written}")
        self.window.saved.emit(str(written))

    def camera(self, name: str) -> None:
        """View > a camera preset: the study's view state asks for it."""
        self.window.model.view.ask_camera(name)

    def _point(self, name: str) -> None:
        if self.view is not None and not (self.digitizing or self.away):
            self.view.camera_preset(name)

    def colour_by(self, what: str) -> None:
        """View > a colouring: the study's (which says why when the canopy shown has none)."""
        self.window.model.colour_view_by(what)
        self.sync_colour_actions()

    def sync_colour_actions(self) -> None:
        for name in COLOURINGS:
            act = self.window.menu_actions.get(f"colour_{name}")
            if act is not None:
                act.setChecked(self.window.model.view.colouring == name)

    def digitizing_started(self) -> None:
        self.away = True
        self.window.workspaces.show("digitize")

    def digitizing_stopped(self, _why: str = "") -> None:
        """In Digitize the plant just digitized stays in the view (no canopy frame on Stop);
        in Analyse the canopy comes back at once."""
        if not self.window.model.closing and self.window.workspaces.current == "analyse":
            self.canopy_back()

    def workspace_changed(self, name: str) -> None:
        if name == "analyse" and not self.digitizing:
            self.canopy_back()

    def canopy_back(self) -> None:
        """The canopy back in the view after a session: the one built meanwhile if any."""
        if not self.away:
            return
        self.away = False
        if self.window.digitizer is not None:
            self.window.digitizer.release_view()
        if self.view is None or self.window.model.canopy is None:
            return
        pending, self.pending = self.pending, None
        if pending is not None:
            self.view.show_canopy(*pending)
            self.view.camera_preset("reset")
        else:
            self.view.restore_canopy()
        self.light_to_view()
