"""Light through a canopy, in layers that only import downward (an import-linter contract in
pyproject.toml)::

    engine, specs   one canopy's Embree scenes kept, every request dispatched; run settings
    report          tables, figures and files of results (what ``maizeviz light`` writes)
    trace           rays through a scene: one direction (direct), many (diffuse: skies and
                    periods), hit classes, leaf optics, scattering and absorbed light
    results         what tracing returns (sun, sky, period, absorbed), per-leaf and per-plant
                    sums over plain arrays, binned maps
    scene           what is traced through: Embree scenes of a canopy (open, periodic, tiled
                    blocks), the periodic wrap, ray grids, sampling requests
    sources         where light comes from: clock and dates, the sun's position, skies,
                    Perez's diffuse split, irradiance over periods

Users reach it through :class:`maizeviz.LightEngine` (:mod:`maizeviz.light.engine`).
"""
