"""What tracing returns: a sun's, a sky's, a period's and absorbed light's results with their
tables, per-leaf and per-plant sums over plain per-triangle arrays (:mod:`.per_leaf`) and
binned maps of sensor planes (:mod:`.maps`)."""
