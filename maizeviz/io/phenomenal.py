"""Read a plant segmented by the Phenomenal pipeline (PhenoTrack3D JSON, optionally gzipped).

Each leaf organ has a midrib polyline (from the plant base through the pseudo-stem to the tip),
its surface voxels and the pipeline's own measures, in millimetres. Turning blades into point
grids is :mod:`maizeviz.leaf.phenomenal`'s job.
"""

from __future__ import annotations

import gzip
import io
import json
import math
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


#: Coordinates and lengths beyond this many millimetres (1 km) are refused: no plant is that
#: large, and larger numbers overflow the geometry of a blade.
MAX_MM = 1e6
#: Leaf ranks above this are refused.
MAX_RANK = 1000
#: The measures :func:`leaf_traits` reads from a leaf's ``info``, each a number or null.
TRAIT_KEYS = ("pm_length", "pm_width_max", "pm_surface", "pm_insertion_angle")


@dataclass(frozen=True)
class LeafOrgan:
    """A leaf organ of a Phenomenal plant, its structure checked.

    Attributes
    ----------
    where : its place in the file, for messages ("voxel_organs[4]")
    label : "mature_leaf" or "growing_leaf"
    rank : leaf number from the base, or None when the pipeline gave none
    polylines : one (k, 3) float64 mm midrib polyline per voxel segment (k may be 0)
    voxels : (v, 3) float64 mm, the surface voxels of every segment
    insertion : (3,) float64 mm, the leaf's insertion (``pm_position_base``), or None
    traits : {key of :data:`TRAIT_KEYS`: float mm, mm2 or deg, NaN when not given}
    """

    where: str
    label: str
    rank: int | None
    polylines: tuple[np.ndarray, ...]
    voxels: np.ndarray
    insertion: np.ndarray | None
    traits: dict


class _Checker:
    """Type checks of a parsed Phenomenal file naming the place: ``p.json:
    voxel_organs[4].voxel_segments[0].polyline: ...``."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, where: str, what: str) -> MaizevizError:
        return MaizevizError(f"{self.source}: {where}: {what}; not a Phenomenal plant")

    def number(self, value, where: str, high: float = MAX_MM) -> float:
        if value is None:
            return float("nan")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(where, f"must be a number, got {type(value).__name__}")
        if not (isinstance(value, int) and abs(value) <= high or
                isinstance(value, float) and math.isfinite(value) and abs(value) <= high):
            raise self.fail(where, f"must be a finite number of at most {high:g} in size")
        return float(value)

    def points(self, value, where: str) -> np.ndarray:
        """(n, 3) float64 mm from a list of [x, y, z]; null or missing -> (0, 3)."""
        if value is None or (isinstance(value, list) and not value):
            return np.empty((0, 3))
        if not isinstance(value, list):
            raise self.fail(where, f"must be a list of [x, y, z], got {type(value).__name__}")
        try:
            arr = np.asarray(value)
        except (ValueError, TypeError, OverflowError):        # ragged rows
            arr = None
        if arr is None or arr.ndim != 2 or arr.shape[1] != 3 or arr.dtype.kind not in "iuf":
            raise self.fail(where, "must be a list of [x, y, z] numbers")
        arr = arr.astype(np.float64)
        if not np.all(np.isfinite(arr)) or np.abs(arr).max() > MAX_MM:
            raise self.fail(where, f"coordinates must be finite numbers of at most {MAX_MM:g} "
                                   "mm in size")
        return arr

    def mapping(self, value, where: str) -> dict:
        if value is None:
            return {}
        if not isinstance(value, dict):
            raise self.fail(where, f"must be an object, got {type(value).__name__}")
        return value

    def organ(self, organ, where: str) -> LeafOrgan | None:
        """The leaf organ checked, or None for an organ that is not a leaf."""
        organ = self.mapping(organ, where)
        label = organ.get("label")
        if label is not None and not isinstance(label, str):
            raise self.fail(f"{where}.label", f"must be text, got {type(label).__name__}")
        if label not in LEAF_LABELS:
            return None
        info = self.mapping(organ.get("info"), f"{where}.info")
        rank = info.get("pm_leaf_number")
        if rank is not None:
            r = self.number(rank, f"{where}.info.pm_leaf_number", MAX_RANK)
            if r < 0 or not r.is_integer():
                raise self.fail(f"{where}.info.pm_leaf_number",
                                f"must be a whole number from 0 to {MAX_RANK}, got {rank}")
            rank = int(r)
        base = info.get("pm_position_base")
        insertion = None
        if base is not None:
            insertion = self.points([base], f"{where}.info.pm_position_base")[0] \
                if isinstance(base, list) and len(base) == 3 else None
            if insertion is None:
                raise self.fail(f"{where}.info.pm_position_base", "must be [x, y, z]")
        traits = {k: self.number(info.get(k), f"{where}.info.{k}") for k in TRAIT_KEYS}
        segs = organ.get("voxel_segments")
        if segs is not None and not isinstance(segs, list):
            raise self.fail(f"{where}.voxel_segments",
                            f"must be a list, got {type(segs).__name__}")
        polylines, voxels = [], []
        for k, seg in enumerate(segs or []):
            at = f"{where}.voxel_segments[{k}]"
            seg = self.mapping(seg, at)
            polylines.append(self.points(seg.get("polyline"), f"{at}.polyline"))
            voxels.append(self.points(seg.get("voxels_position"), f"{at}.voxels_position"))
        return LeafOrgan(where, label, rank, tuple(polylines),
                         np.concatenate(voxels) if voxels else np.empty((0, 3)), insertion,
                         traits)


def leaf_organs(data, source: str = "Phenomenal plant") -> list[LeafOrgan]:
    """The leaf organs of a parsed Phenomenal file, in file order, their structure checked.

    Raises
    ------
    MaizevizError
        One line naming the place: not an object at the top, no ``voxel_organs`` list, an
        organ, a segment or a point of the wrong type or shape, a number not finite or
        larger than :data:`MAX_MM`.
    """
    check = _Checker(str(source))
    if not isinstance(data, dict) or not isinstance(data.get("voxel_organs"), list):
        raise MaizevizError(f"{source}: no 'voxel_organs' list; not a Phenomenal plant")
    found = (check.organ(o, f"voxel_organs[{i}]") for i, o in enumerate(data["voxel_organs"]))
    return [o for o in found if o is not None]


def load_phenomenal(path: str | Path) -> dict:
    """Read a (gzip-compressed) Phenomenal JSON file; its leaf organs are checked
    (:func:`leaf_organs`).

    Raises
    ------
    MaizevizError
        Missing, unreadable, larger than :data:`MAX_JSON_BYTES` (decompressed), not JSON
        (nested too deeply, a number of thousands of digits), or of the wrong structure.
    """
    path = Path(path)
    try:
        data = json.loads(_read_bounded(path).decode("utf-8"))
    except MaizevizError:
        raise
    except (gzip.BadGzipFile, EOFError, UnicodeDecodeError, ValueError, RecursionError) as exc:
        # ValueError: json's decode errors, and integers beyond Python's 4,300 digits
        reason = "nested too deeply" if isinstance(exc, RecursionError) else exc
        raise MaizevizError(f"{path}: not a Phenomenal JSON file ({reason})") from None
    except OSError as exc:
        raise MaizevizError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    leaf_organs(data, str(path))
    return data


def leaf_traits(data: dict) -> list[PhenomenalLeaf]:
    """Measured traits of every leaf with a rank, sorted by rank."""
    out = []
    for organ in leaf_organs(data):
        if organ.rank is None:
            continue
        t = organ.traits
        base_z = organ.insertion[2] if organ.insertion is not None else np.nan
        out.append(PhenomenalLeaf(organ.rank, organ.label, t["pm_length"] / 10,
                                  t["pm_width_max"] / 10, t["pm_surface"] / 100,
                                  t["pm_insertion_angle"], base_z / 10))
    return sorted(out, key=lambda t: t.rank)
