"""maizeviz core: digitized maize plants to leaf surfaces, meshes, canopies and light.

The core never imports Qt or pyvista; the desktop app lives in the ``app`` package.
"""

__version__ = "0.1.0"
