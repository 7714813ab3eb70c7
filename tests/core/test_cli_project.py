"""A ``.maizeviz`` project in place of a points file: the command line reads its points and
the stands it opens with (the oracle: the same stands given as a layout file)."""

import json
from dataclasses import replace

import pytest

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for, layout_to_dict
from maizeviz.cli import EXIT_FAIL, EXIT_OK, main
from maizeviz.leaf.fit import read_leaves
from maizeviz.mesh.levels import parse_level
from maizeviz.project.study import read_study, save_study
from maizeviz.resources import example_points

SUN = ["--sun-zenith", "30", "--sun-azimuth", "140", "--density", "0.5", "--rect=10,10,170,170",
       "--json"]


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def edited(tmp_path_factory):
    """The bundled block tiled 2 x 2 with three stands removed and one turned, as a project
    and as a layout file."""
    folder = tmp_path_factory.mktemp("cli_project")
    leaves = read_leaves(example_points()).leaves
    layout = layout_for(leaves, (2, 2))
    stands = list(layout.placements[:-3])
    stands[4] = replace(stands[4], azimuth_deg=75.0)
    layout = replace(layout, placements=tuple(stands))
    project = save_study(folder / "edited.maizeviz", example_points(), layout, level="16")
    layout_file = folder / "edited.json"
    layout_file.write_text(json.dumps(layout_to_dict(layout)))
    return project, layout_file, leaves, layout


def test_canopy_of_a_project_is_the_canopy_of_its_stands(capsys, edited):
    project, _, leaves, layout = edited
    code, out, err = run(capsys, "canopy", project, "--levels", "16", "--json")
    assert code == EXIT_OK, err
    row = json.loads(out)["levels"][0]
    assert row["plants"] == 33 == len(layout.placements)
    assert row["triangles"] == build_canopy(leaves, layout, parse_level("16")).n_triangles
    assert "33 plants as the project lays them out" in err


def test_light_on_a_project_equals_light_on_its_points_and_layout(capsys, edited):
    project, layout_file, *_ = edited
    code, out, err = run(capsys, "light", project, "--levels", "16", *SUN)
    assert code == EXIT_OK, err
    code2, out2, err2 = run(capsys, "light", example_points(), "--layout", layout_file,
                            "--levels", "16", *SUN)
    assert code2 == EXIT_OK, err2
    got, want = json.loads(out), json.loads(out2)
    for doc in (got, want):
        doc.pop("seconds")
    assert got == want                 # same rays, same hits, same numbers
    assert got["transmission"][0] < 1 and got["triangles"] > 0


def test_a_layout_file_replaces_the_projects_stands(capsys, edited, tmp_path):
    project, *_ = edited
    code, out, err = run(capsys, "canopy", project, "--tile", "3x3", "--levels", "16",
                         "--json")
    assert code == EXIT_OK, err
    assert json.loads(out)["levels"][0]["plants"] == 81


@pytest.mark.parametrize("content", [b"", b"PK\x03\x04 not a zip", b"plant,leaf\n1,2\n"])
def test_a_damaged_project_is_one_line(capsys, tmp_path, content):
    bad = tmp_path / "bad.maizeviz"
    bad.write_bytes(content)
    code, out, err = run(capsys, "canopy", bad, "--levels", "16")
    assert code == EXIT_FAIL and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and str(bad) in lines[0]


def test_read_study_gives_the_saved_stands_level_and_results(edited, tmp_path):
    project, _, _, layout = edited
    study = read_study(project, tmp_path)
    assert study.level == "16 triangles" and study.results == [] and study.notes == []
    assert [(p.plant, p.x, p.y, p.azimuth_deg) for p in study.layout.placements] == \
        [(p.plant, p.x, p.y, p.azimuth_deg) for p in layout.placements]
