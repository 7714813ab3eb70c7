"""Errors of the sweep: one line each, naming the key, path or address that is wrong."""

from __future__ import annotations

from maizeviz.errors import MaizevizError


class SweepSpecError(MaizevizError):
    """A sweep file that cannot be run: missing, not TOML, an unknown key, a bad value."""


class SweepStoreError(MaizevizError):
    """An output folder that cannot be used (another sweep's results, not writable)."""


class SchedulerError(MaizevizError):
    """The Dask scheduler cannot be reached or the local cluster cannot start."""


class WorkerInputError(MaizevizError):
    """A worker cannot read an input file the sweep file named: an environment problem (a
    cluster without the shared folder), recorded as "failed" so that a rerun retries it."""
