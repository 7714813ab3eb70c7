"""Virtual field instruments on a canopy: what a line ceptometer (AccuPAR LP-80 style), a
plant canopy analyser (LAI-2200 style) and a hemispherical camera would read in it.

Each looks through the light engine's Embree scenes (:mod:`maizeviz.instruments.sight`):
:mod:`~maizeviz.instruments.ceptometer`, :mod:`~maizeviz.instruments.analyser`,
:mod:`~maizeviz.instruments.hemiphoto`. See docs/instruments.md.
"""
