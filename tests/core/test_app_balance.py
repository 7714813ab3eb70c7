"""The app's energy balance adds up (a new user's report): a sun traced with leaf optics and a
diffuse sky shows, in the results table, rows that sum to the incident light within the
closure the light panel states; the stalks' row is there when they were traced (their light
was missing from rows that claimed to close within 0.1 %), and the numbers are those of
``maizeviz light ... --json`` on the same canopy, rays and optics. Driven through the app's
model, without Qt."""

from __future__ import annotations

import json

import pytest

from maizeviz.io.points import write_points
from maizeviz.leaf.synth import block_grids

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")

SUN = (40.0, 150.0)


@pytest.fixture(scope="module")
def points(tmp_path_factory):
    path = tmp_path_factory.mktemp("balance") / "two_plants.csv"
    write_points(path, block_grids(1, 2, seed=3))
    return path


@pytest.fixture
def study():
    from maizeviz_app.model import StudyModel
    from maizeviz_app.runner import InlineRunner

    runner = InlineRunner()
    yield StudyModel(tile=1, runner=runner)
    runner.shutdown()


def _sun_with_optics(m, stalks: bool = True):
    s = m.settings
    s.canopy.level = "36"
    s.sampling.heights, s.sampling.density, s.sampling.periodic = "0, 100, 200", 0.5, True
    s.sun.zenith_deg, s.sun.azimuth_deg = SUN
    s.light.stalks = stalks
    s.optics.enabled = True
    s.optics.diffuse_w_m2 = 60.0
    s.photosynthesis.model, s.photosynthesis.temperature_c = "c4", 30.0
    assert m.compute_light()
    return m.runs.last


def _balance_rows(m) -> dict[str, float]:
    _header, rows = m.runs.table()
    return {r[0]: float(r[1]) for r in rows if r[0].endswith("W/m²")}


def test_the_balance_rows_shown_add_up_to_the_incident(study, points, capsys):
    m = study
    m.open_points(points)
    run = _sun_with_optics(m)
    b = run.balance
    assert run.stalks and b.absorbed_stalks > 0
    rows = _balance_rows(m)
    assert rows["absorbed by stalks W/m²"] == round(b.absorbed_stalks, 1)
    incident = rows.pop("PAR incident W/m²")
    assert incident == pytest.approx(540.0)                 # 480 direct + 60 diffuse
    # each shown number is rounded to 0.1: the rows miss the incident by at most the
    # closure stated in the panel plus half a tenth per row
    stated = abs(b.closure) * b.incident
    assert abs(sum(rows.values()) - incident) <= stated + 0.05 * (len(rows) + 1) + 1e-9
    # without the stalks' row the rows would miss it by their light, far more than stated
    assert b.absorbed_stalks > stated + 0.05 * (len(rows) + 1)
    info = m.runs_info
    assert f"the stalks {b.absorbed_stalks / b.incident:.1%}" in info
    assert f"balance closes within {abs(b.closure):.2%}" in info
    # the command line's balance on the same canopy and rays: the same numbers
    from maizeviz.cli import main

    code = main(["light", str(points), "--tile", "1x1", "--triangles", "36", "--periodic",
                 "--sun-zenith", f"{SUN[0]:g}", "--sun-azimuth", f"{SUN[1]:g}",
                 "--density", "0.5", "--heights", "0,100,200", "--diffuse", "60",
                 "--photosynthesis", "c4", "--temperature", "30", "--json"])
    out = capsys.readouterr()
    assert code == 0, out.err
    cli = json.loads(out.out)
    cb = cli["balance"] if "balance" in cli else cli["absorbed"]["balance"]
    for field in ("incident", "absorbed_leaves", "absorbed_stalks", "absorbed_ground",
                  "reflected_top", "escaped_sides", "unresolved"):
        assert getattr(b, field) == pytest.approx(cb[field], rel=1e-9, abs=1e-9), field


def test_leaves_only_has_no_stalks_row_and_still_adds_up(study, points):
    m = study
    m.open_points(points)
    b = _sun_with_optics(m, stalks=False).balance
    rows = _balance_rows(m)
    assert "absorbed by stalks W/m²" not in rows and b.absorbed_stalks == 0.0
    incident = rows.pop("PAR incident W/m²")
    stated = abs(b.closure) * b.incident
    assert abs(sum(rows.values()) - incident) <= stated + 0.05 * (len(rows) + 1) + 1e-9
