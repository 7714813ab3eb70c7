"""Scenario sweeps on a real Dask LocalCluster of two worker processes (no mocks)."""

from __future__ import annotations

import json
import logging
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

distributed = pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

from maizeviz.cli import main as cli_main  # noqa: E402
from maizeviz.sweep.command import main as sweep_main  # noqa: E402
from maizeviz.sweep.errors import SchedulerError, SweepSpecError, SweepStoreError  # noqa: E402
from maizeviz.sweep.run import dask_client, plan_tasks, run_sweep  # noqa: E402
from maizeviz.sweep.spec import load_spec  # noqa: E402
from maizeviz.sweep.store import ResultStore, done_keys_on_disk, read_results  # noqa: E402
from maizeviz.sweep.summary import summarize  # noqa: E402

HEIGHTS = [0, 50, 100, 150, 200, 250]
SUNS = [(30, 180), (45, 90), (60, 225)]
SPEC = """
[canopy]
points = ["b*.csv"]
tile = ["1x1"]
level = ["standard", "8"]
[light]
sun = [{zenith = 30, azimuth = 180}, {zenith = 45, azimuth = 90}, {zenith = 60, azimuth = 225}]
density = [0.5]
heights = [0, 50, 100, 150, 200, 250]
periodic = true
"""


@pytest.fixture(scope="module")
def blocks(tmp_path_factory):
    """Two synthetic blocks of 1 x 2 plants (different seeds) in one folder."""
    d = tmp_path_factory.mktemp("blocks")
    for seed in (0, 1):
        assert cli_main(["synth", "--plants", "1x2", "--seed", str(seed),
                         "--out", str(d / f"b{seed}.csv")]) == 0
    return d


@pytest.fixture(scope="module")
def client():
    """A LocalCluster of 2 worker processes, one thread each, shared by this module."""
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=logging.CRITICAL)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def spec_file(folder: Path, text: str = SPEC, name: str = "sweep.toml") -> Path:
    p = folder / name
    p.write_text(text)
    return p


def keys_on_disk(out: Path) -> list[str]:
    return sorted(p.stem for p in (out / "parts").glob("*.json"))


def check_complete(out: Path, spec) -> list[dict]:
    """Every scenario exactly once on disk and in the tables, one row per height."""
    rows = read_results(out)
    assert len(rows) == len(spec.scenarios) * len(HEIGHTS)
    assert len({(r["scenario"], r["height_cm"]) for r in rows}) == len(rows)
    assert sorted({r["scenario"] for r in rows}) == sorted(s.key for s in spec.scenarios)
    assert keys_on_disk(out) == sorted(s.key for s in spec.scenarios)
    csv_lines = (out / "results.csv").read_text().splitlines()
    assert len(csv_lines) == len(rows) + 1
    return rows


# ------------------------------------------------------------------------ the numbers
def test_sweep_rows_equal_the_single_run_cli(blocks, client, tmp_path, capsys):
    spec = load_spec(spec_file(blocks))
    assert len(spec.scenarios) == 12 and len(spec.groups()) == 4
    out = tmp_path / "r"
    outcome = run_sweep(spec, out, client=client, progress=False)
    assert outcome.complete and outcome.computed == 12 and outcome.errors == 0
    rows = check_complete(out, spec)
    assert all(r["status"] == "ok" and r["worker"].startswith("tcp://") for r in rows)
    info = json.loads((out / "sweep.json").read_text())
    assert info["fingerprint"] == spec.fingerprint and info["runs"][0]["finished"]
    assert info["runs"][0]["cluster"]["workers"] == 2
    capsys.readouterr()

    by = {(r["points"], r["level"], r["sun_zenith_deg"], r["height_cm"]): r for r in rows}
    for name in ("b0.csv", "b1.csv"):
        path = str(blocks / name)
        assert cli_main(["canopy", path, "--levels", "standard,8", "--json"]) == 0
        canopy = json.loads(capsys.readouterr().out)["levels"]
        for rec in (r for r in canopy if r["preserve_area"]):
            r = by[(name, rec["level"], 30.0, 0.0)]
            for k in ("triangles", "plants", "leaves", "leaf_area_m2", "projected_area_m2",
                      "ground_cover_m2", "ground_area_m2", "lai"):
                assert r[k] == rec[k], k
        for zen, az in SUNS:
            assert cli_main(["light", path, "--levels", "standard,8", "--sun-zenith", str(zen),
                             "--sun-azimuth", str(az), "--density", "0.5", "--periodic",
                             "--heights", ",".join(map(str, HEIGHTS)), "--json"]) == 0
            for rec in json.loads(capsys.readouterr().out)["levels"]:
                for h, t in zip(rec["heights_cm"], rec["transmission"]):
                    r = by[(name, rec["level"], float(zen), h)]
                    assert r["transmission"] == t and r["triangles"] == rec["triangles"]
                    assert r["rays"] == rec["rays"] and r["sun_azimuth_deg"] == az

    summary = summarize(rows, 0.02)
    assert len(summary) == 2 * 4                       # 2 canopies x (3 suns + all suns)
    assert all(s["finest_level"] == "standard" for s in summary)


def test_a_scenario_with_bad_input_is_recorded_and_the_sweep_goes_on(blocks, client, tmp_path):
    (tmp_path / "b0.csv").write_bytes((blocks / "b0.csv").read_bytes())
    (tmp_path / "bad.csv").write_text("plant,leaf,row,col,x,y,z\n1,1,0,0,a,b,c\n")
    spec = load_spec(spec_file(tmp_path, SPEC.replace('"b*.csv"', '"b0.csv", "bad.csv"')))
    outcome = run_sweep(spec, tmp_path / "r", client=client, progress=False)
    assert outcome.complete and outcome.errors == 6 and outcome.failed == 0
    rows = check_complete(tmp_path / "r", spec)
    bad = [r for r in rows if r["points"] == "bad.csv"]
    assert {r["status"] for r in bad} == {"error"}
    assert all("bad.csv" in r["error"] and "\n" not in r["error"] for r in bad)
    assert all(r["transmission"] is None for r in bad)
    assert {r["status"] for r in rows if r["points"] == "b0.csv"} == {"ok"}


def test_a_file_the_workers_cannot_read_fails_and_is_retried_by_the_rerun(blocks, client,
                                                                          tmp_path):
    (tmp_path / "b0.csv").write_bytes((blocks / "b0.csv").read_bytes())
    # content no worker has fitted yet (workers cache leaves by content, not by path)
    assert cli_main(["synth", "--plants", "1x2", "--seed", "7", "--out",
                     str(tmp_path / "b1.csv")]) == 0
    spec = load_spec(spec_file(tmp_path))
    hidden = tmp_path / "b1.csv.away"
    (tmp_path / "b1.csv").rename(hidden)               # gone after the spec was read
    first = run_sweep(spec, tmp_path / "r", client=client, progress=False)
    assert first.failed == 6 and first.computed == 6 and not first.complete
    rows = read_results(tmp_path / "r")
    failed = [r for r in rows if r["status"] == "failed"]
    assert len(failed) == 6 * len(HEIGHTS)
    assert "cannot be read here" in failed[0]["error"] and "same path" in failed[0]["error"]
    hidden.rename(tmp_path / "b1.csv")
    second = run_sweep(spec, tmp_path / "r", client=client, progress=False)
    assert second.already_done == 6 and second.computed == 6 and second.complete
    assert {r["status"] for r in check_complete(tmp_path / "r", spec)} == {"ok"}


# ------------------------------------------------------------------------------ faults
def test_a_killed_worker_costs_only_its_task(blocks, client, tmp_path):
    spec = load_spec(spec_file(blocks, SPEC.replace("density = [0.5]", "density = [6]")))
    killed = []

    def kill_one(outcome):
        if killed:
            return
        busy = [w for w, keys in client.processing().items()
                if any(str(k).startswith("maizeviz-sweep") for k in keys)]
        assert busy, "no sweep task in flight to lose"
        pid = client.run(os.getpid, workers=[busy[0]])[busy[0]]
        os.kill(pid, signal.SIGKILL)
        killed.append(pid)

    outcome = run_sweep(spec, tmp_path / "r", client=client, progress=False, on_result=kill_one)
    assert killed and outcome.complete and outcome.failed == 0 and outcome.errors == 0
    rows = check_complete(tmp_path / "r", spec)
    assert {r["status"] for r in rows} == {"ok"}
    client.wait_for_workers(2, timeout=60)


def test_rerun_after_an_interruption_computes_only_the_missing(blocks, client, tmp_path):
    spec = load_spec(spec_file(blocks))
    out = tmp_path / "r"

    def ctrl_c(outcome):
        raise KeyboardInterrupt

    first = run_sweep(spec, out, client=client, progress=False, on_result=ctrl_c)
    assert first.interrupted and 0 < first.computed < 12
    kept = {k: (out / "parts" / f"{k}.json").stat().st_mtime_ns for k in keys_on_disk(out)}
    assert len(kept) == first.computed
    assert len(read_results(out)) == first.computed * len(HEIGHTS)   # tables rebuilt on stop
    assert json.loads((out / "sweep.json").read_text())["runs"][0]["interrupted"]

    second = run_sweep(spec, out, client=client, progress=False)
    assert second.complete and second.already_done == first.computed
    assert second.computed == 12 - first.computed
    assert {k: (out / "parts" / f"{k}.json").stat().st_mtime_ns for k in kept} == kept
    check_complete(out, spec)
    third = run_sweep(spec, out, client=client, progress=False)       # nothing left to do
    assert third.computed == 0 and third.already_done == 12


def test_ctrl_c_on_the_command_stops_cleanly_and_the_rerun_finishes(blocks, client, tmp_path,
                                                                    capsys):
    # slow enough that Ctrl-C lands mid-sweep (tracing got 10x faster: 12 scenarios at
    # density 2 finished in 2.5 s, before the signal; then the planes of a periodic block came
    # from the ground rays and density 16 could finish too)
    spec = spec_file(blocks, SPEC.replace("density = [0.5]", "density = [64]").replace(
        'tile = ["1x1"]', 'tile = ["3x3"]'), "slow.toml")
    out = tmp_path / "r"
    cmd = [sys.executable, "-m", "maizeviz.sweep", str(spec), "--out", str(out),
           "--workers", "1"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline and not list((out / "parts").glob("*.json")):
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGINT)                 # what a terminal's Ctrl-C does
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "interrupted" in err and "Traceback" not in err
    done = len(keys_on_disk(out))
    assert 1 <= done < 12 and f"interrupted: {done} of 12 scenarios are in" in err
    assert len(read_results(out)) == done * len(HEIGHTS)

    address = client.scheduler.address                # the rerun on a running scheduler
    assert sweep_main([str(spec), "--out", str(out), "--scheduler", address,
                       "--no-progress"]) == 0
    cap = capsys.readouterr()
    assert f"{12 - done} computed now" in cap.err and f"{done} already there" in cap.err
    assert "cheapest level" in cap.out and (out / "summary.csv").exists()
    check_complete(out, load_spec(spec))


# --------------------------------------------------------------------------- bad input
def test_optics_axis_rows_equal_the_single_run_cli(blocks, client, tmp_path, capsys):
    """Leaf optics as an axis: black leaves keep today's keys and numbers; each optics row
    carries the energy balance of ``maizeviz light --reflectance ... --json``."""
    base = load_spec(spec_file(blocks))
    text = SPEC.replace('level = ["standard", "8"]', 'level = ["8"]').replace(
        "periodic = true", 'periodic = true\noptics = ["black", {band = "par"}, '
        '{band = "nir", reflectance = 0.4, transmittance = 0.4, ground_reflectance = 0.2, '
        'depth = 2}, {band = "par", seed = 3}]').replace('points = ["b*.csv"]',
                                                        'points = ["b0.csv"]')
    spec = load_spec(spec_file(blocks, text, "optics.toml"))
    assert len(spec.scenarios) == 3 * 4
    black = {s.key for s in spec.scenarios if s.optics is None}
    assert black <= {s.key for s in base.scenarios}          # the same keys as without optics
    out = tmp_path / "r"
    outcome = run_sweep(spec, out, client=client, progress=False)
    assert outcome.complete and outcome.errors == 0
    rows = [r for r in read_results(out) if r["height_cm"] == 0.0]
    capsys.readouterr()
    for r in rows:
        if r["optics_band"] is None:
            assert r["absorbed_leaves_w_m2"] is None and r["incident_w_m2"] is None
            continue
        args = ["light", str(blocks / "b0.csv"), "--triangles", "8", "--sun-zenith",
                str(r["sun_zenith_deg"]), "--sun-azimuth", str(r["sun_azimuth_deg"]),
                "--density", "0.5", "--periodic", "--heights", ",".join(map(str, HEIGHTS)),
                "--json",
                "--band", r["optics_band"], "--reflectance", str(r["leaf_reflectance"]),
                "--transmittance", str(r["leaf_transmittance"]), "--ground-reflectance",
                str(r["ground_reflectance"]), "--depth", str(r["scatter_depth"]),
                "--seed", "3" if r["optics"].endswith("seed 3") else "0"]
        assert cli_main(args) == 0
        balance = json.loads(capsys.readouterr().out)["balance"]       # one level: flat
        assert r["incident_w_m2"] == pytest.approx(balance["incident"], rel=1e-12)
        assert r["absorbed_leaves_w_m2"] == pytest.approx(balance["absorbed_leaves"], rel=1e-9)
        assert r["reflected_top_w_m2"] == pytest.approx(balance["reflected_top"], rel=1e-9)
        assert abs(r["balance_closure"]) < 0.02
    summary = summarize(read_results(out), 0.02)
    assert {s["optics"] for s in summary} == {"black", "par rho 0.1 tau 0.05 soil 0.1",
                                              "nir rho 0.4 tau 0.4 soil 0.2 depth 2",
                                              "par rho 0.1 tau 0.05 soil 0.1 seed 3"}


def test_photosynthesis_axis_rows_equal_the_cli_and_the_summary_names_the_carbon_level(
        blocks, client, tmp_path, capsys):
    """Photosynthesis as an axis of PAR scenarios (black and NIR ones take only "none"): each
    row carries ``maizeviz light --photosynthesis ... --json``'s canopy assimilation, and the
    summary names the cheapest level within 1 % of the finest level's assimilation."""
    text = SPEC.replace('points = ["b*.csv"]', 'points = ["b0.csv"]').replace(
        "periodic = true", 'periodic = true\noptics = ["black", {band = "par"}, '
        '{band = "nir"}]\nphotosynthesis = ["none", {model = "c4", temperature = 30}, '
        '{model = "wofost", amax = 60}]').replace(
        "sun = [{zenith = 30, azimuth = 180}, {zenith = 45, azimuth = 90}, "
        "{zenith = 60, azimuth = 225}]", "sun = [{zenith = 30, azimuth = 180}]")
    spec = load_spec(spec_file(blocks, text, "carbon.toml"))
    # 2 levels x (black none, par x 3, nir none)
    assert len(spec.scenarios) == 2 * 5
    out = tmp_path / "r"
    outcome = run_sweep(spec, out, client=client, progress=False)
    assert outcome.complete and outcome.errors == 0
    rows = [r for r in read_results(out) if r["height_cm"] == 0.0]
    capsys.readouterr()
    carbon = [r for r in rows if r["photosynthesis"] != "none"]
    assert {r["photosynthesis"] for r in carbon} == {"c4 30 C", "wofost 25 C amax 60"}
    assert all(r["optics_band"] == "par" for r in carbon)
    for r in carbon:
        model = r["photosynthesis"].split()[0]
        args = ["light", str(blocks / "b0.csv"), "--triangles", r["level"].split()[0]
                if r["level"] != "standard" else "72", "--sun-zenith", "30", "--sun-azimuth",
                "180", "--density", "0.5", "--periodic", "--heights",
                ",".join(map(str, HEIGHTS)), "--json", "--photosynthesis", model,
                "--temperature", "30" if model == "c4" else "25"]
        if r["level"] == "standard":
            args[2:4] = ["--levels", "standard"]
        if model == "wofost":
            args += ["--amax", "60"]
        assert cli_main(args) == 0
        ph = json.loads(capsys.readouterr().out)["photosynthesis"]
        assert r["canopy_gross_umol_m2_s"] == pytest.approx(ph["canopy_gross_umol_m2_s"],
                                                            rel=1e-9)
        assert r["canopy_gross_umol_m2_s_se"] > 0 and r["absorbed_leaves_se_w_m2"] > 0
    summary = [s for s in summarize(read_results(out), 0.02) if s["photosynthesis"] != "none"]
    assert len(summary) == 2
    for s in summary:
        assert s["assimilation_cheapest_level"] in ("standard", "8 triangles")
        assert s["assimilation_max_rel_difference"] <= 0.01
        assert s["assimilation_tolerance"] == 0.01


def test_the_carbon_example_asks_the_mesh_question_for_carbon():
    from maizeviz.resources import example_points

    spec = load_spec(Path(example_points()).parent / "sweep-carbon.toml")
    assert len(spec.scenarios) == 8
    assert {s.level for s in spec.scenarios} == {"K=4", "standard", "36 triangles",
                                                  "8 triangles"}
    assert all(s.optics is not None and s.optics.band == "par" and s.photosynthesis
               for s in spec.scenarios)
    assert {dict(s.photosynthesis)["model"] for s in spec.scenarios} == {"c4", "wofost"}


@pytest.mark.parametrize("text, says", [
    ("[canopy\npoints = 1", r"not valid TOML.*line 1"),
    (SPEC.replace("tile =", "tiles ="), r"unknown key 'canopy.tiles' \(known in canopy: points, "),
    (SPEC + 'optics = [{band = "par"}]\nphotosynthesis = [{model = "c3"}]',
     r"light.photosynthesis\[0\]: unknown photosynthesis model 'c3'"),
    (SPEC + 'photosynthesis = [{model = "c4", temperature = 99}]',
     r"light.photosynthesis\[0\].temperature: must be from -50 to 70 C, got 99"),
    (SPEC + 'photosynthesis = [{model = "wofost", vmax = 3}]',
     r"light.photosynthesis\[0\]: the wofost model has no parameter vmax"),
    (SPEC + "[sky]\n", r"unknown key 'sky' \(known: canopy, light, exclude\)"),
    (SPEC.replace('level = ["standard", "8"]', "level = []"), r"canopy.level: is empty"),
    (SPEC.replace("density = [0.5]", 'density = ["a"]'), r"light.density\[0\]: must be a number"),
    (SPEC.replace("periodic = true", "periodic = 1"), r"light.periodic: must be true or false"),
    (SPEC.replace('"8"]', '"8x"]'), r"canopy.level\[1\]: '8x' is not a mesh level"),
    (SPEC.replace('"8"]', '"standard"]'), r"canopy.level\[1\]: repeats canopy.level\[0\]"),
    (SPEC.replace('"b*.csv"', '"c*.csv"'), r"canopy.points\[0\]: 'c\*.csv' matches no file"),
    (SPEC.replace('"b*.csv"', '"missing.csv"'), r"canopy.points\[0\]: missing.csv: no such file"),
    (SPEC.replace('tile = ["1x1"]', 'tile = ["3by3"]'), r"canopy.tile\[0\]: must look like 3x3"),
    (SPEC.replace("zenith = 30,", "zenit = 30,"), r"unknown key 'light.sun\[0\].zenit'"),
    (SPEC.replace("zenith = 30,", "zenith = 95,"),
     r"light.sun\[0\].zenith: must be from 0 to 90 degrees, got 95"),
    (SPEC.replace("zenith = 30,", "zenith = 90,"), r"light.sun\[0\]: .*below the horizon"),
    (SPEC.replace("heights = [0, 50, 100, 150, 200, 250]", "heights = 7"),
     r"light.heights: must be a list"),
    ('exclude = [{level = "K9"}]\n' + SPEC, r"exclude\[0\]: matches no scenario"),
    (SPEC + '[[exclude]]\ncolour = "red"\n', r"unknown key 'exclude\[0\].colour'"),
    (SPEC + 'exclude = [{level = "8"}]\n', r"'light.exclude': exclude belongs at the top"),
    (SPEC.replace("[canopy]", "[canopee]"), r"unknown key 'canopee' \(known: canopy, "),
    # the canopy's own checks, at load rather than on every worker
    (SPEC.replace('tile = ["1x1"]', 'tile = ["1x1"]\nrow_spacing = [60, 0.5]'),
     r"canopy.row_spacing\[1\]: row spacing is 0.5 cm; it must be from 1 to 100000 cm"),
    (SPEC.replace('tile = ["1x1"]', 'tile = ["1x1"]\nplant_spacing = 2e6'),
     r"canopy.plant_spacing: plant spacing is 2e\+06 cm; it must be from 1 to 100000 cm"),
    (SPEC.replace('tile = ["1x1"]', 'tile = ["1000x1000"]'),
     r"canopy.tile\[0\]: 1000 x 1000 tiles of one plant make 1,000,000 plants; a canopy holds "
     r"at most 100,000"),
    (SPEC.replace('tile = ["1x1"]', 'tile = ["1x1"]\nblock = "1x200000"'),
     r"canopy.block: the block shape must be a whole number from 1 to 100,000"),
    (SPEC.replace('tile = ["1x1"]', 'tile = ["1x1"]\nrow_spacing = [1' + "0" * 400 + "]"),
     r"canopy.row_spacing\[0\]: must be a number, got an integer too large"),
    (SPEC.replace("density = [0.5]", "density = 1" + "0" * 400),
     r"light.density: must be a number, got an integer too large"),
    (SPEC + "[[exclude]]\nsun = {zenith = 1" + "0" * 400 + "}\n",
     r"exclude\[0\].sun.zenith: must be a number, got an integer too large"),
    (SPEC + "[[exclude]]\nrow_spacing = 0.5\n",
     r"exclude\[0\].row_spacing: row spacing is 0.5 cm; it must be from 1"),
    # leaf optics
    (SPEC.replace("periodic = true", 'periodic = true\noptics = ["white"]'),
     r"light.optics\[0\]: must be \"black\" or a table"),
    (SPEC.replace("periodic = true", 'periodic = true\noptics = [{band = "uv"}]'),
     r"light.optics\[0\]: unknown band 'uv'"),
    (SPEC.replace("periodic = true",
                  "periodic = true\noptics = [{reflectance = 0.7, transmittance = 0.6}]"),
     r"light.optics\[0\]: .*1"),
    (SPEC.replace("periodic = true", "periodic = true\noptics = [{depth = 1000}]"),
     r"light.optics\[0\].depth: must be a whole number from 0 to 50"),
    (SPEC.replace("periodic = true", "periodic = true\noptics = [{colour = 1}]"),
     r"unknown key 'light.optics\[0\].colour'"),
    (SPEC.replace("periodic = true", "periodic = true\noptics = [{direct_w_m2 = 1e308}]"),
     r"light.optics\[0\].direct_w_m2: must be from 0 to 5000 W/m2"),
])
def test_bad_sweep_files_say_one_line_naming_the_key(blocks, tmp_path, text, says):
    (tmp_path / "b0.csv").write_bytes((blocks / "b0.csv").read_bytes())
    with pytest.raises(SweepSpecError, match=says) as info:
        load_spec(spec_file(tmp_path, text))
    assert "\n" not in str(info.value) and str(info.value).startswith(str(tmp_path))


def test_missing_sweep_file(tmp_path):
    with pytest.raises(SweepSpecError, match=r"nope.toml: no such sweep file"):
        load_spec(tmp_path / "nope.toml")


def test_a_fifo_as_the_sweep_file_is_refused_at_once_in_one_line(tmp_path):
    fifo = tmp_path / "sweep.toml"
    os.mkfifo(fifo)                                  # nobody writes: reading it would wait
    # in a subprocess first, so that a regression fails on the timeout instead of hanging
    proc = subprocess.run([sys.executable, "-m", "maizeviz.sweep", str(fifo), "--dry-run"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 1, proc.stderr
    assert proc.stderr.strip().splitlines() == [f"error: {fifo}: is a FIFO (named pipe), not a "
                                                "regular file; a sweep file must be a regular "
                                                "file"]
    with pytest.raises(SweepSpecError, match=r"sweep.toml: is a FIFO \(named pipe\), not a "
                                             r"regular file; a sweep file must be a regular"):
        load_spec(fifo)


def test_too_many_scenarios_need_yes(blocks, tmp_path):
    many = SPEC.replace("density = [0.5]", f"density = {list(range(1, 18))}").replace(
        'tile = ["1x1"]', f'tile = ["1x1"]\nrow_spacing = {list(range(40, 90))}')
    path = spec_file(blocks, many, "many.toml")
    with pytest.raises(SweepSpecError, match=r"10,200 scenarios is more than 10,000: confirm "
                                             r"with --yes"):
        load_spec(path)
    small = spec_file(blocks, 'exclude = [{level = "8", sun = {zenith = 60}}]\n' + SPEC,
                      "small.toml")                     # 10 scenarios after the exclusion
    with pytest.raises(SweepSpecError, match=r"10 scenarios is more than 9: confirm"):
        load_spec(small, max_scenarios=9)
    assert len(load_spec(small, yes=True, max_scenarios=9).scenarios) == 10


def test_keys_follow_content_not_names_and_exclude_drops(blocks, tmp_path):
    (tmp_path / "renamed.csv").write_bytes((blocks / "b0.csv").read_bytes())
    one = load_spec(spec_file(blocks, SPEC.replace('"b*.csv"', '"b0.csv"'), "one.toml"))
    two = load_spec(spec_file(tmp_path, SPEC.replace('"b*.csv"', '"renamed.csv"')))
    assert [s.key for s in one.scenarios] == [s.key for s in two.scenarios]
    assert one.fingerprint == two.fingerprint
    moved = load_spec(spec_file(blocks, SPEC.replace('"b*.csv"', '"b1.csv"'), "other.toml"))
    assert not {s.key for s in one.scenarios} & {s.key for s in moved.scenarios}
    ex = load_spec(spec_file(blocks, 'exclude = [{level = "8", sun = {zenith = 60}},\n'
                                     '           {points = "b1*"}]\n' + SPEC, "ex.toml"))
    assert ex.excluded == 7 and len(ex.scenarios) == 5
    assert all(s.points.name == "b0.csv" for s in ex.scenarios)


def test_unreachable_scheduler_fails_within_seconds(tmp_path):
    with socket.socket() as s:                      # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    t0 = time.monotonic()
    with pytest.raises(SchedulerError, match=rf"cannot reach the Dask scheduler at "
                                             rf"tcp://127.0.0.1:{port} within 2 s"):
        with dask_client(scheduler=f"tcp://127.0.0.1:{port}", connect_timeout=2):
            pass
    assert time.monotonic() - t0 < 6


def test_an_output_folder_of_another_sweep_is_refused_unless_forced(blocks, tmp_path):
    a = load_spec(spec_file(blocks))
    b = load_spec(spec_file(blocks, SPEC.replace("density = [0.5]", "density = [1]"), "b.toml"))
    out = tmp_path / "r"
    ResultStore(out, a).start_run({})
    ResultStore(out, a)                              # the same sweep: resumed
    with pytest.raises(SweepStoreError, match=r"holds results of another sweep .* --force"):
        ResultStore(out, b)
    ResultStore(out, b, force=True).start_run({})
    other = tmp_path / "other"
    other.mkdir()
    (other / "thesis.tex").write_text("x")
    with pytest.raises(SweepStoreError, match=r"holds other files \(thesis.tex\)"):
        ResultStore(other, a)


def test_the_dry_run_and_the_store_agree_on_what_is_done(blocks, tmp_path, capsys):
    spec = spec_file(blocks)
    a = load_spec(spec)
    out = tmp_path / "r"
    store = ResultStore(out, a)
    store.start_run({})
    first, second, third = a.scenarios[:3]
    store.add(first, {"status": "error", "error": "bad input"})      # done: not retried
    store.add(third, {"status": "failed", "error": "worker died"})   # retried
    # a part under another scenario's name (a copy, a renamed file) is not that scenario's
    (out / "parts" / f"{second.key}.json").write_bytes(
        (out / "parts" / f"{first.key}.json").read_bytes())
    assert done_keys_on_disk(out, a) == {first.key} == ResultStore(out, a).done_keys()
    assert sweep_main([str(spec), "--dry-run", "--out", str(out)]) == 0
    listing = capsys.readouterr().out
    assert f"12 scenarios (0 excluded, 1 already in {out})" in listing
    assert [ln.split()[1] for ln in listing.splitlines() if ln.rstrip().endswith(" done")] \
        == [first.key[:12]]
    b = load_spec(spec_file(blocks, SPEC.replace("density = [0.5]", "density = [1]"), "b.toml"))
    assert done_keys_on_disk(out, b) == set()       # another sweep's folder: nothing skipped


def test_tasks_are_groups_split_only_when_workers_would_idle(blocks):
    spec = load_spec(spec_file(blocks))
    assert [len(c) for c in plan_tasks(spec.scenarios, 2)] == [3, 3, 3, 3]
    chunks = plan_tasks(spec.scenarios, 8)
    assert sorted(len(c) for c in chunks) == [1] * 12
    assert all(len({s.group_key for s in c}) == 1 for c in chunks)
    assert chunks[0][0].level == "standard"         # finer levels first


def test_summary_picks_the_cheapest_level_within_tolerance():
    def rows(level, tri, ts, sun=30.0):
        return [{"status": "ok", "points": "p.csv", "layout": None, "tile": "1x1",
                 "row_spacing": 60.0, "plant_spacing": 30.0, "preserve_area": True,
                 "density": 1.0, "periodic": True, "sun_zenith_deg": sun,
                 "sun_azimuth_deg": 180.0, "sun_when": None, "level": level,
                 "triangles": tri, "height_cm": float(h), "transmission": t}
                for h, t in zip((0, 100), ts)]
    data = (rows("K=4", 1000, [0.10, 0.50]) + rows("standard", 100, [0.11, 0.52])
            + rows("8 triangles", 10, [0.14, 0.50]) + rows("K=4", 1000, [0.2, 0.6], 60.0)
            + rows("standard", 100, [0.2, 0.63], 60.0) + rows("8 triangles", 10, [0.2, 0.6], 60.0))
    s = summarize(data, 0.02)
    assert [(r["sun"], r["cheapest_level"]) for r in s] == [
        ("z 30.00 az 180.00", "standard"), ("z 60.00 az 180.00", "8 triangles"),
        ("all 2 suns", "K=4")]
    assert s[0]["max_abs_difference"] == pytest.approx(0.02)


def test_a_c4_temperature_response_is_an_axis_value_named_in_the_rows(blocks):
    """``temperature_response`` is the one named (not numeric) parameter a scenario's leaf
    model takes; the rows' label names it when it is not the default."""
    from maizeviz.errors import MaizevizError
    from maizeviz.sweep.spec import photosynthesis_label

    text = SPEC.replace('points = ["b*.csv"]', 'points = ["b0.csv"]').replace(
        "periodic = true", 'periodic = true\noptics = [{band = "par"}]\nphotosynthesis = '
        '[{model = "c4", temperature = 38}, {model = "c4", temperature = 38, '
        'temperature_response = "clm45"}]')
    spec = load_spec(spec_file(blocks, text, "forms.toml"))
    labels = {photosynthesis_label(s.photosynthesis) for s in spec.scenarios}
    assert labels == {"c4 38 C", "c4 38 C temperature_response clm45"}
    bad = text.replace('"clm45"', '"q10"')
    with pytest.raises(MaizevizError, match="temperature_response"):
        load_spec(spec_file(blocks, bad, "bad.toml"))
