"""Light: the sun (direct light at one sun position), the sky (diffuse light of an overcast
sky) or a day (direct and diffuse PAR over a day at a place); Compute/Cancel, the results table
(every height, every mesh level and light traced with the same sampling), the day's summary and
the light each plant intercepted, and the figures (heatmap per height and light, transmission
vs height).

:class:`LightRuns` is the model: the last result per mesh level and light (sun, sky, day), all
sampled the same way (heights, density, periodic field), so switching levels or lights and
computing again adds a column and a curve to the comparison. Changing the sampling starts a new
comparison; changing one light's own settings (the sun's angles, the sky, the day) replaces
that light's results only.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from PySide6.QtCore import QDate, QSize, Qt, Signal
from PySide6.QtGui import QImage, QPixmap
from PySide6.QtWidgets import (
    QAbstractItemView,
    QButtonGroup,
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
    QStackedWidget,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from maizeviz.errors import MaizevizError
from maizeviz.light.sources.irradiance import (
    DEFAULT_PAR_UMOL_PER_J,
    PAR_FRACTION,
    PAR_UMOL_PER_J_PAR,
)
from maizeviz.numbers import number
from maizeviz_app.runs import MODES, SKIES, LightRuns, Run, level_order  # noqa: F401 - re-exported

DEFAULT_PLACE = "2005-08-01 12:00 39.9 116.4 Asia/Shanghai"
DEFAULT_HEIGHTS = "0, 50, 100, 150, 200, 225"
PROBLEM_STYLE = "border: 2px solid #d0342c; border-radius: 3px;"
MODE_BUTTONS = {"sun": "Sun", "sky": "Sky", "day": "Day"}
COMPUTE_TEXT = {"sun": "Compute direct light", "sky": "Compute diffuse light",
                "day": "Compute the day's light"}
#: Sky splits offered: directions (None: an equal-area split of n) -> what the combo says.
SKY_SPLITS = {16: "16 directions (turtle)", 46: "46 directions (turtle, as Caribu)",
              145: "145 directions (Tregenza)", None: "equal-area split of n directions"}
DEFAULT_DAY: dict[str, Any] = {
    "date": "2005-08-01", "lat": 39.9, "lon": 116.4, "tz": "Asia/Shanghai", "step_min": 30.0,
    "from": "", "to": "", "source": "clear", "linke": 3.0, "weather": "",
    "par_factor": DEFAULT_PAR_UMOL_PER_J}


class InputProblem(MaizevizError):
    """A light setting the user typed that cannot be used; ``quantity`` names the field. A
    MaizevizError: the user's to correct, told in one line, never an internal error."""

    def __init__(self, message: str, quantity: str):
        super().__init__(message, quantity=quantity)


def parse_heights(text: str) -> tuple[float, ...]:
    """``"0, 50, 100"`` -> (0.0, 50.0, 100.0); a word that is not a number is named."""
    out = []
    for part in text.replace(";", ",").split(","):
        part = part.strip()
        if not part:
            continue
        try:
            h = number(part.removesuffix("cm").strip())
        except ValueError:
            raise InputProblem(f"heights: '{part}' is not a number of centimetres; write them "
                               "separated by commas, e.g. 0, 50, 100", "heights") from None
        if not math.isfinite(h) or h < 0:
            raise InputProblem(f"heights must be finite numbers of 0 cm or more, got {part}",
                               "heights")
        out.append(h)
    if not out:
        raise InputProblem("give at least one height in cm, e.g. 0, 50, 100", "heights")
    return tuple(out)


def _form() -> QFormLayout:
    form = QFormLayout()
    form.setFieldGrowthPolicy(QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)
    return form


def _time_zones() -> list[str]:
    try:
        import zoneinfo

        return sorted(zoneinfo.available_timezones())
    except Exception:  # noqa: BLE001 - only the completer's list
        return ["UTC", "Asia/Shanghai", "Europe/Paris", "America/Chicago"]


class LightPanel(QWidget):
    """The light settings and the results table of the study in ``study`` (a
    :class:`~maizeviz_app.model.StudyModel`, followed: its runs fill the table).

    Signals: ``compute_requested()``, ``cancel_requested()``, ``place_requested(text)``,
    ``export_requested(what)`` with what in ``table``, ``heatmap``, ``plot``, ``canopy``,
    ``steps``, ``leaves``, ``plants``, ``day``; ``mode_changed(mode)``."""

    compute_requested = Signal()
    cancel_requested = Signal()
    place_requested = Signal(str)
    export_requested = Signal(str)
    mode_changed = Signal(str)

    def __init__(self, study=None, parent=None):
        super().__init__(parent)
        self.study = study
        lay = QVBoxLayout(self)
        # ---- which light
        modes = QHBoxLayout()
        modes.addWidget(QLabel("light"))
        self.mode_group = QButtonGroup(self)
        self.mode_buttons: dict[str, QPushButton] = {}
        tips = {"sun": "direct light at one sun position (the paper's Table 3)",
                "sky": "diffuse light from an overcast sky, traced from many directions",
                "day": "direct and diffuse PAR over a day at a place: clear sky or a weather "
                       "file"}
        for k, mode in enumerate(MODES):
            b = QPushButton(MODE_BUTTONS[mode])
            b.setCheckable(True)
            b.setToolTip(tips[mode])
            self.mode_group.addButton(b, k)
            self.mode_buttons[mode] = b
            modes.addWidget(b, 1)
        self.mode_buttons["sun"].setChecked(True)
        self.mode_group.idToggled.connect(self._on_mode_toggled)
        lay.addLayout(modes)
        self.pages = QStackedWidget()
        self.pages.addWidget(self._sun_page())
        self.pages.addWidget(self._day_page())
        self.pages.addWidget(QWidget())               # the sky needs only the sky group
        lay.addWidget(self.pages)
        self.sky_box = self._sky_group()
        lay.addWidget(self.sky_box)
        # ---- sampling, shared by every light
        form = _form()
        self.heights = QLineEdit(DEFAULT_HEIGHTS)
        self.heights.setToolTip("heights of the sensor planes, cm, separated by commas")
        form.addRow("heights (cm)", self.heights)
        self.density = QDoubleSpinBox(decimals=2, minimum=0.01, maximum=100.0, value=2.0,
                                      suffix=" rays/cm²")
        self.density.setToolTip("rays (and sensors) per cm² of the sample rectangle, for the "
                                 "sun and for each sky direction and time step")
        form.addRow("ray density", self.density)
        self.periodic = QCheckBox("infinite field (rays wrap at the plot edges)")
        self.periodic.setChecked(True)
        form.addRow(self.periodic)
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
                                       "periodic": self.periodic, "rect": self.heights,
                                       "threads": self.density}
        self.mode_fields: dict[str, dict[str, Any]] = {
            "sun": {"band": self.band, "reflectance": self.reflectance,
                    "transmittance": self.transmittance,
                    "ground_reflectance": self.ground_reflectance,
                    "sun": self.zenith, "place": self.place, "date": self.place,
                    "time": self.place, "tz": self.place},
            "sky": {"sky": self.sky_kind, "sky_directions": self.sky_n},
            "day": {"sky": self.sky_kind, "sky_directions": self.sky_n,
                    "diffuse": self.day_diffuse,
                    "date": self.day_date, "place": [self.lat, self.lon], "tz": self.tz,
                    "step": self.step, "period": [self.day_from, self.day_to],
                    "par_factor": self.par_factor, "linke_turbidity": self.linke,
                    "weather": self.weather, "altitude": self.lat, "time": self.day_from}}
        for edit in (self.heights, self.place, self.tz, self.day_from, self.day_to,
                     self.weather):
            edit.textEdited.connect(lambda _t, w=edit: self.clear_problem(w))
        for box in (self.zenith, self.azimuth, self.density, self.lat, self.lon, self.step,
                    self.par_factor, self.linke, self.sky_n):
            box.valueChanged.connect(lambda _v, w=box: self.clear_problem(w))
        self.sky_kind.currentIndexChanged.connect(lambda _i: self.clear_problem(self.sky_kind))
        self.day_date.dateChanged.connect(lambda _d: self.clear_problem(self.day_date))
        self.set_mode("sun")
        self._fit_table()
        if study is not None:
            study.runs_changed.connect(self.show_runs)

    # ------------------------------------------------------------------ pages
    def _sun_page(self) -> QWidget:
        page = QWidget()
        form = _form()
        form.setContentsMargins(0, 0, 0, 0)
        page.setLayout(form)
        self.zenith = QDoubleSpinBox(decimals=2, minimum=0.0, maximum=89.9, value=22.34,
                                     suffix=" °")
        self.zenith.setToolTip("angle of the sun from the vertical")
        self.azimuth = QDoubleSpinBox(decimals=2, minimum=0.0, maximum=360.0, value=166.95,
                                      suffix=" ° from N")
        self.azimuth.setToolTip("direction of the sun, clockwise from north")
        form.addRow("sun zenith", self.zenith)
        form.addRow("sun azimuth", self.azimuth)
        self.place = QLineEdit(DEFAULT_PLACE)
        self.place.setCursorPosition(0)                 # the date shows, not the zone's end
        self.place.setToolTip("date, local time, latitude, longitude, time zone: the sun's "
                              "angles are computed with pvlib")
        self.place_button = QPushButton("Sun from place")
        self.place_button.clicked.connect(lambda: self.place_requested.emit(self.place.text()))
        place_row = QHBoxLayout()
        place_row.addWidget(self.place, 1)
        place_row.addWidget(self.place_button)
        form.addRow("date time lat lon tz", place_row)
        form.addRow(self._optics_group())
        return page

    def _optics_group(self) -> QGroupBox:
        """Leaf optics: absorbed light with scattering (off: black leaves, interception)."""
        from maizeviz.light.trace.optics import DEFAULT_OPTICS, SHORTWAVE_SHARE

        box = QGroupBox("leaf optics: absorbed light with scattering")
        box.setCheckable(True)
        box.setChecked(False)
        box.setToolTip("off: leaves are black (light intercepted at first hits); on: leaves "
                       "reflect and transmit, light is followed through the canopy and each "
                       "leaf's absorbed light painted on the plants, with the energy balance")
        form = _form()
        box.setLayout(form)
        self.optics_box = box
        self.band = QComboBox()
        self.band.addItem("PAR (400-700 nm)", "par")
        self.band.addItem("NIR (700-3000 nm)", "nir")
        self.band.setToolTip("the waveband traced; its leaf and soil optics and irradiance "
                             "follow the band's defaults (maize: see docs/method.md)")
        form.addRow("band", self.band)

        def fraction(tip: str) -> QDoubleSpinBox:
            w = QDoubleSpinBox(decimals=3, minimum=0.0, maximum=1.0, singleStep=0.01)
            w.setToolTip(tip)
            return w

        self.reflectance = fraction("share of the light a leaf reflects (Lambertian)")
        self.transmittance = fraction("share of the light a leaf transmits (Lambertian)")
        self.ground_reflectance = fraction("share of the light the soil reflects")
        leaf = QHBoxLayout()
        leaf.addWidget(QLabel("ρ"))
        leaf.addWidget(self.reflectance, 1)
        leaf.addWidget(QLabel("τ"))
        leaf.addWidget(self.transmittance, 1)
        form.addRow("leaf", leaf)
        form.addRow("soil ρ", self.ground_reflectance)
        self.direct_w = QDoubleSpinBox(decimals=1, minimum=0.0, maximum=2000.0,
                                       suffix=" W/m²")
        self.direct_w.setToolTip("the band's direct irradiance on a horizontal plane above the "
                                 "canopy")
        self.diffuse_w = QDoubleSpinBox(decimals=1, minimum=0.0, maximum=2000.0, value=0.0,
                                        suffix=" W/m²")
        self.diffuse_w.setToolTip("the band's diffuse irradiance on a horizontal plane, from a "
                                  "standard overcast sky of 46 directions (0: direct only)")
        form.addRow("direct", self.direct_w)
        form.addRow("diffuse", self.diffuse_w)
        from maizeviz.light.trace.scatter import DEFAULT_DEPTH

        self.scatter_depth = QSpinBox(minimum=0, maximum=50, value=DEFAULT_DEPTH)
        self.scatter_depth.setToolTip("most scatterings followed per ray (0: first hits only; "
                                      "Russian roulette ends most paths long before, as on "
                                      "the command line)")
        form.addRow("scattering depth", self.scatter_depth)

        def band_defaults(_i: int = 0) -> None:
            band = str(self.band.currentData())
            d = DEFAULT_OPTICS[band]
            self.reflectance.setValue(d.reflectance)
            self.transmittance.setValue(d.transmittance)
            self.ground_reflectance.setValue(d.ground_reflectance)
            self.direct_w.setValue(round(1000.0 * SHORTWAVE_SHARE[band], 1))

        self.band.currentIndexChanged.connect(band_defaults)
        band_defaults()
        return box

    def optics_spec(self):
        """Absorbed light as chosen (:class:`maizeviz.light.specs.OpticsSpec`), None when leaf
        optics are off; leaf scattering above 1 refused naming the field."""
        from maizeviz.light.specs import OpticsSpec

        if not self.optics_box.isChecked():
            return None
        spec = OpticsSpec(str(self.band.currentData()), self.reflectance.value(),
                          self.transmittance.value(), self.ground_reflectance.value(),
                          self.direct_w.value(), self.diffuse_w.value(), self.scatter_depth.value())
        spec.optics()                                   # checked now, named by the core
        return spec

    def _sky_group(self) -> QGroupBox:
        box = QGroupBox("diffuse sky")
        form = _form()
        box.setLayout(form)
        self.sky_kind = QComboBox()
        for kind, (text, _name) in SKIES.items():
            self.sky_kind.addItem(text, kind)
        self.sky_kind.setToolTip("how the sky's brightness varies with the zenith angle θ "
                                 "(Moon and Spencer's standard overcast sky, or uniform)")
        form.addRow("sky", self.sky_kind)
        self.sky_split = QComboBox()
        for n, text in SKY_SPLITS.items():
            self.sky_split.addItem(text, n)
        self.sky_split.setCurrentIndex(list(SKY_SPLITS).index(46))
        self.sky_split.setToolTip("the directions the sky is traced from, each weighted by its "
                                  "share of the horizontal diffuse light (the weights sum to 1)")
        self.sky_n = QSpinBox(minimum=0, maximum=1000, value=46, suffix=" directions")
        self.sky_n.setToolTip("directions of an equal-area split of the sky (each cell the "
                              "same solid angle)")
        split_row = QHBoxLayout()
        split_row.addWidget(self.sky_split, 1)
        split_row.addWidget(self.sky_n)
        form.addRow("directions", split_row)
        self.sky_split.currentIndexChanged.connect(self._on_split)
        self._on_split()
        return box

    def _day_page(self) -> QWidget:
        page = QWidget()
        form = _form()
        form.setContentsMargins(0, 0, 0, 0)
        page.setLayout(form)
        self.day_date = QDateEdit(QDate(2005, 8, 1))
        self.day_date.setDisplayFormat("yyyy-MM-dd")
        self.day_date.setCalendarPopup(True)
        self.day_date.setToolTip("the local day traced")
        form.addRow("date", self.day_date)
        self.lat = QDoubleSpinBox(decimals=3, minimum=-90.0, maximum=90.0, value=39.9,
                                  suffix=" ° N")
        self.lat.setToolTip("latitude, degrees north (south negative)")
        self.lon = QDoubleSpinBox(decimals=3, minimum=-180.0, maximum=180.0, value=116.4,
                                  suffix=" ° E")
        self.lon.setToolTip("longitude, degrees east (west negative)")
        where = QHBoxLayout()
        where.addWidget(self.lat, 1)
        where.addWidget(self.lon, 1)
        form.addRow("latitude, longitude", where)
        self.tz = QLineEdit(str(DEFAULT_DAY["tz"]))
        self.tz.setToolTip("time zone of the clock times (IANA name such as Asia/Shanghai, "
                           "Europe/Paris or UTC)")
        completer = QCompleter(_time_zones(), self.tz)
        completer.setCaseSensitivity(Qt.CaseSensitivity.CaseInsensitive)
        completer.setFilterMode(Qt.MatchFlag.MatchContains)
        self.tz.setCompleter(completer)
        form.addRow("time zone", self.tz)
        self.source_clear = QRadioButton("clear sky (Ineichen-Perez, pvlib), Linke turbidity")
        self.source_clear.setToolTip("irradiance of a cloudless day, with no downloaded data; "
                                     "the Linke turbidity says how hazy the air is (1 clean, "
                                     "3 average rural, 5 and more hazy)")
        self.linke = QDoubleSpinBox(decimals=1, minimum=1.0, maximum=10.0, value=3.0,
                                    singleStep=0.5)
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
        self.weather = QLineEdit("")
        self.weather.setPlaceholderText("CSV (time, ghi [, dni, dhi, par]), EPW, TMY3, PSM")
        self.weather.setToolTip(self.source_weather.toolTip())
        self.weather_button = QPushButton("Choose…")
        self.weather_button.clicked.connect(self.choose_weather)
        weather_row = QHBoxLayout()
        weather_row.addWidget(self.source_weather)
        weather_row.addWidget(self.weather, 1)
        weather_row.addWidget(self.weather_button)
        form.addRow(weather_row)
        self.source_group = QButtonGroup(self)
        self.source_group.addButton(self.source_clear)
        self.source_group.addButton(self.source_weather)
        self.source_clear.setChecked(True)
        self.step = QDoubleSpinBox(decimals=1, minimum=0.0, maximum=1440.0, value=30.0,
                                   suffix=" min")
        self.step.setToolTip("time step: the sun is traced once per step (at its middle)")
        form.addRow("time step", self.step)
        self.day_diffuse = QComboBox()
        self.day_diffuse.addItem("the sky chosen below, all day", "sky")
        self.day_diffuse.addItem("Perez anisotropic: circumsolar with the sun", "perez")
        self.day_diffuse.setToolTip(
            "how each step's diffuse light comes from the sky: one sky shape all day, or "
            "Perez's split of each step (its circumsolar part traced with the sun, the rest "
            "from a uniform sky of the directions chosen below; pvlib)")
        form.addRow("diffuse light", self.day_diffuse)
        self.day_diffuse.currentIndexChanged.connect(lambda _i: self._sync_sky_kind())
        self.day_from = QLineEdit("")
        self.day_from.setPlaceholderText("00:00")
        self.day_to = QLineEdit("")
        self.day_to.setPlaceholderText("24:00")
        for w, what in ((self.day_from, "start"), (self.day_to, "end")):
            w.setToolTip(f"optional {what} of the period, local clock time HH:MM (empty: the "
                         "whole day)")
        span = QHBoxLayout()
        span.addWidget(QLabel("from"))
        span.addWidget(self.day_from, 1)
        span.addWidget(QLabel("to"))
        span.addWidget(self.day_to, 1)
        form.addRow("hours (optional)", span)
        self.par_factor = QDoubleSpinBox(decimals=4, minimum=0.0001, maximum=10.0,
                                         value=float(DEFAULT_DAY["par_factor"]),
                                         singleStep=0.01,
                                         suffix=" µmol/J")
        self.par_factor.setToolTip("µmol of PAR photons per joule of shortwave (default "
                                   f"{PAR_FRACTION:g} × {PAR_UMOL_PER_J_PAR:g} = "
                                   f"{DEFAULT_PAR_UMOL_PER_J:g})")
        form.addRow("PAR factor", self.par_factor)
        for b in (self.source_clear, self.source_weather):
            b.toggled.connect(lambda _c: self._on_source())
        self._on_source()
        return page

    def _on_split(self, _index: int = 0) -> None:
        n = self.sky_split.currentData()
        self.sky_n.setEnabled(n is None)
        if n is not None:
            self.sky_n.blockSignals(True)
            self.sky_n.setValue(int(n))
            self.sky_n.blockSignals(False)

    def _on_source(self) -> None:
        weather = self.source_weather.isChecked()
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
        if path:
            self.weather.setText(path)
            self.source_weather.setChecked(True)
            self.clear_problem(self.weather)

    # ------------------------------------------------------------------ mode
    @property
    def mode(self) -> str:
        return MODES[max(self.mode_group.checkedId(), 0)]

    def set_mode(self, mode: str) -> None:
        if mode not in MODES:
            mode = "sun"
        self.mode_buttons[mode].setChecked(True)
        self._show_mode(mode)

    def _on_mode_toggled(self, index: int, checked: bool) -> None:
        if checked:
            self._show_mode(MODES[index])
            self.mode_changed.emit(MODES[index])

    def _show_mode(self, mode: str) -> None:
        page = {"sun": 0, "day": 1, "sky": 2}[mode]
        for k in range(self.pages.count()):
            # only the page shown takes room: the sun page is short, the day page tall
            policy = QSizePolicy.Policy.Preferred if k == page else QSizePolicy.Policy.Ignored
            widget = self.pages.widget(k)
            if widget is not None:
                widget.setSizePolicy(QSizePolicy.Policy.Preferred, policy)
        self.pages.setCurrentIndex(page)
        self.pages.setVisible(mode != "sky")
        self.sky_box.setVisible(mode != "sun")
        self.sky_box.setTitle("diffuse sky" if mode == "sky" else
                              "diffuse part of the day: the sky it comes from")
        self.compute_button.setText(COMPUTE_TEXT[mode])
        self.pages.adjustSize()
        self._sync_sky_kind()

    def _sync_sky_kind(self) -> None:
        """With Perez's diffuse light in a day, the sky's shape is Perez's (a uniform sky for
        its isotropic part, the circumsolar part with the sun): the shape choice is off."""
        perez = self.mode == "day" and self.day_diffuse.currentData() == "perez"
        self.sky_kind.setEnabled(not perez)
        self.sky_kind.setToolTip(
            "Perez's diffuse light: its isotropic part comes from a uniform sky of the "
            "directions chosen, its circumsolar part with the sun" if perez else
            "how the sky's brightness varies with the zenith angle θ")

    # ------------------------------------------------------------------ settings
    def settings(self) -> dict:
        """The settings as typed (for a project file)."""
        return {"mode": self.mode,
                "zenith_deg": self.zenith.value(), "azimuth_deg": self.azimuth.value(),
                "place": self.place.text(), "heights": self.heights.text(),
                "density": self.density.value(), "periodic": self.periodic.isChecked(),
                "sky_kind": self.sky_kind.currentData(),
                "sky_split": "equal" if self.sky_split.currentData() is None else "auto",
                "sky_directions": self.sky_n.value(),
                "day_date": self.day_date.date().toString("yyyy-MM-dd"),
                "latitude": self.lat.value(), "longitude": self.lon.value(),
                "tz": self.tz.text(), "step_min": self.step.value(),
                "from": self.day_from.text(), "to": self.day_to.text(),
                "source": "weather" if self.source_weather.isChecked() else "clear",
                "linke_turbidity": self.linke.value(), "weather": self.weather.text(),
                "par_factor": self.par_factor.value(),
                "day_diffuse": self.day_diffuse.currentData(),
                "optics": self.optics_box.isChecked(), "band": self.band.currentData(),
                "reflectance": self.reflectance.value(),
                "transmittance": self.transmittance.value(),
                "ground_reflectance": self.ground_reflectance.value(),
                "direct_w_m2": self.direct_w.value(), "diffuse_w_m2": self.diffuse_w.value(),
                "depth": self.scatter_depth.value()}

    def apply_settings(self, s: dict) -> None:
        if s.get("band") in ("par", "nir"):
            self.band.setCurrentIndex(self.band.findData(s["band"]))
        for key, w in (("reflectance", self.reflectance),
                       ("transmittance", self.transmittance),
                       ("ground_reflectance", self.ground_reflectance),
                       ("direct_w_m2", self.direct_w), ("diffuse_w_m2", self.diffuse_w)):
            if key in s:
                w.setValue(float(s[key]))
        if "depth" in s:
            self.scatter_depth.setValue(int(s["depth"]))
        self.optics_box.setChecked(bool(s.get("optics", False)))
        if s.get("day_diffuse") in ("sky", "perez"):
            self.day_diffuse.setCurrentIndex(self.day_diffuse.findData(s["day_diffuse"]))
        self.zenith.setValue(float(s.get("zenith_deg", self.zenith.value())))
        self.azimuth.setValue(float(s.get("azimuth_deg", self.azimuth.value())))
        self.place.setText(str(s.get("place", self.place.text())))
        self.place.setCursorPosition(0)
        self.heights.setText(str(s.get("heights", self.heights.text())))
        self.density.setValue(float(s.get("density", self.density.value())))
        self.periodic.setChecked(bool(s.get("periodic", self.periodic.isChecked())))
        kind = s.get("sky_kind")
        if kind in SKIES:
            self.sky_kind.setCurrentIndex(list(SKIES).index(kind))
        n = int(s.get("sky_directions", self.sky_n.value()))
        split = None if s.get("sky_split") == "equal" or n not in SKY_SPLITS else n
        self.sky_split.setCurrentIndex(list(SKY_SPLITS).index(split))
        self.sky_n.setValue(n)
        if "day_date" in s:
            date = QDate.fromString(str(s["day_date"]), "yyyy-MM-dd")
            if date.isValid():
                self.day_date.setDate(date)
        self.lat.setValue(float(s.get("latitude", self.lat.value())))
        self.lon.setValue(float(s.get("longitude", self.lon.value())))
        self.tz.setText(str(s.get("tz", self.tz.text())))
        self.step.setValue(float(s.get("step_min", self.step.value())))
        self.day_from.setText(str(s.get("from", self.day_from.text())))
        self.day_to.setText(str(s.get("to", self.day_to.text())))
        self.linke.setValue(float(s.get("linke_turbidity", self.linke.value())))
        self.weather.setText(str(s.get("weather", self.weather.text())))
        self.par_factor.setValue(float(s.get("par_factor", self.par_factor.value())))
        (self.source_weather if s.get("source") == "weather" else self.source_clear) \
            .setChecked(True)
        self.set_mode(str(s.get("mode", "sun")))

    def request(self):
        """The sun's light request the fields describe (hit classes on: the canopy is
        coloured).

        Raises
        ------
        InputProblem, MaizevizError
            Naming the field (``quantity``).
        """
        from maizeviz.light.scene.request import LightRequest
        from maizeviz.light.sources.sun import Sun

        sampling = self.sampling()
        sun = Sun(self.zenith.value(), self.azimuth.value())
        return LightRequest(sun, sampling, classes=True)

    def sampling(self):
        """Heights, density and field of a sky or a day (a ``Sampling``; 2 tracing threads)."""
        from maizeviz.light.scene.request import Sampling

        return Sampling(parse_heights(self.heights.text()), self.density.value(), None,
                        self.periodic.isChecked(), 2)

    def sky_spec(self):
        """The sky chosen (:class:`maizeviz_app.jobs.SkySpec`)."""
        from maizeviz_app.jobs import SkySpec

        equal = self.sky_split.currentData() is None
        return SkySpec(str(self.sky_kind.currentData()), int(self.sky_n.value()),
                       "equal" if equal else "auto")

    def day_spec(self):
        """The day chosen (:class:`maizeviz_app.jobs.DaySpec`); an empty weather file field is
        refused here, the rest (clock times included) by the core when the period is made."""
        from maizeviz_app.jobs import DaySpec

        weather = None
        if self.source_weather.isChecked():
            weather = self.weather.text().strip()
            if not weather:
                raise InputProblem("choose a weather file (CSV with a time column and ghi in "
                                   "W/m²), or use the clear sky", "weather")
        return DaySpec(self.day_date.date().toString("yyyy-MM-dd"), self.lat.value(),
                       self.lon.value(), self.tz.text().strip(), self.step.value(),
                       self.day_from.text().strip() or None, self.day_to.text().strip() or None,
                       self.linke.value(), self.par_factor.value(), weather,
                       str(self.day_diffuse.currentData()))

    def sampling_key(self, heights) -> tuple:
        """What every result of a comparison shares."""
        return (tuple(float(h) for h in heights), self.density.value(),
                self.periodic.isChecked())

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
        if w is None or self.problem.isVisible():
            self.show_problem("")

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
        diffuse = day or runs.of_kind("sky") is not None
        for what in ("steps", "day"):
            self.export_buttons[what].setEnabled(day)
        for what in ("leaves", "plants"):
            self.export_buttons[what].setEnabled(diffuse)
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
                      "sunlit m² leaf"]
            keys = ("absorbed_w", "absorbed_w_m2_leaf", "sunlit_area_cm2")
            fmt = "{:.2f}"
            self.plants_title.setText(f"{band} each plant absorbs, with scattering "
                                      f"({run.label})")
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
        t.setHorizontalHeaderLabels(header)
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
        if t.horizontalScrollBar().isVisible() or t.columnCount() > 4:
            h += t.horizontalScrollBar().sizeHint().height()
        t.setFixedHeight(max(h, head + 30))


class ImageView(QLabel):
    """A picture scaled to fit the widget, keeping its aspect (figures drawn elsewhere)."""

    def __init__(self, placeholder: str = "", parent=None):
        super().__init__(placeholder, parent)
        self._placeholder = placeholder
        self._image: QImage | None = None
        self.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.setMinimumSize(160, 120)
        self.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Ignored)
        self.setStyleSheet("background: white; color: #666;")

    def set_rgba(self, rgba: np.ndarray | None) -> None:
        if rgba is None:
            self._image = None
            self.clear()
            self.setText(self._placeholder)         # what will appear here
            return
        h, w = rgba.shape[:2]
        self._image = QImage(np.ascontiguousarray(rgba).data, w, h, 4 * w,
                             QImage.Format.Format_RGBA8888).copy()
        self._rescale()

    def image(self) -> QImage | None:
        return self._image

    def resizeEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        self._rescale()

    def _rescale(self) -> None:
        if self._image is None:
            return
        self.setPixmap(QPixmap.fromImage(self._image).scaled(
            self.size(), Qt.AspectRatioMode.KeepAspectRatio,
            Qt.TransformationMode.SmoothTransformation))

    def sizeHint(self) -> QSize:  # noqa: N802
        return QSize(360, 200)


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
        top.addWidget(self.source)
        top.addWidget(QLabel("at"))
        self.height_box = QComboBox()
        self.source.currentIndexChanged.connect(lambda _i: self._show_height(
            self.height_box.currentIndex()))
        self.height_box.setToolTip("height of the sample plane shown (PgUp / PgDown)")
        self.height_box.currentIndexChanged.connect(self._show_height)
        top.addWidget(self.height_box)
        top.addStretch(1)
        left.addLayout(top)
        from maizeviz_app.panels.heatmap_view import HeatmapView

        self.heatmap = HeatmapView("compute light to see where it reaches each height")
        left.addWidget(self.heatmap, 1)
        # the value under the mouse (always in place: showing a widget relayouts the dock)
        self.hover = QLabel(" ")
        self.hover.setToolTip("the value of the heatmap's bin under the mouse")
        self.heatmap.hovered.connect(lambda text: self.hover.setText(text or " "))
        left.addWidget(self.hover)
        lay.addLayout(left, 1)
        self.transmission = ImageView("transmission by height appears here")
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

    def redraw(self, keep: str | None = None) -> None:
        """The colours changed: every map (but those of the light ``keep``) is drawn again
        when shown (the one shown now is asked for at once, by ``heatmap_needed``)."""
        for kind, maps in self._maps.items():
            if kind != keep:
                self._maps[kind] = [(h, None) for h, _ in maps]
        self._show_height(self.height_box.currentIndex())

    def set_heatmap(self, index: int, rgba: np.ndarray, kind: str = "sun") -> None:
        """A height's figure, drawn after it was asked for."""
        maps = self._maps.get(kind)
        if maps is not None and 0 <= index < len(maps):
            maps[index] = (maps[index][0], rgba)
            if kind == self.kind and index == self.height_box.currentIndex():
                self.heatmap.set_rgba(rgba)

    def _show_height(self, index: int) -> None:
        kind = self.kind
        maps = self._maps.get(kind, []) if kind is not None else []
        if len(maps) != self.height_box.count():          # another light chosen: its heights
            self._fill_sources(kind)
            return
        if 0 <= index < len(maps):
            rgba = maps[index][1]
            self.heatmap.set_rgba(rgba)
            if rgba is None:
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
