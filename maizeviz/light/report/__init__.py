"""Tables, figures and files made from light results: per-leaf and per-step tables, maps of
the sensor planes, a period's plots, and the Beer-Lambert estimate they are compared with."""
