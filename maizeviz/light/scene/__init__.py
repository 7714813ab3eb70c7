"""What light is traced through: a canopy's Embree scenes (an open field, a periodic field, a
tiled block), the periodic wrap, the grids of rays over the sample rectangle and the sampling
a request asks for."""
