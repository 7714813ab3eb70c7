"""Light: the sun (direct light at one sun position), the sky (diffuse light of an overcast
sky) or a day (direct and diffuse PAR over a day at a place); Compute/Cancel, the results table
(every height, every mesh level and light traced with the same sampling), the day's summary and
the light each plant intercepted, and the figures (heatmap per height and light, transmission
vs height).

The panel's fields are bound both ways to the study's light settings
(:class:`maizeviz_app.settings.StudySettings`: ``light``, ``sun``, ``sampling``, ``sky``,
``day``, ``optics``, ``photosynthesis``): what is typed is the model's, and a project opened or
an undo shows in the fields. :class:`LightRuns` is the results' model: the last result per mesh
level and light (sun, sky, day), all sampled the same way (heights, density, periodic field),
so switching levels or lights and computing again adds a column and a curve to the comparison.
Changing the sampling starts a new comparison; changing one light's own settings (the sun's
angles, the sky, the day) replaces that light's results only.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import (
    QAbstractItemView,
    QCheckBox,
    QComboBox,
    QCompleter,
    QDateEdit,
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QLineEdit,
    QPushButton,
    QRadioButton,
    QSizePolicy,
    QSpinBox,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from maizeviz_app.bind import bind, bind_choice
from maizeviz_app.panels.heatmap_view import HeatmapView
from maizeviz_app.panels.image_view import ImageView
from maizeviz_app.runs import MODES, SKIES, LightRuns, Run, level_order  # noqa: F401 - re-exported
from maizeviz_app.settings import (  # noqa: F401 - re-exported
    DEFAULT_HEIGHTS,
    DEFAULT_PLACE,
    InputProblem,
    StudySettings,
    parse_heights,
)

PROBLEM_STYLE = "border: 2px solid #d0342c; border-radius: 3px;"
MODE_BUTTONS = {"sun": "Sun", "sky": "Sky", "day": "Day"}
COMPUTE_TEXT = {"sun": "Compute direct light", "sky": "Compute diffuse light",
                "day": "Compute the day's light"}
#: Sky splits offered: directions (None: an equal-area split of n) -> what the combo says.
SKY_SPLITS = {16: "16 directions (turtle)", 46: "46 directions (turtle, as Caribu)",
              145: "145 directions (Tregenza)", None: "equal-area split of n directions"}


def _form() -> QFormLayout:
    form = QFormLayout()
    form.setFieldGrowthPolicy(QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)
    # a narrow dock (1366 x 768) puts a field under its label rather than cutting either
    form.setRowWrapPolicy(QFormLayout.RowWrapPolicy.WrapLongRows)
    return form


def _time_zones() -> list[str]:
    try:
        import zoneinfo

        return sorted(zoneinfo.available_timezones())
    except Exception:  # noqa: BLE001 - only the completer's list
        return ["UTC", "Asia/Shanghai", "Europe/Paris", "America/Chicago"]


class PageStack(QWidget):
    """Pages shown one at a time, of which only the one shown takes room (a column whose
    other pages are hidden). A QStackedWidget is as tall as its tallest page (its layout's
    height for a width is the tallest's: the sun's with its optics open, 527 px), so the
    day's page (279 px) stood in a gap that pushed the sky it needs below a laptop's dock."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self._column = QVBoxLayout(self)
        self._column.setContentsMargins(0, 0, 0, 0)
        self._pages: list[QWidget] = []
        self._current = -1

    def addWidget(self, page: QWidget) -> int:  # noqa: N802 - QStackedWidget's name
        self._pages.append(page)
        self._column.addWidget(page)
        if self._current < 0:
            self._current = 0
        page.setVisible(len(self._pages) - 1 == self._current)
        return len(self._pages) - 1

    def count(self) -> int:
        return len(self._pages)

    def widget(self, index: int) -> QWidget | None:
        return self._pages[index] if 0 <= index < len(self._pages) else None

    def currentIndex(self) -> int:  # noqa: N802 - QStackedWidget's name
        return self._current

    def currentWidget(self) -> QWidget | None:  # noqa: N802 - QStackedWidget's name
        return self.widget(self._current)

    def setCurrentIndex(self, index: int) -> None:  # noqa: N802 - QStackedWidget's name
        self._current = index
        for k, page in enumerate(self._pages):
            page.setVisible(k == index)


class LightPanel(QWidget):
    """The light settings of ``study`` (a :class:`~maizeviz_app.model.StudyModel`; its
    ``settings``, bound both ways) and its results table (its runs fill it). Without a study
    the panel edits ``settings`` (default: settings of its own).

    Signals: ``compute_requested()``, ``cancel_requested()``, ``place_requested()``,
    ``export_requested(what)`` with what in ``table``, ``heatmap``, ``plot``, ``canopy``,
    ``steps``, ``leaves``, ``plants``, ``day``."""

    compute_requested = Signal()
    cancel_requested = Signal()
    place_requested = Signal()
    export_requested = Signal(str)

    def __init__(self, study=None, settings: StudySettings | None = None, parent=None):
        super().__init__(parent)
        self.study = study
        self.settings = study.settings if study is not None else settings or StudySettings()
        s = self.settings
        lay = QVBoxLayout(self)
        # ---- which light
        modes = QHBoxLayout()
        modes.addWidget(QLabel("light"))
        self.mode_buttons: dict[str, QPushButton] = {}
        tips = {"sun": "direct light at one sun position (the paper's Table 3)",
                "sky": "diffuse light from an overcast sky, traced from many directions",
                "day": "direct and diffuse PAR over a day at a place: clear sky or a weather "
                       "file"}
        for mode in MODES:
            b = QPushButton(MODE_BUTTONS[mode])
            b.setToolTip(tips[mode])
            self.mode_buttons[mode] = b
            modes.addWidget(b, 1)
        self.mode_group = bind_choice(self.mode_buttons, s.light, "mode")
        lay.addLayout(modes)
        self.pages = PageStack()
        self.pages.addWidget(self._sun_page())
        self.pages.addWidget(self._day_page())
        self.pages.addWidget(QWidget())               # the sky needs only the sky group
        lay.addWidget(self.pages)
        self.sky_box = self._sky_group()
        lay.addWidget(self.sky_box)
        # ---- sampling, shared by every light
        form = _form()
        self.heights = QLineEdit()
        self.heights.setToolTip("heights of the sensor planes, cm, separated by commas")
        bind(self.heights, s.sampling, "heights", "heights (cm)")
        form.addRow("heights (cm)", self.heights)
        self.density = QDoubleSpinBox(decimals=2, suffix=" rays/cm²")
        self.density.setToolTip("rays (and sensors) per cm² of the sample rectangle, for the "
                                "sun and for each sky direction and time step")
        bind(self.density, s.sampling, "density", "ray density")
        form.addRow("ray density", self.density)
        self.periodic = QCheckBox("infinite field (rays wrap at the plot edges)")
        self.periodic.setToolTip("rays leaving the plot sideways come back on the other side, "
                                 "as in a field that goes on (off: an isolated plot)")
        bind(self.periodic, s.sampling, "periodic")
        form.addRow(self.periodic)
        self.stalks = QCheckBox("stalks take light")
        self.stalks.setAccessibleName("stalks take light")
        self.stalks.setToolTip("the stalks intercept and scatter light as the leaves do (off: "
                               "the leaves alone, as the paper's canopy and maizeviz light "
                               "--leaves-only)")
        bind(self.stalks, s.light, "stalks")
        form.addRow(self.stalks)
        lay.addLayout(form)
        # ---- compute, cancel, progress, problems
        buttons = QHBoxLayout()
        self.compute_button = QPushButton(COMPUTE_TEXT["sun"])
        self.compute_button.setToolTip("trace the light through the canopy shown (Ctrl+L)")
        self.compute_button.clicked.connect(self.compute_requested)
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.setToolTip("stop the light computation (Esc)")
        self.cancel_button.setEnabled(False)
        self.cancel_button.clicked.connect(self.cancel_requested)
        buttons.addWidget(self.compute_button, 1)
        buttons.addWidget(self.cancel_button)
        lay.addLayout(buttons)
        self.progress = QLabel("")
        self.progress.setStyleSheet("color: #1f4e79;")
        self.progress.setWordWrap(True)
        lay.addWidget(self.progress)
        self.problem = QLabel("")
        self.problem.setWordWrap(True)
        self.problem.setStyleSheet("color: #b3261e; font-weight: bold;")
        self.problem.hide()
        lay.addWidget(self.problem)
        # ---- results
        self.table_title = QLabel("transmission by height, mesh level and light (the paper's "
                                  "Table 3 for the sun)")
        self.table_title.setWordWrap(True)
        lay.addWidget(self.table_title)
        self.table = QTableWidget(0, 1)
        self.table.setAccessibleName("transmission table")
        self.table.setToolTip("the fraction of the light reaching each height, per mesh level "
                              "and light")
        self.table.setHorizontalHeaderLabels(["height cm"])
        self.table.verticalHeader().setVisible(False)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setVerticalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        self.table.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        lay.addWidget(self.table)
        self.info = QLabel("")
        self.info.setWordWrap(True)
        lay.addWidget(self.info)
        self.summary = QLabel("")
        self.summary.setWordWrap(True)
        self.summary.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.summary.setStyleSheet("background: #fff8e1; padding: 4px;")
        self.summary.hide()
        lay.addWidget(self.summary)
        self.plants_title = QLabel("")
        self.plants_title.setWordWrap(True)
        self.plants_title.hide()
        lay.addWidget(self.plants_title)
        self.plants = QTableWidget(0, 0)
        self.plants.setAccessibleName("light per plant")
        self.plants.setToolTip("the light each plant intercepted or absorbed")
        self.plants.verticalHeader().setVisible(False)
        self.plants.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.plants.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        self.plants.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        self.plants.hide()
        lay.addWidget(self.plants)
        # ---- exports
        self.export_buttons = {}
        rows = (
            (("table", "Table…", "the transmission table as CSV"),
             ("heatmap", "Heatmap…", "the heatmap shown, as PNG"),
             ("plot", "Plot…", "transmission vs height, as PNG"),
             ("canopy", "Canopy…", "the canopy with its light per triangle as cell data "
                                   "(PLY, VTK...)")),
            (("steps", "Steps…", "the day's time steps as CSV (sun, irradiance, PAR "
                                 "intercepted, transmission)"),
             ("leaves", "Leaves…", "the light each leaf intercepted, as CSV"),
             ("plants", "Plants…", "the light each plant intercepted, as CSV"),
             ("day", "Day figure…", "PAR through the day and the transmission profile, as "
                                    "PNG")))
        lay.addWidget(QLabel("export"))
        for row in rows:
            line = QHBoxLayout()
            for what, text, tip in row:
                b = QPushButton(text)
                b.setToolTip(f"export {tip}")
                b.setEnabled(False)
                b.clicked.connect(lambda _=False, w=what: self.export_requested.emit(w))
                line.addWidget(b)
                self.export_buttons[what] = b
            lay.addLayout(line)
        lay.addStretch(1)
        self.fields: dict[str, Any] = {"heights": self.heights, "density": self.density,
                                       "periodic": self.periodic, "stalks": self.stalks,
                                       "rect": self.heights,
                                       "threads": self.density}
        self.mode_fields: dict[str, dict[str, Any]] = {
            "sun": {"band": self.band, "reflectance": self.reflectance,
                    "transmittance": self.transmittance,
                    "ground_reflectance": self.ground_reflectance,
                    "photosynthesis": self.photo_model, "temperature": self.leaf_temp,
                    "sun": self.zenith, "place": self.place, "date": self.place,
                    "time": self.place, "tz": self.place},
            "sky": {"sky": self.sky_kind, "sky_directions": self.sky_n},
            "day": {"sky": self.sky_kind, "sky_directions": self.sky_n,
                    "diffuse": self.day_diffuse,
                    "date": self.day_date, "place": [self.lat, self.lon], "tz": self.tz,
                    "step": self.step, "period": [self.day_from, self.day_to],
                    "par_factor": self.par_factor, "linke_turbidity": self.linke,
                    "weather": self.weather, "altitude": self.lat, "time": self.day_from}}
        # a field edited loses its problem mark; so does every field when the light changes
        for name, group in s.groups.items():
            if name not in ("canopy", "digitizer"):
                group.events.connect(self._setting_changed)
        self._show_mode(s.light.mode)
        self._fit_table()
        if study is not None:
            study.runs_changed.connect(self.show_runs)
            self.destroyed.connect(lambda *_: study.runs_changed.disconnect(self.show_runs))

    def _setting_changed(self, info=None) -> None:
        """A light setting changed (typed, opened, undone): its field's problem mark goes;
        the widgets that depend on it follow."""
        try:
            name = info.signal.name if info is not None else ""
        except AttributeError:
            name = ""
        if name == "mode":
            self._show_mode(self.settings.light.mode)
            self.clear_problem()
            return
        if name in ("split", "directions"):
            self._show_split()
        if name in ("source",):
            self._show_source()
        if name in ("diffuse",):
            self._sync_sky_kind()
        if name == "model":
            self._show_photosynthesis()
        widget = self._widget_of(name)
        if widget is not None:
            self.clear_problem(widget)

    def _widget_of(self, name: str):
        return {"heights": self.heights, "density": self.density, "periodic": self.periodic,
                "stalks": self.stalks,
                "zenith_deg": self.zenith, "azimuth_deg": self.azimuth, "place": self.place,
                "kind": self.sky_kind, "directions": self.sky_n, "date": self.day_date,
                "latitude": self.lat, "longitude": self.lon, "tz": self.tz,
                "step_min": self.step, "start": self.day_from, "end": self.day_to,
                "linke_turbidity": self.linke, "weather": self.weather,
                "par_factor": self.par_factor, "diffuse": self.day_diffuse,
                "band": self.band, "reflectance": self.reflectance,
                "transmittance": self.transmittance,
                "ground_reflectance": self.ground_reflectance, "model": self.photo_model,
                "temperature_c": self.leaf_temp, "alpha": self.c4_alpha,
                "co2_ppm": self.co2, "amax": self.wofost_amax,
                "eff": self.wofost_eff, "vmax": self.c4_vmax}.get(name)

    # ------------------------------------------------------------------ pages
    def _sun_page(self) -> QWidget:
        s = self.settings.sun
        page = QWidget()
        form = _form()
        form.setContentsMargins(0, 0, 0, 0)
        page.setLayout(form)
        self.zenith = QDoubleSpinBox(decimals=2, suffix=" °")
        self.zenith.setToolTip("angle of the sun from the vertical")
        bind(self.zenith, s, "zenith_deg", "sun zenith")
        self.azimuth = QDoubleSpinBox(decimals=2, suffix=" ° from N")
        self.azimuth.setToolTip("direction of the sun, clockwise from north")
        bind(self.azimuth, s, "azimuth_deg", "sun azimuth")
        form.addRow("sun zenith", self.zenith)
        form.addRow("sun azimuth", self.azimuth)
        self.place = QLineEdit()
        self.place.setToolTip("date, local time, latitude, longitude, time zone: the sun's "
                              "angles are computed with pvlib")
        bind(self.place, s, "place", "date, time, latitude, longitude, time zone")
        self.place_button = QPushButton("Sun from place")
        self.place_button.setToolTip("compute the sun's zenith and azimuth from the date, "
                                     "time and place typed (Ctrl+Shift+L)")
        self.place_button.clicked.connect(self.place_requested)
        place_row = QHBoxLayout()
        place_row.addWidget(self.place, 1)
        place_row.addWidget(self.place_button)
        # the place on a row of its own: the whole of it shows in a narrow dock
        form.addRow(QLabel("date, time, latitude, longitude, time zone"))
        form.addRow(place_row)
        form.addRow(self._optics_group())
        return page

    def _optics_group(self) -> QGroupBox:
        """Leaf optics: absorbed light with scattering (off: black leaves, interception)."""
        o = self.settings.optics
        box = QGroupBox("leaf optics: absorbed light with scattering")
        box.setCheckable(True)
        box.setToolTip("off: leaves are black (light intercepted at first hits); on: leaves "
                       "reflect and transmit, light is followed through the canopy and each "
                       "leaf's absorbed light painted on the plants, with the energy balance")
        bind(box, o, "enabled", "leaf optics")
        form = _form()
        box.setLayout(form)
        self.optics_box = box
        self.band = QComboBox()
        self.band.addItem("PAR (400-700 nm)", "par")
        self.band.addItem("NIR (700-3000 nm)", "nir")
        self.band.setToolTip("the waveband traced; its leaf and soil optics and irradiance "
                             "follow the band's defaults (maize: see docs/method.md)")
        bind(self.band, o, "band", "band")
        form.addRow("band", self.band)

        def fraction(name: str, label: str, tip: str) -> QDoubleSpinBox:
            w = QDoubleSpinBox(decimals=3, singleStep=0.01)
            w.setToolTip(tip)
            bind(w, o, name, label)
            return w

        self.reflectance = fraction("reflectance", "leaf ρ",
                                    "share of the light a leaf reflects (Lambertian)")
        self.transmittance = fraction("transmittance", "leaf τ",
                                      "share of the light a leaf transmits (Lambertian)")
        self.ground_reflectance = fraction("ground_reflectance", "soil ρ",
                                           "share of the light the soil reflects")
        leaf = QHBoxLayout()
        leaf.addWidget(QLabel("ρ"))
        leaf.addWidget(self.reflectance, 1)
        leaf.addWidget(QLabel("τ"))
        leaf.addWidget(self.transmittance, 1)
        form.addRow("leaf", leaf)
        form.addRow("soil ρ", self.ground_reflectance)
        self.direct_w = QDoubleSpinBox(decimals=1, suffix=" W/m²")
        self.direct_w.setToolTip("the band's direct irradiance on a horizontal plane above the "
                                 "canopy")
        bind(self.direct_w, o, "direct_w_m2", "direct")
        self.diffuse_w = QDoubleSpinBox(decimals=1, suffix=" W/m²")
        self.diffuse_w.setToolTip("the band's diffuse irradiance on a horizontal plane, from a "
                                  "standard overcast sky of 46 directions (0: direct only)")
        bind(self.diffuse_w, o, "diffuse_w_m2", "diffuse")
        form.addRow("direct", self.direct_w)
        form.addRow("diffuse", self.diffuse_w)
        self.scatter_depth = QSpinBox()
        self.scatter_depth.setToolTip("most scatterings followed per ray (0: first hits only; "
                                      "Russian roulette ends most paths long before, as on "
                                      "the command line)")
        bind(self.scatter_depth, o, "depth", "scattering depth")
        form.addRow("scattering depth", self.scatter_depth)
        form.addRow(self._photosynthesis_group())
        return box

    def _photosynthesis_group(self) -> QGroupBox:
        """Leaf photosynthesis of the absorbed PAR: the model and its main parameters (those
        of the model chosen show), bound to ``settings.photosynthesis``."""
        ph = self.settings.photosynthesis
        box = QGroupBox("photosynthesis (gross CO₂ assimilation)")
        box.setToolTip("each leaf's absorbed PAR turned into gross CO₂ assimilation, the sunlit "
                       "and shaded parts of every triangle each at its own light; painted on "
                       "the plants (View > Colour by > CO₂ assimilation) and added to the "
                       "plants table. PAR only")
        form = _form()
        box.setLayout(form)
        self.photo_box = box
        self.photo_model = QComboBox()
        self.photo_model.addItem("none (absorbed light only)", "none")
        self.photo_model.addItem("C4 leaf (Collatz et al. 1992, maize)", "c4")
        self.photo_model.addItem("WOFOST negative exponential", "wofost")
        self.photo_model.setToolTip("the leaf model: Collatz, Ribas-Carbo & Berry's C4 leaf "
                                    "with maize parameters, or the crop model WOFOST's light "
                                    "response (see docs/method.md)")
        bind(self.photo_model, ph, "model", "leaf model")
        form.addRow("leaf model", self.photo_model)

        def number(name: str, label: str, decimals: int, suffix: str, tip: str,
                   step: float = 1.0) -> QDoubleSpinBox:
            w = QDoubleSpinBox(decimals=decimals, suffix=suffix, singleStep=step)
            w.setToolTip(tip)
            bind(w, ph, name, label)
            return w

        self.leaf_temp = number("temperature_c", "leaf temperature", 1, " °C",
                                "air (leaf) temperature: the C4 model's Vmax, k and Rd "
                                "follow it (WOFOST's leaf response does not)")
        self.c4_vmax = number("vmax", "C4 Vmax at 25 °C", 1, " µmol/m²/s",
                              "Rubisco capacity at 25 °C (maize: 39, Collatz et al. 1992)")
        self.c4_alpha = number("alpha", "C4 quantum yield", 3, " mol/mol",
                               "CO₂ fixed per absorbed PAR photon (maize: 0.04)", 0.005)
        self.co2 = number("co2_ppm", "CO₂", 0, " ppm", "ambient CO₂ (intercellular: 0.4 of it)",
                          10.0)
        self.c4_temperature = QComboBox()
        self.c4_temperature.addItem("Collatz et al. 1992 (the paper's)", "collatz")
        self.c4_temperature.addItem("CLM 4.5 (maizeviz 0.2)", "clm45")
        self.c4_temperature.setToolTip(
            "how the C4 leaf's Rubisco capacity falls in heat and cold: the paper's own "
            "response (Vmax 44.7 µmol/m²/s at 35 °C, 25.5 at 40 °C) or the Community Land "
            "Model 4.5's (62.6 and 54.8), which maizeviz 0.2 used (see docs/method.md)")
        bind(self.c4_temperature, ph, "c4_temperature", "C4 temperature response")
        self.wofost_amax = number("amax", "WOFOST AMAX", 1, " kg CO₂/ha/h",
                                  "assimilation at light saturation (maize: 70)")
        self.wofost_eff = number("eff", "WOFOST EFF", 3, " kg/ha/h per W/m²",
                                 "initial light use efficiency (0.45)", 0.01)
        self.photo_rows: dict[str, list[QWidget]] = {"c4": [], "wofost": []}
        form.addRow("leaf temperature", self.leaf_temp)
        for model, widget, text in (("c4", self.c4_vmax, "Vmax (25 °C)"),
                                    ("c4", self.c4_alpha, "quantum yield α"),
                                    ("c4", self.co2, "CO₂"),
                                    ("c4", self.c4_temperature, "temperature response"),
                                    ("wofost", self.wofost_amax, "AMAX"),
                                    ("wofost", self.wofost_eff, "EFF")):
            label = QLabel(text)
            form.addRow(label, widget)
            self.photo_rows[model] += [label, widget]
        self._show_photosynthesis()
        return box

    def _show_photosynthesis(self) -> None:
        """Only the chosen model's parameters show (and the temperature with a model)."""
        model = self.settings.photosynthesis.model
        for name, widgets in self.photo_rows.items():
            for w in widgets:
                w.setVisible(name == model)
        self.leaf_temp.setEnabled(model != "none")

    def _sky_group(self) -> QGroupBox:
        s = self.settings.sky
        box = QGroupBox("diffuse sky")
        form = _form()
        box.setLayout(form)
        self.sky_kind = QComboBox()
        for kind, (text, _name) in SKIES.items():
            self.sky_kind.addItem(text, kind)
        self.sky_kind.setToolTip("how the sky's brightness varies with the zenith angle θ "
                                 "(Moon and Spencer's standard overcast sky, or uniform)")
        bind(self.sky_kind, s, "kind", "sky")
        form.addRow("sky", self.sky_kind)
        self.sky_split = QComboBox()
        for n, text in SKY_SPLITS.items():
            self.sky_split.addItem(text, n)
        self.sky_split.setToolTip("the directions the sky is traced from, each weighted by its "
                                  "share of the horizontal diffuse light (the weights sum to 1)")
        self.sky_split.setAccessibleName("directions")
        self.sky_n = QSpinBox(suffix=" directions")
        self.sky_n.setToolTip("directions of an equal-area split of the sky (each cell the "
                              "same solid angle)")
        bind(self.sky_n, s, "directions", "equal-area directions")
        self.sky_split.currentIndexChanged.connect(self._on_split)
        self._show_split()
        split_row = QHBoxLayout()
        split_row.addWidget(self.sky_split, 1)
        split_row.addWidget(self.sky_n)
        form.addRow("directions", split_row)
        return box

    def _day_page(self) -> QWidget:
        d = self.settings.day
        page = QWidget()
        form = _form()
        form.setContentsMargins(0, 0, 0, 0)
        page.setLayout(form)
        self.day_date = QDateEdit()
        self.day_date.setDisplayFormat("yyyy-MM-dd")
        self.day_date.setCalendarPopup(True)
        self.day_date.setToolTip("the local day traced")
        bind(self.day_date, d, "date", "date")
        form.addRow("date", self.day_date)
        self.lat = QDoubleSpinBox(decimals=3, suffix=" ° N")
        self.lat.setToolTip("latitude, degrees north (south negative)")
        bind(self.lat, d, "latitude", "latitude")
        self.lon = QDoubleSpinBox(decimals=3, suffix=" ° E")
        self.lon.setToolTip("longitude, degrees east (west negative)")
        bind(self.lon, d, "longitude", "longitude")
        where = QHBoxLayout()
        where.addWidget(self.lat, 1)
        where.addWidget(self.lon, 1)
        form.addRow("latitude, longitude", where)
        self.tz = QLineEdit()
        self.tz.setToolTip("time zone of the clock times (IANA name such as Asia/Shanghai, "
                           "Europe/Paris or UTC)")
        bind(self.tz, d, "tz", "time zone")
        completer = QCompleter(_time_zones(), self.tz)
        completer.setCaseSensitivity(Qt.CaseSensitivity.CaseInsensitive)
        completer.setFilterMode(Qt.MatchFlag.MatchContains)
        self.tz.setCompleter(completer)
        form.addRow("time zone", self.tz)
        self.source_clear = QRadioButton("clear sky (Ineichen-Perez, pvlib), Linke turbidity")
        self.source_clear.setToolTip("irradiance of a cloudless day, with no downloaded data; "
                                     "the Linke turbidity says how hazy the air is (1 clean, "
                                     "3 average rural, 5 and more hazy)")
        self.linke = QDoubleSpinBox(decimals=1, singleStep=0.5)
        self.linke.setToolTip("Linke turbidity of the clear sky: 1 clean air, 3 average rural, "
                              "5 and more hazy")
        bind(self.linke, d, "linke_turbidity", "Linke turbidity")
        clear_row = QHBoxLayout()
        clear_row.addWidget(self.source_clear, 1)
        clear_row.addWidget(self.linke)
        form.addRow(clear_row)
        self.source_weather = QRadioButton("weather file")
        self.source_weather.setToolTip("measured irradiance: a CSV with a time column (with "
                                       "its time zone) and ghi in W/m², optionally dni, dhi, "
                                       "par (µmol/m²/s, used as the PAR) and temp_air (°C); "
                                       "or an EPW, TMY3 or NSRDB PSM3/PSM4 file (its own time "
                                       "zone); it sets the period and its steps")
        self.weather = QLineEdit()
        self.weather.setPlaceholderText("CSV (time, ghi [, dni, dhi, par]), EPW, TMY3, PSM")
        self.weather.setToolTip(self.source_weather.toolTip())
        bind(self.weather, d, "weather", "weather file path")
        self.weather_button = QPushButton("Weather file…")
        self.weather_button.setToolTip("choose the weather file")
        self.weather_button.clicked.connect(self.choose_weather)
        weather_row = QHBoxLayout()
        weather_row.addWidget(self.source_weather)
        weather_row.addWidget(self.weather_button)
        form.addRow(weather_row)
        form.addRow(self.weather)
        self.source_group = bind_choice({"clear": self.source_clear,
                                         "weather": self.source_weather}, d, "source")
        self.step = QDoubleSpinBox(decimals=1, suffix=" min")
        self.step.setToolTip("time step: the sun is traced once per step (at its middle)")
        bind(self.step, d, "step_min", "time step")
        form.addRow("time step", self.step)
        self.day_diffuse = QComboBox()
        self.day_diffuse.addItem("the sky chosen below, all day", "sky")
        self.day_diffuse.addItem("Perez anisotropic: circumsolar with the sun", "perez")
        self.day_diffuse.setToolTip(
            "how each step's diffuse light comes from the sky: one sky shape all day, or "
            "Perez's split of each step (its circumsolar part traced with the sun, the rest "
            "from a uniform sky of the directions chosen below; pvlib)")
        bind(self.day_diffuse, d, "diffuse", "diffuse light")
        form.addRow("diffuse light", self.day_diffuse)
        self.day_from = QLineEdit()
        self.day_from.setPlaceholderText("00:00")
        self.day_to = QLineEdit()
        self.day_to.setPlaceholderText("24:00")
        for w, what, name in ((self.day_from, "start", "start"), (self.day_to, "end", "end")):
            w.setToolTip(f"optional {what} of the period, local clock time HH:MM (empty: the "
                         "whole day)")
            bind(w, d, name, f"hours {'from' if name == 'start' else 'to'}")
        span = QHBoxLayout()
        span.addWidget(QLabel("from"))
        span.addWidget(self.day_from, 1)
        span.addWidget(QLabel("to"))
        span.addWidget(self.day_to, 1)
        form.addRow("hours (optional)", span)
        self.par_factor = QDoubleSpinBox(decimals=4, singleStep=0.01, suffix=" µmol/J")
        self.par_factor.setToolTip("µmol of PAR photons per joule of shortwave (default "
                                   f"0.48 × 4.57 = {0.48 * 4.57:g})")
        bind(self.par_factor, d, "par_factor", "PAR factor")
        form.addRow("PAR factor", self.par_factor)
        self._show_source()
        return page

    def _on_split(self, _index: int = 0) -> None:
        n = self.sky_split.currentData()
        s = self.settings.sky
        if n is None:
            s.split = "equal"
        else:
            self.settings.set("sky", {"split": "auto", "directions": int(n)})

    def _show_split(self) -> None:
        """The split combo and the directions box as the sky settings say."""
        s = self.settings.sky
        n = None if s.split == "equal" or s.directions not in SKY_SPLITS else s.directions
        k = list(SKY_SPLITS).index(n)
        if self.sky_split.currentIndex() != k:
            self.sky_split.blockSignals(True)
            self.sky_split.setCurrentIndex(k)
            self.sky_split.blockSignals(False)
        self.sky_n.setEnabled(n is None)

    def _show_source(self) -> None:
        weather = self.settings.day.source == "weather"
        self.linke.setEnabled(not weather)
        self.weather.setEnabled(weather)
        self.weather_button.setEnabled(weather)
        # a weather file sets the period and its steps
        for w in (self.day_date, self.step, self.day_from, self.day_to):
            w.setEnabled(not weather)

    def choose_weather(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Weather file", self.weather.text(),
                                              "Weather files (*.csv *.epw *.CSV *.EPW);;"
                                              "All files (*)")
        if path and self.study is not None:
            self.study.choose_weather(path)         # its header's place too, one step
        elif path:
            self.settings.set("day", {"weather": path, "source": "weather"})

    # ------------------------------------------------------------------ mode
    @property
    def mode(self) -> str:
        return self.settings.light.mode

    def set_mode(self, mode: str) -> None:
        self.settings.light.mode = mode if mode in MODES else "sun"

    def _show_mode(self, mode: str) -> None:
        page = {"sun": 0, "day": 1, "sky": 2}[mode]
        self.pages.setCurrentIndex(page)
        self.pages.setVisible(mode != "sky")
        self.sky_box.setVisible(mode != "sun")
        self.sky_box.setTitle("diffuse sky" if mode == "sky" else
                              "diffuse part of the day: the sky it comes from")
        self.compute_button.setText(COMPUTE_TEXT[mode])
        self.compute_button.setAccessibleName(COMPUTE_TEXT[mode])
        self._sync_sky_kind()

    def _sync_sky_kind(self) -> None:
        """With Perez's diffuse light in a day, the sky's shape is Perez's (a uniform sky for
        its isotropic part, the circumsolar part with the sun): the shape choice is off."""
        perez = self.mode == "day" and self.settings.day.diffuse == "perez"
        self.sky_kind.setEnabled(not perez)
        self.sky_kind.setToolTip(
            "Perez's diffuse light: its isotropic part comes from a uniform sky of the "
            "directions chosen, its circumsolar part with the sun" if perez else
            "how the sky's brightness varies with the zenith angle θ")

    # ------------------------------------------------------------------ problems
    def point_at(self, quantity: str | None, message: str, mode: str | None = None) -> bool:
        """Mark the field(s) a problem is about (red frame, tooltip, focus), among the shared
        fields and those of ``mode`` (default: the mode shown); False if none."""
        fields = {**self.fields, **self.mode_fields[mode or self.mode]}
        found = fields.get(quantity or "")
        if found is None:
            return False
        widgets = found if isinstance(found, list) else [found]
        for w in widgets:
            if not w.property("tip"):
                w.setProperty("tip", w.toolTip())
            w.setStyleSheet(PROBLEM_STYLE)
            w.setToolTip(message)
        widgets[0].setFocus()
        return True

    def show_problem(self, text: str) -> None:
        """A problem with the light settings, in the panel (empty: none)."""
        self.problem.setText(text)
        self.problem.setVisible(bool(text))

    def _all_fields(self):
        seen = []
        for group in (self.fields, *self.mode_fields.values()):
            for found in group.values():
                for w in (found if isinstance(found, list) else [found]):
                    if w not in seen:
                        seen.append(w)
        return seen

    def clear_problem(self, w=None) -> None:
        for f in ([w] if w is not None else self._all_fields()):
            if f.styleSheet():
                f.setStyleSheet("")
                if f.property("tip"):                   # its own tooltip back
                    f.setToolTip(f.property("tip"))
        if w is None or self.problem.isVisible():
            self.show_problem("")

    def show_failure(self, text: str, doing: str, quantity, mode) -> bool:
        """An error of the study (``doing``: what failed): one about light is said here and
        its field marked; True when a field was."""
        if doing not in ("light", "sun"):
            return False
        self.show_problem(text)
        if quantity:
            return self.point_at(quantity, text, mode or ("sun" if doing == "sun" else None))
        return False

    # ------------------------------------------------------------------ state
    def set_running(self, running: bool) -> None:
        self.compute_button.setEnabled(not running)
        self.cancel_button.setEnabled(running)
        if not running:
            self.progress.setText("")

    def set_progress(self, text: str) -> None:
        self.progress.setText(text)

    def show_runs(self, runs: LightRuns, info: str = "") -> None:
        header, rows = runs.table()
        self.table.setColumnCount(len(header))
        # "36 triangles, overcast sky" on two lines: the table stays narrow
        self.table.setHorizontalHeaderLabels([h.replace(", ", ",\n") for h in header])
        self.table.setRowCount(len(rows))
        for r, vals in enumerate(rows):
            for c, text in enumerate(vals):
                item = QTableWidgetItem(text)
                item.setTextAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
                self.table.setItem(r, c, item)
        self._fit_table()
        self.info.setText(info)
        last = runs.last is not None
        for what in ("table", "heatmap", "plot", "canopy"):
            self.export_buttons[what].setEnabled(last)
        day = runs.of_kind("day") is not None
        for what in ("steps", "day"):
            self.export_buttons[what].setEnabled(day)
        per_leaf = runs.with_plants() is not None
        for what in ("leaves", "plants"):
            self.export_buttons[what].setEnabled(per_leaf)
        if not runs.runs:
            self.show_summary("")
            self.show_plants(None)

    def show_summary(self, text: str) -> None:
        """The day's totals (empty: none)."""
        self.summary.setText(text)
        self.summary.setVisible(bool(text))

    def show_plants(self, run: Run | None) -> None:
        """What each plant intercepted in a sky or day ``run``, or absorbed in a sun traced
        with leaf optics (None: hide the table)."""
        rows = run.extra.plant_rows if run is not None and run.extra is not None else []
        t = self.plants
        if run is None or not rows:
            self.plants_title.hide()
            t.hide()
            return
        day = run.kind == "day"
        keys: tuple[str, ...]
        scale = 1.0
        if run.kind == "sun":
            band = run.extra.light.band.upper()
            header = ["stand", "plant", "x, y cm", f"{band} absorbed W", "W/m² leaf",
                      "sunlit m²"]
            keys = ("absorbed_w", "absorbed_w_m2_leaf", "sunlit_area_cm2")
            fmt = "{:.2f}"
            title = f"{band} each plant absorbs, with scattering"
            assimilation = getattr(run.extra, "assimilation", None)
            if assimilation is not None and "gross_umol_s" in rows[0]:
                # beside the light it comes from, before the sunlit area (a narrow dock
                # shows it without scrolling)
                header[5:5] = ["CO₂ gross µmol/s", "± se"]
                keys = keys[:2] + ("gross_umol_s", "gross_umol_s_se") + keys[2:]
                title += (f", and its gross CO₂ assimilation ({_model_text(assimilation)})")
            self.plants_title.setText(f"{title} ({run.label})")
        elif day:
            header = ["stand", "plant", "x, y cm", "PAR mol", "direct mol", "diffuse mol"]
            keys = ("par_intercepted_mol", "direct_par_intercepted_mol",
                    "diffuse_par_intercepted_mol")
            fmt = "{:.2f}"
            self.plants_title.setText(f"PAR intercepted by each plant over the day, mol "
                                      f"({run.label})")
        else:
            scale = 1.0 / run.result.rect_area_cm2
            header = ["stand", "plant", "x, y cm", "share of the sky light"]
            keys = ("diffuse_intercepted_cm2",)
            fmt = "{:.1%}"
            self.plants_title.setText(f"share of the sky's diffuse light each plant "
                                      f"intercepts ({run.label})")
        t.setColumnCount(len(header))
        # a header of several words on two lines: the table fits a laptop's dock (1366 x 768)
        # without hiding the CO2 columns behind a sideways scroll
        t.setHorizontalHeaderLabels([_two_lines(h) for h in header])
        t.setRowCount(len(rows))
        for r, row in enumerate(rows):
            vals = [str(row["instance"]), str(row["plant"]),
                    f"{float(row['x_cm']):.0f}, {float(row['y_cm']):.0f}"]
            for k in keys:
                v = float(row.get(k, 0.0)) * (1e-4 if run.kind == "sun" and k.endswith("_cm2")
                                              else scale)
                vals.append(fmt.format(v))
            for c, text in enumerate(vals):
                item = QTableWidgetItem(text)
                item.setTextAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
                t.setItem(r, c, item)
        t.resizeColumnsToContents()
        t.resizeRowsToContents()
        shown = min(len(rows), 9)
        h = t.horizontalHeader().sizeHint().height() + 2 * t.frameWidth()
        h += sum(t.rowHeight(r) for r in range(shown))
        t.setFixedHeight(h + (t.horizontalScrollBar().sizeHint().height()
                              if t.columnCount() > 5 else 0))
        self.plants_title.show()
        t.show()

    def _fit_table(self) -> None:
        """Every row visible: the table is as tall as its rows (no vertical scrolling)."""
        t = self.table
        t.resizeRowsToContents()
        head = max(t.horizontalHeader().height(), t.horizontalHeader().sizeHint().height())
        h = head + 2 * t.frameWidth()
        h += sum(t.rowHeight(r) for r in range(t.rowCount()))
        # the sideways scroll bar, when the columns are wider than the table (it may not be
        # shown yet), must not hide the last row
        if t.horizontalScrollBar().isVisible() or t.columnCount() > 4 or \
                t.horizontalHeader().length() > t.viewport().width():
            h += t.horizontalScrollBar().sizeHint().height()
        t.setFixedHeight(max(h, head + 30))


def _two_lines(header: str) -> str:
    """A column header of several words a word a line ("CO₂\ngross\nµmol/s"), as the
    canopy panel's; short ones as they are."""
    return header if len(header) <= 8 else header.replace(" ", "\n")


def _model_text(assimilation) -> str:
    """The leaf model of an assimilation result in a few words: its name, main parameters
    and the leaves' temperature."""
    d = assimilation.model
    if d.get("model") == "wofost":
        what = f"WOFOST, AMAX {d['amax']:g} kg CO₂/ha/h, EFF {d['eff']:g}"
    else:
        form = {"collatz": "Collatz et al. 1992", "clm45": "CLM 4.5"}.get(
            str(d.get("temperature_response", "clm45")), "CLM 4.5")
        what = (f"C4 leaf, Vmax {d['vmax']:g} µmol/m²/s, α {d['alpha']:g}, CO₂ "
                f"{d['co2_ppm']:g} ppm, temperature response {form}")
    return f"{what}, leaves at {assimilation.temp_c:g} °C"


#: What the heatmap selector offers, per light.
MAP_NAMES = {"sun": "direct sun", "sky": "diffuse sky", "day": "the day's PAR"}


class LightPlots(QWidget):
    """The heatmap of one light (``source``: direct sun, diffuse sky, the day's PAR) at one
    height (``height``) beside transmission vs height. ``heatmap_needed(kind, index)`` asks
    for a figure not drawn yet."""

    heatmap_needed = Signal(str, int)

    def __init__(self, parent=None):
        super().__init__(parent)
        lay = QHBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        left = QVBoxLayout()
        top = QHBoxLayout()
        top.addWidget(QLabel("heatmap of"))
        self.source = QComboBox()
        self.source.setToolTip("which light's map: the direct sun, the diffuse sky or the "
                               "day's PAR")
        self.source.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToContents)
        self.source.setAccessibleName("heatmap of")
        top.addWidget(self.source)
        top.addWidget(QLabel("at"))
        self.height_box = QComboBox()
        self.source.currentIndexChanged.connect(lambda _i: self._show_height(
            self.height_box.currentIndex()))
        self.height_box.setToolTip("height of the sample plane shown (PgUp / PgDown)")
        self.height_box.setAccessibleName("heatmap height")
        self.height_box.currentIndexChanged.connect(self._show_height)
        top.addWidget(self.height_box)
        top.addStretch(1)
        left.addLayout(top)
        self.heatmap = HeatmapView("compute light to see where it reaches each height")
        self.heatmap.window_title = "maizeviz: heatmap"
        left.addWidget(self.heatmap, 1)
        # the value under the mouse (always in place: showing a widget relayouts the dock)
        self.hover = QLabel(" ")
        self.hover.setToolTip("the value of the heatmap's bin under the mouse")
        self.heatmap.hovered.connect(lambda text: self.hover.setText(text or " "))
        left.addWidget(self.hover)
        lay.addLayout(left, 1)
        self.transmission = ImageView("transmission by height appears here")
        self.transmission.window_title = "maizeviz: transmission by height"
        lay.addWidget(self.transmission, 1)
        self._maps: dict[str, list[tuple[float, np.ndarray | None]]] = {}

    @property
    def kind(self) -> str | None:
        """The light whose map is shown."""
        return self.source.currentData()

    def clear(self) -> None:
        self._maps.clear()
        self._fill_sources(None)

    def set_heatmaps(self, maps: Sequence[tuple[float, np.ndarray | None]],
                     kind: str = "sun") -> None:
        """The maps of one light (a figure per height, None where not drawn yet); that light
        is shown. No maps: forget that light's."""
        if maps:
            self._maps[kind] = list(maps)
        else:
            self._maps.pop(kind, None)
        self._fill_sources(kind if maps else None)

    def _fill_sources(self, show: str | None) -> None:
        keep_height = self.height_box.currentIndex()
        current = show or self.kind
        self.source.blockSignals(True)
        self.source.clear()
        for kind in MODES:
            if kind in self._maps:
                self.source.addItem(MAP_NAMES[kind], kind)
        k = self.source.findData(current)
        self.source.setCurrentIndex(k if k >= 0 else 0)
        self.source.blockSignals(False)
        maps = self._maps.get(self.kind or "", [])
        self.height_box.blockSignals(True)
        self.height_box.clear()
        self.height_box.addItems([f"{h:g} cm" for h, _ in maps])
        self.height_box.blockSignals(False)
        if maps:
            self.height_box.setCurrentIndex(keep_height if 0 <= keep_height < len(maps) else 0)
        self._show_height(self.height_box.currentIndex())

    def keep_only(self, kinds) -> None:
        """Forget the maps of the lights not in ``kinds`` (a new comparison started)."""
        gone = [k for k in self._maps if k not in kinds]
        for k in gone:
            del self._maps[k]
        if gone:
            self._fill_sources(None)

    def redraw(self, keep: str | None = None, hold: bool = False) -> None:
        """The colours (or the view's size) changed: every map (but those of the light
        ``keep``) is drawn again when shown (the one shown now is asked for at once, by
        ``heatmap_needed``; with ``hold`` it stays in view until its new drawing comes)."""
        for kind, maps in self._maps.items():
            if kind != keep:
                self._maps[kind] = [(h, None) for h, _ in maps]
        self._show_height(self.height_box.currentIndex(), hold)

    def set_heatmap(self, index: int, rgba: np.ndarray, kind: str = "sun") -> None:
        """A height's figure, drawn after it was asked for."""
        maps = self._maps.get(kind)
        if maps is not None and 0 <= index < len(maps):
            maps[index] = (maps[index][0], rgba)
            if kind == self.kind and index == self.height_box.currentIndex():
                self.heatmap.set_rgba(rgba)

    def _show_height(self, index: int, hold: bool = False) -> None:
        kind = self.kind
        maps = self._maps.get(kind, []) if kind is not None else []
        if len(maps) != self.height_box.count():          # another light chosen: its heights
            self._fill_sources(kind)
            return
        if 0 <= index < len(maps):
            rgba = maps[index][1]
            if rgba is not None or not hold:
                self.heatmap.set_rgba(rgba)
            if rgba is None:
                if not hold:
                    self.heatmap.setText("drawing…")
                self.heatmap_needed.emit(kind, index)
        else:
            self.heatmap.set_rgba(None)

    @property
    def shown_height(self) -> float | None:
        i = self.height_box.currentIndex()
        maps = self._maps.get(self.kind or "", []) if self.kind is not None else []
        return maps[i][0] if 0 <= i < len(maps) else None

    def set_transmission(self, rgba: np.ndarray | None) -> None:
        self.transmission.set_rgba(rgba)
