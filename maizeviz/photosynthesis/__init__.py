"""Leaf photosynthesis: gross CO2 assimilation of a leaf from the PAR it absorbs.

Two leaf models, both vectorised over triangles (numpy only, no light tracing here):

- :mod:`~maizeviz.photosynthesis.c4`: the C4 model of Collatz, Ribas-Carbo & Berry (1992),
  with its maize parameters and temperature responses; needs leaf temperature and
  intercellular CO2.
- :mod:`~maizeviz.photosynthesis.wofost`: WOFOST's negative exponential light response
  (Spitters et al. 1988), ``AMAX (1 - exp(-EFF I / AMAX))``, for comparison with crop models.

:mod:`~maizeviz.photosynthesis.split` applies either to a triangle whose rays say part of it
is in the sun and part in the shade: each part through the light response at its own light,
never the triangle's mean (the response is concave, so the mean overstates it).
:mod:`~maizeviz.photosynthesis.units` converts between the units crop models and leaf
physiologists use.
"""
