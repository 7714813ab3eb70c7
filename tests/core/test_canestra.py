"""maizeviz.io.canestra: Caribu's files written and read back, and each malformed line
refused in one line naming it."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.errors import MaizevizError
from maizeviz.io.canestra import (
    CanestraFileError,
    decode_label,
    encode_label,
    read_can,
    read_light,
    read_opt,
    read_pattern,
    write_can,
    write_light,
    write_opt,
    write_pattern,
)

coords = st.floats(-1e4, 1e4, allow_nan=False).map(lambda v: round(v, 6))


@settings(max_examples=30, deadline=None)
@given(st.dictionaries(st.integers(1, 10 ** 6).map(str),
                       st.lists(st.lists(st.tuples(coords, coords, coords), min_size=3,
                                         max_size=3), min_size=1, max_size=4),
                       min_size=1, max_size=5))
def test_a_scene_written_reads_back_label_by_label(tmp_path_factory, scene):
    path = tmp_path_factory.mktemp("can") / "s.can"
    write_can(path, scene)
    back = read_can(path)
    assert list(back) == list(scene)
    for label, tris in scene.items():
        np.testing.assert_allclose(back[label], np.array(tris), atol=1e-6)


def test_a_polygon_is_cut_into_a_fan_and_comments_are_skipped(tmp_path):
    path = tmp_path / "q.can"
    path.write_text("# a quad\np 1 100001001001 4 0 0 0 1 0 0 1 1 0 0 1 0\n\n"
                    "p 2 100001001002 7 3 0 0 0 1 0 0 0 1 0\n")
    scene = read_can(path)
    assert scene["100001001001"].shape == (2, 3, 3)
    np.testing.assert_array_equal(scene["100001001001"][1], [[0, 0, 0], [1, 1, 0], [0, 1, 0]])
    assert scene["100001001002"].shape == (1, 3, 3)


@pytest.mark.parametrize("text, words", [
    ("q 1 1 3 0 0 0 1 0 0 0 1 0\n", "line 1: a primitive starts with 'p'"),
    ("p 1 1 3 0 0 0 1 0 0 0 1\n", "3 vertices need 9 coordinates, the line has 8"),
    ("p 1 1 3 0 0 0 1 0 0 0 1 x\n", "coordinate 'x' is not a number"),
    ("p 1 1 3 0 0 0 1 0 0 0 1 nan\n", "coordinate is nan"),
    ("p 1 1 3 0 0 0 1 0 0 0 1 1_0\n", "is not a number"),
    ("p 1 1 2 0 0 0 1 0 0\n", "a polygon of 2 vertices"),
    ("p 0 3 0 0 0 1 0 0 0 1 0\n", "needs its label"),
    ("p x\n", "not 'p <attributes>"),
    ("# nothing\n", "no primitive"),
    ("", "empty"),
])
def test_a_malformed_can_file_is_refused_naming_the_line(tmp_path, text, words):
    path = tmp_path / "bad.can"
    path.write_text(text)
    with pytest.raises(CanestraFileError) as err:
        read_can(path)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_binary_and_missing_files_are_refused(tmp_path):
    (tmp_path / "b.can").write_bytes(b"p 1 1 3 \x00\xff\xfe")
    with pytest.raises(CanestraFileError):
        read_can(tmp_path / "b.can")
    with pytest.raises(MaizevizError):
        read_can(tmp_path / "missing.can")


def test_lights_patterns_and_optics_round_trip(tmp_path):
    lights = [(0.5, (0.0, 0.0, -1.0)), (0.25, (0.5, -0.1, -0.8))]
    assert read_light(write_light(tmp_path / "s.light", lights)) == lights
    assert read_pattern(write_pattern(tmp_path / "p.8", (2, -1, -3, 4))) == (-3, -1, 2, 4)
    soil, species = read_opt(write_opt(tmp_path / "par.opt", 0.2,
                                       {1: (0.06, 0.07), 2: (0.13,), 3: (0.1, 0.05, 0.2, 0.0)}))
    assert soil == 0.2
    assert species == {1: (-1.0, 0.06, 0.07, 0.06, 0.07), 2: (0.13, -1.0, -1.0, -1.0, -1.0),
                       3: (-1.0, 0.1, 0.05, 0.2, 0.0)}


@pytest.mark.parametrize("name, text, reader, words", [
    ("l.light", "1 0 0\n", read_light, "line 1: a source is 'energy vx vy vz'"),
    ("l.light", "1 0 0 0\n", read_light, "has no way"),
    ("l.light", "\n", read_light, "no light source"),
    ("p.8", "0 0\n", read_pattern, "the file has 1"),
    ("p.8", "0 0\n0 5\n", read_pattern, "enclose no area"),
    ("o.opt", "n 2\ns d 0.1\ne d -1 d 0.1 0.1 d 0.1 0.1\n", read_opt, "declares 2 species"),
    ("o.opt", "n 1\ne d -1 d 0.1 0.1 d 0.1 0.1\n", read_opt, "no soil line"),
    ("o.opt", "n 1\ns d 0.1\ne d -1 d 0.1\n", read_opt, "line 3"),
])
def test_malformed_light_pattern_and_optics_files_are_refused(tmp_path, name, text, reader,
                                                              words):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(CanestraFileError) as err:
        reader(path)
    assert words in str(err.value)


def test_labels_encode_and_decode_as_caribus_barcodes():
    assert encode_label(1, True, 1, 1) == "100001001001"
    assert encode_label(12, False, 345, 7) == "1200345000007"
    assert decode_label("1200345000007") == (12, False, 345, 7)
    for bad in ("abc", "1234", "1000010010０1"):
        with pytest.raises(MaizevizError):
            decode_label(bad)
    with pytest.raises(MaizevizError, match="plant id is 0..99999"):
        encode_label(plant=100_000)


def test_a_label_with_white_space_cannot_be_written(tmp_path):
    with pytest.raises(CanestraFileError, match="white space"):
        write_can(tmp_path / "s.can", {"a leaf": [[(0, 0, 0), (1, 0, 0), (0, 1, 0)]]})
