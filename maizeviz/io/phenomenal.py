"""Read a plant segmented by the Phenomenal pipeline (PhenoTrack3D JSON, optionally gzipped).

Each leaf organ has a midrib polyline (from the plant base through the pseudo-stem to the tip),
its surface voxels and the pipeline's own measures, in millimetres. Turning blades into point
grids is :mod:`maizeviz.leaf.phenomenal`'s job.
"""

from __future__ import annotations

import gzip
import io
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.io.inputs import read_input

LEAF_LABELS = ("mature_leaf", "growing_leaf")


@dataclass(frozen=True)
class PhenomenalLeaf:
    """Measured traits of a leaf, as the pipeline reports them (cm and degrees)."""

    rank: int
    label: str
    length_cm: float
    width_max_cm: float
    area_cm2: float
    insertion_angle_deg: float
    insertion_height_cm: float


#: Largest Phenomenal file read, after decompression (bytes): the real plant is about 15 MB.
MAX_JSON_BYTES = 512 * 2**20


def _read_bounded(path: Path) -> bytes:
    """The file's bytes, gunzipped if compressed, never more than :data:`MAX_JSON_BYTES`."""
    data = read_input(path, "Phenomenal plant", MAX_JSON_BYTES)
    gz = data[:2] == b"\x1f\x8b"
    if gz:
        with gzip.GzipFile(fileobj=io.BytesIO(data)) as fh:
            data = fh.read(MAX_JSON_BYTES + 1)
    if len(data) > MAX_JSON_BYTES:
        raise MaizevizError(f"{path}: more than {MAX_JSON_BYTES // 2**20} MiB"
                            f"{' once decompressed' if gz else ''}; a Phenomenal plant is "
                            "about 15 MiB, so this is not one")
    return data


def load_phenomenal(path: str | Path) -> dict:
    """Read a (gzip-compressed) Phenomenal JSON file.

    Raises
    ------
    MaizevizError
        Missing, unreadable, larger than :data:`MAX_JSON_BYTES` (decompressed), not JSON, or
        without the ``voxel_organs`` list.
    """
    path = Path(path)
    try:
        data = json.loads(_read_bounded(path).decode("utf-8"))
    except MaizevizError:
        raise
    except (gzip.BadGzipFile, EOFError, UnicodeDecodeError, json.JSONDecodeError,
            RecursionError) as exc:
        raise MaizevizError(f"{path}: not a Phenomenal JSON file ({exc})") from None
    except OSError as exc:
        raise MaizevizError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    if not isinstance(data, dict) or not isinstance(data.get("voxel_organs"), list):
        raise MaizevizError(f"{path}: no 'voxel_organs' list; not a Phenomenal plant")
    return data


def leaf_traits(data: dict) -> list[PhenomenalLeaf]:
    """Measured traits of every leaf with a rank, sorted by rank."""
    out = []
    for organ in data["voxel_organs"]:
        info = organ.get("info", {}) if isinstance(organ, dict) else {}
        if organ.get("label") not in LEAF_LABELS or info.get("pm_leaf_number") is None:
            continue
        base = info.get("pm_position_base") or [np.nan] * 3
        out.append(PhenomenalLeaf(
            int(info["pm_leaf_number"]), organ["label"], info.get("pm_length", np.nan) / 10,
            info.get("pm_width_max", np.nan) / 10, info.get("pm_surface", np.nan) / 100,
            info.get("pm_insertion_angle", np.nan), base[2] / 10))
    return sorted(out, key=lambda t: t.rank)
