"""The window's panels, each a widget over its model: canopy (slider, Table 2), light
(settings, results, figures), layout editor and digitizer."""
