"""maizeviz core: digitized maize plants to leaf surfaces, meshes, canopies and light.

The core never imports Qt or pyvista; the desktop app lives in the ``maizeviz_app`` package.

A points file to a light table (run as a doctest by ``tests/core/test_facade.py``):

>>> import maizeviz as mv
>>> plants = mv.read_points(mv.example_points())
>>> canopy = mv.build_canopy(plants, tile=(3, 3), level="36")
>>> light = mv.LightEngine(canopy, periodic=True).sun(date="2005-08-01", time="12:00",
...                                                   lat=39.9, lon=116.4, tz="Asia/Shanghai")
>>> table = light.table()                  # a pandas DataFrame, one row per sensor height
>>> table.columns.tolist(), table["height_cm"].tolist()
(['height_cm', 'transmission'], [0.0, 50.0, 100.0, 150.0, 200.0, 225.0])
>>> bool(table["transmission"].is_monotonic_increasing)     # more sunlight higher up
True

The names below load on first use (PEP 562), so ``import maizeviz`` stays cheap: it imports
neither numpy nor Embree until a name is asked for.
"""

import importlib as _importlib
from typing import TYPE_CHECKING

__version__ = "0.3.0"

if TYPE_CHECKING:  # what a user's type checker sees (at run time the names load on first use)
    from maizeviz.api import build_canopy as build_canopy
    from maizeviz.api import example_points as example_points
    from maizeviz.api import lay_out as lay_out
    from maizeviz.api import measure_canopy as measure_canopy
    from maizeviz.api import read_points as read_points
    from maizeviz.canopy.export import export_canopy as export_canopy
    from maizeviz.canopy.from_mesh import read_mesh_canopy as read_mesh_canopy
    from maizeviz.errors import MaizevizError as MaizevizError
    from maizeviz.instruments.analyser import AnalyserPosition as AnalyserPosition
    from maizeviz.instruments.analyser import AnalyserReadings as AnalyserReadings
    from maizeviz.instruments.analyser import read_analyser as read_analyser
    from maizeviz.instruments.ceptometer import CeptometerReadings as CeptometerReadings
    from maizeviz.instruments.ceptometer import Probe as Probe
    from maizeviz.instruments.ceptometer import read_ceptometer as read_ceptometer
    from maizeviz.instruments.hemiphoto import Hemiphoto as Hemiphoto
    from maizeviz.instruments.hemiphoto import hemiphoto as hemiphoto
    from maizeviz.instruments.sight import Sight as Sight
    from maizeviz.light.engine import LightEngine as LightEngine
    from maizeviz.light.results.absorbed import AbsorbedLight as AbsorbedLight
    from maizeviz.light.results.absorbed import AbsorbedPeriod as AbsorbedPeriod
    from maizeviz.light.results.assimilation import Assimilation as Assimilation
    from maizeviz.light.results.assimilation import PeriodAssimilation as PeriodAssimilation
    from maizeviz.light.results.diffuse import PeriodLight as PeriodLight
    from maizeviz.light.results.diffuse import SkyLight as SkyLight
    from maizeviz.light.results.direct import LightResult as LightResult
    from maizeviz.light.scene.request import Sampling as Sampling
    from maizeviz.light.sources.irradiance import DEFAULT_PAR_UMOL_PER_J as DEFAULT_PAR_UMOL_PER_J
    from maizeviz.light.sources.irradiance import clear_sky_period as clear_sky_period
    from maizeviz.light.sources.irradiance import read_weather as read_weather
    from maizeviz.light.sources.irradiance import weather_period as weather_period
    from maizeviz.light.sources.sky import make_sky as make_sky
    from maizeviz.light.sources.sun import Sun as Sun
    from maizeviz.light.sources.sun import sun_at as sun_at
    from maizeviz.light.specs import DaySpec as DaySpec
    from maizeviz.light.specs import OpticsSpec as OpticsSpec
    from maizeviz.light.specs import SkySpec as SkySpec
    from maizeviz.photosynthesis.c4 import C4Leaf as C4Leaf
    from maizeviz.photosynthesis.split import leaf_model as leaf_model
    from maizeviz.photosynthesis.wofost import WofostLeaf as WofostLeaf
    from maizeviz.project.study import read_study as read_study
    from maizeviz.project.study import save_study as save_study

#: Public name -> the module defining it.
_EXPORTS = {
    # points, layout, canopy
    "example_points": "maizeviz.api",
    "read_points": "maizeviz.api",
    "lay_out": "maizeviz.api",
    "build_canopy": "maizeviz.api",
    "measure_canopy": "maizeviz.api",
    "export_canopy": "maizeviz.canopy.export",
    "read_mesh_canopy": "maizeviz.canopy.from_mesh",
    "read_study": "maizeviz.project.study",
    "save_study": "maizeviz.project.study",
    # light
    "LightEngine": "maizeviz.light.engine",
    "Sampling": "maizeviz.light.scene.request",
    "Sun": "maizeviz.light.sources.sun",
    "sun_at": "maizeviz.light.sources.sun",
    "make_sky": "maizeviz.light.sources.sky",
    "SkySpec": "maizeviz.light.specs",
    "DaySpec": "maizeviz.light.specs",
    "OpticsSpec": "maizeviz.light.specs",
    "clear_sky_period": "maizeviz.light.sources.irradiance",
    "read_weather": "maizeviz.light.sources.irradiance",
    "weather_period": "maizeviz.light.sources.irradiance",
    "DEFAULT_PAR_UMOL_PER_J": "maizeviz.light.sources.irradiance",
    # results and errors
    "LightResult": "maizeviz.light.results.direct",
    "SkyLight": "maizeviz.light.results.diffuse",
    "PeriodLight": "maizeviz.light.results.diffuse",
    "AbsorbedLight": "maizeviz.light.results.absorbed",
    "AbsorbedPeriod": "maizeviz.light.results.absorbed",
    "Assimilation": "maizeviz.light.results.assimilation",
    "PeriodAssimilation": "maizeviz.light.results.assimilation",
    # photosynthesis
    "leaf_model": "maizeviz.photosynthesis.split",
    "C4Leaf": "maizeviz.photosynthesis.c4",
    "WofostLeaf": "maizeviz.photosynthesis.wofost",
    # virtual field instruments (docs/instruments.md)
    "Sight": "maizeviz.instruments.sight",
    "Probe": "maizeviz.instruments.ceptometer",
    "read_ceptometer": "maizeviz.instruments.ceptometer",
    "CeptometerReadings": "maizeviz.instruments.ceptometer",
    "AnalyserPosition": "maizeviz.instruments.analyser",
    "read_analyser": "maizeviz.instruments.analyser",
    "AnalyserReadings": "maizeviz.instruments.analyser",
    "hemiphoto": "maizeviz.instruments.hemiphoto",
    "Hemiphoto": "maizeviz.instruments.hemiphoto",
    "MaizevizError": "maizeviz.errors",
}

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str) -> object:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'maizeviz' has no attribute '{name}'")
    value = getattr(_importlib.import_module(module), name)
    globals()[name] = value                 # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
