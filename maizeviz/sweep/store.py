"""A sweep's output folder: one part file per scenario, written atomically as results arrive.

Layout of the folder::

    sweep.json          the spec, its fingerprint, and every run (start, end, cluster, counts)
    parts/<key>.json    one finished scenario: its rows (one per height); written to a temporary
                        name in the same folder, fsynced, then renamed over, so a part is either
                        whole or absent whatever happens to the process
    results.parquet     all rows of the spec's scenarios (pyarrow), rebuilt from the parts
    results.csv         the same as CSV (empty cells for missing values)
    summary.csv         see :mod:`maizeviz.sweep.summary`

A folder holding a sweep with the same fingerprint is resumed: scenarios whose part is on disk
with status "ok" or "error" (bad input, which would fail again) are not computed again; status
"failed" (a worker died too often, an internal error) is retried. A folder of another sweep is
refused unless ``force``; parts are keyed by content, so a forced run reuses whichever of them
belong to the new spec and leaves the others on disk.
"""

from __future__ import annotations

import csv
import datetime as dt
import json
import os
from pathlib import Path
from typing import Any

import maizeviz
from maizeviz.io.atomic import atomic_open, atomic_path, write_text
from maizeviz.sweep.errors import SweepStoreError

SCHEMA = 1
#: Result columns and their types (pyarrow type names). One row per scenario and height;
#: scenario-level values (measures, seconds) repeat on each of its rows.
COLUMNS = (
    ("scenario", "string"), ("points", "string"), ("points_sha256", "string"),
    ("layout", "string"), ("tile", "string"), ("row_spacing", "float64"),
    ("plant_spacing", "float64"), ("block", "string"), ("level", "string"),
    ("preserve_area", "bool"), ("sun_zenith_deg", "float64"), ("sun_azimuth_deg", "float64"),
    ("sun_when", "string"), ("density", "float64"), ("periodic", "bool"),
    ("height_cm", "float64"), ("transmission", "float64"), ("rays", "int64"),
    ("triangles", "int64"), ("plants", "int64"), ("leaves", "int64"),
    ("leaves_skipped", "int64"), ("leaf_area_m2", "float64"), ("projected_area_m2", "float64"),
    ("ground_cover_m2", "float64"), ("ground_area_m2", "float64"), ("lai", "float64"),
    ("status", "string"), ("error", "string"), ("warnings", "string"),
    ("seconds_fit", "float64"), ("seconds_layout", "float64"), ("seconds_build", "float64"),
    ("seconds_scene", "float64"), ("seconds_measure", "float64"), ("seconds_trace", "float64"),
    # leaf optics (None for black leaves): the axis, then the energy balance, W/m2 of ground
    ("optics", "string"), ("optics_band", "string"), ("leaf_reflectance", "float64"),
    ("leaf_transmittance", "float64"), ("ground_reflectance", "float64"),
    ("scatter_depth", "int64"), ("incident_w_m2", "float64"), ("absorbed_leaves_w_m2", "float64"),
    ("absorbed_ground_w_m2", "float64"), ("reflected_top_w_m2", "float64"),
    ("balance_closure", "float64"), ("seconds_scatter", "float64"),
    ("absorbed_leaves_se_w_m2", "float64"), ("unresolved_w_m2", "float64"),
    # photosynthesis (PAR optics only): the axis, then gross assimilation per m2 of ground
    ("photosynthesis", "string"), ("canopy_gross_umol_m2_s", "float64"),
    ("canopy_gross_umol_m2_s_se", "float64"), ("canopy_gross_kg_co2_ha_h", "float64"),
    ("worker", "string"), ("maizeviz_version", "string"), ("finished_at", "string"),
)
COLUMN_NAMES = tuple(c for c, _ in COLUMNS)
STAGES = ("fit", "layout", "build", "scene", "measure", "trace", "scatter")
#: Statuses that count as done when resuming.
DONE = ("ok", "error")
OWN_FILES = {"sweep.json", "parts", "results.parquet", "results.csv", "summary.csv"}


def now_iso() -> str:
    return dt.datetime.now(dt.UTC).astimezone().isoformat(timespec="seconds")


def scenario_rows(s, result: dict, worker: str | None, finished_at: str) -> list[dict]:
    """Result rows of a scenario, one per height, every column of :data:`COLUMNS`."""
    ok = result.get("status") == "ok"
    base: dict[str, Any] = dict.fromkeys(COLUMN_NAMES)
    base.update(s.axes())
    base.update(scenario=s.key, status=result["status"], error=result.get("error"),
                worker=worker, maizeviz_version=maizeviz.__version__, finished_at=finished_at)
    if ok:
        for k in ("rays", "triangles", "plants", "leaves", "leaves_skipped", "leaf_area_m2",
                  "projected_area_m2", "ground_cover_m2", "ground_area_m2", "lai"):
            base[k] = result[k]
        for k in ("incident_w_m2", "absorbed_leaves_w_m2", "absorbed_ground_w_m2",
                  "reflected_top_w_m2", "balance_closure", "absorbed_leaves_se_w_m2",
                  "unresolved_w_m2", "canopy_gross_umol_m2_s", "canopy_gross_umol_m2_s_se",
                  "canopy_gross_kg_co2_ha_h"):
            base[k] = result.get(k)
        warnings = result.get("warnings") or []
        base["warnings"] = "; ".join(warnings[:5]) + (
            f"; and {len(warnings) - 5} more" if len(warnings) > 5 else "") if warnings else None
        for st in STAGES:
            base[f"seconds_{st}"] = float(result["seconds"].get(st, 0.0))
    rows = []
    for i, h in enumerate(s.heights_cm):
        r = dict(base, height_cm=float(h))
        if ok:
            r["transmission"] = float(result["transmission"][i])
        rows.append(r)
    return rows


def done_parts(folder, spec) -> dict[str, list[dict]]:
    """Rows of the spec's scenarios whose part file in ``folder/parts`` is whole, its own and
    done (status ok or error), by scenario key; missing, damaged or foreign parts are left out
    (computed again)."""
    parts = Path(folder) / "parts"
    out: dict[str, list[dict]] = {}
    if not parts.is_dir():
        return out
    for s in spec.scenarios:
        try:
            part = json.loads((parts / f"{s.key}.json").read_text())
        except (OSError, ValueError):
            continue                            # missing, not ours or damaged
        if not isinstance(part, dict) or part.get("scenario") != s.key:
            continue
        rows = part.get("rows")
        if isinstance(rows, list) and rows and isinstance(rows[0], dict) \
                and rows[0].get("status") in DONE:
            out[s.key] = rows
    return out


def done_keys_on_disk(folder, spec) -> set[str]:
    """Keys of the scenarios a resumed run in ``folder`` would skip: those of
    :func:`done_parts` when ``folder/sweep.json`` holds the same sweep (same fingerprint),
    else none (a run would refuse the folder without ``force``)."""
    try:
        same = json.loads((Path(folder) / "sweep.json").read_text()).get(
            "fingerprint") == spec.fingerprint
    except (OSError, ValueError, AttributeError):
        same = False
    return set(done_parts(folder, spec)) if same else set()


class ResultStore:
    """The output folder of one sweep spec.

    Parameters
    ----------
    folder : path, created if missing
    spec : SweepSpec
    resume : bool, skip scenarios already on disk (same spec)
    force : bool, use a folder holding another sweep (or unrelated files)

    Raises
    ------
    SweepStoreError
        The folder holds another sweep or unrelated files (without ``force``), or cannot be
        written.
    """

    def __init__(self, folder, spec, resume: bool = True, force: bool = False):
        self.folder = Path(folder)
        self.spec = spec
        self.parts = self.folder / "parts"
        self.rows: dict[str, list[dict]] = {}
        self.info = self._open(resume, force)

    # ------------------------------------------------------------------ opening
    def _open(self, resume: bool, force: bool) -> dict:
        f = self.folder
        if f.exists() and not f.is_dir():
            raise SweepStoreError(f"{f}: exists and is not a folder")
        meta = f / "sweep.json"
        old = None
        if meta.is_file():
            try:
                old = json.loads(meta.read_text())
            except (OSError, ValueError) as exc:
                if not force:
                    raise SweepStoreError(f"{meta}: unreadable ({exc}); use another --out or "
                                          "--force") from None
        elif f.is_dir() and not force:
            others = sorted(p.name for p in f.iterdir() if p.name not in OWN_FILES)
            if others:
                raise SweepStoreError(f"{f}: holds other files ({', '.join(others[:3])}"
                                      f"{', ...' if len(others) > 3 else ''}) and no sweep: "
                                      "choose an empty or new folder, or --force")
        if old is not None and old.get("fingerprint") != self.spec.fingerprint and not force:
            raise SweepStoreError(
                f"{f}: holds results of another sweep ({old.get('spec_file', '?')}, "
                f"{old.get('scenarios', '?')} scenarios, fingerprint "
                f"{old.get('fingerprint', '?')}; this one {self.spec.fingerprint}): use "
                "another --out, or --force to reuse the folder")
        existing = f
        while not existing.exists() and existing.parent != existing:
            existing = existing.parent                 # created only when a run starts
        if not os.access(existing, os.W_OK | os.X_OK):
            raise SweepStoreError(f"{f}: cannot be written (no permission in {existing})")
        if resume:
            self._load_parts()
        info = {"maizeviz_sweep": SCHEMA, "spec_file": self.spec.source,
                "fingerprint": self.spec.fingerprint, "scenarios": len(self.spec.scenarios),
                "excluded": self.spec.excluded, "groups": len(self.spec.groups()),
                "maizeviz_version": maizeviz.__version__, "spec": self.spec.document,
                "runs": list(old.get("runs", [])) if old and
                old.get("fingerprint") == self.spec.fingerprint else []}
        return info

    def _load_parts(self) -> None:
        self.rows.update(done_parts(self.folder, self.spec))

    # ---------------------------------------------------------------- recording
    def done_keys(self) -> set[str]:
        """Keys of the spec's scenarios already computed (status ok or error)."""
        return {k for k, rows in self.rows.items() if rows[0]["status"] in DONE}

    def add(self, s, result: dict, worker: str | None = None) -> list[dict]:
        """Record one scenario's result: its part file first (atomically), then memory."""
        rows = scenario_rows(s, result, worker, now_iso())
        part = {"scenario": s.key, "index": s.index, "rows": rows}
        write_text(self.parts / f"{s.key}.json", json.dumps(part, allow_nan=True))
        self.rows[s.key] = rows
        return rows

    def all_rows(self) -> list[dict]:
        """Rows of the spec's scenarios on record, in scenario order."""
        out: list[dict] = []
        for s in self.spec.scenarios:
            out.extend(self.rows.get(s.key, ()))
        return out

    def flush(self) -> None:
        """Rebuild results.parquet and results.csv from the rows on record (atomically)."""
        rows = self.all_rows()
        _write_csv(self.folder / "results.csv", rows)
        write_parquet(self.folder / "results.parquet", rows)

    def start_run(self, cluster: dict) -> dict:
        """Create the folder and note a run in sweep.json (written at once, so a crash still
        leaves the spec)."""
        try:
            self.parts.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise SweepStoreError(f"{self.folder}: cannot be written "
                                  f"({exc.strerror or exc})") from None
        run = {"started": now_iso(), "finished": None, "cluster": cluster,
               "already_done": len(self.done_keys()), "computed": 0, "errors": 0,
               "failed": 0, "interrupted": False}
        self.info["runs"].append(run)
        self.write_info()
        return run

    def write_info(self) -> None:
        write_text(self.folder / "sweep.json", json.dumps(self.info, indent=1, default=str))


def _write_csv(path: Path, rows: list[dict]) -> None:
    """All rows as CSV with a header (empty cells for missing values), atomically."""
    with atomic_open(path, "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(COLUMN_NAMES)
        for r in rows:
            w.writerow(["" if r.get(c) is None else r[c] for c in COLUMN_NAMES])


def write_parquet(path: Path, rows: list[dict]) -> None:
    """All rows as a Parquet table with the column types of :data:`COLUMNS`."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    schema = pa.schema([(c, getattr(pa, "bool_" if t == "bool" else t)()) for c, t in COLUMNS])
    table = pa.Table.from_pylist([{c: r.get(c) for c in COLUMN_NAMES} for r in rows],
                                 schema=schema)
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp)


def read_results(folder) -> list[dict]:
    """Rows of ``folder/results.parquet`` as dicts (for the summary and tests)."""
    import pyarrow.parquet as pq

    return pq.read_table(Path(folder) / "results.parquet").to_pylist()
