import numpy as np
import pytest
from hypothesis import settings

from maizeviz.leaf.synth import example_leaf

# Property tests draw the same examples on every run ("default": a run that passed passes
# again, on CI too); "explore" draws new ones each run to hunt for new failures:
#   .venv/bin/python -m pytest --hypothesis-profile=explore
# (a failure it finds is kept as an @example in its test, as test_measure_batch's sliver).
settings.register_profile("default", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile("default")


@pytest.fixture
def leaf_grid():
    """A realistic 13 x 5 ear-leaf grid (cm), tip collapsed."""
    return example_leaf(seed=1)


@pytest.fixture
def write_csv(tmp_path):
    """Write text to a CSV file in a temporary folder and return its path."""
    def _write(text, name="points.csv"):
        p = tmp_path / name
        p.write_text(text)
        return p
    return _write


def grid_csv(grid, plant=1, leaf=1, header=True):
    """Points-format text of one (m, n, 3) grid."""
    lines = ["plant,leaf,row,col,x,y,z"] if header else []
    for i, row in enumerate(grid):
        for j, p in enumerate(row):
            lines.append(f"{plant},{leaf},{i},{j},{p[0]:.4f},{p[1]:.4f},{p[2]:.4f}")
    return "\n".join(lines) + "\n"


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
