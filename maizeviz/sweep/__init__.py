"""Scenario sweeps: many canopies, mesh levels and suns, on Dask (a laptop or a cluster).

The data flow, one module per step::

    schema.py   the sweep file's keys, types, units, ranges and defaults, declared once
    spec.py     sweep file (TOML) -> checked scenarios, each with a content key and a group
    run.py      groups -> Dask tasks on a LocalCluster or a scheduler; results as they finish
    compute.py  on a worker: leaves (cached) -> canopy -> measures -> Embree scene -> suns
                (the only module that calls the maizeviz core)
    store.py    results folder: atomic part per scenario, results.parquet/.csv, sweep.json
    summary.py  cheapest mesh level within a transmission tolerance of the finest
    command.py  ``maizeviz sweep SPEC --out DIR``

Needs the ``sweep`` extra: ``dask[distributed]``, ``pyarrow``, ``tqdm``, ``pydantic``.
"""
