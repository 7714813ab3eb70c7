"""maizeviz core: digitized maize plants to leaf surfaces, meshes, canopies and light.

The core never imports Qt or pyvista; the desktop app lives in the ``maizeviz_app`` package.

A points file to a light table::

    import maizeviz as mv
    plants = mv.read_points(mv.example_points())
    canopy = mv.build_canopy(plants, tile=(3, 3), level="36")
    light = mv.LightEngine(canopy, periodic=True).sun(date="2005-08-01", time="12:00",
                                                      lat=39.9, lon=116.4, tz="Asia/Shanghai")
    light.table()

The names below load on first use (PEP 562), so ``import maizeviz`` stays cheap: it imports
neither numpy nor Embree until a name is asked for.
"""

import importlib as _importlib

__version__ = "0.1.0"

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
