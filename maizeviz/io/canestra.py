"""Canestra's text files, as Caribu (OpenAlea's light model) reads and writes them: a scene of
labelled polygons (``.can``), light sources (``.light``), the pattern of an infinite canopy
(``.8``) and optical species (``.opt``).

Formats (Chelle & Andrieu's Canestra documentation, as ``alinea.caribu.file_adaptor`` reads
them):

- ``.can``: one primitive a line, ``p <n_attr> <attr ...> <n_vertices> x y z x y z ...``; the
  first attribute is the primitive's label, a Canestra barcode (see :func:`decode_label`);
  lines starting ``#`` are comments. Caribu's own writer gives triangles (``p 1 label 3 ...``);
  a polygon of more vertices is cut into a fan of triangles here, its label kept.
- ``.light``: one source a line, ``energy vx vy vz``: the source's energy on a horizontal
  plane (per unit area) and the direction the light travels (``vz < 0``: downward).
- ``.8``: the pattern, two lines ``x y`` (opposite corners of the rectangle an infinite
  canopy repeats).
- ``.opt``: ``n <species>``, ``s d <soil reflectance>``, then one ``e`` line a species:
  ``e d <stem reflectance> d <reflectance> <transmittance> d <reflectance> <transmittance>``
  (the leaves' lower then upper side; -1 where it does not apply).

Every reader refuses what it cannot read in one :class:`CanestraFileError` line naming the
file and the line; numbers are read strictly (:mod:`maizeviz.numbers`).

References
----------
Chelle, M. & Andrieu, B. (1998). The nested radiosity model for the distribution of light
within plant canopies. Ecological Modelling 111, 75-91.
Caribu, OpenAlea's light model (``alinea.caribu``): https://github.com/openalea-incubator/caribu
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.io.inputs import read_input
from maizeviz.numbers import number, whole

#: Largest Canestra file read (a scene of about 5 M triangles).
MAX_CAN_BYTES = 1 << 30
#: Largest light, pattern or optics file read.
MAX_SMALL_BYTES = 16 << 20


class CanestraFileError(MaizevizError):
    """A Canestra file (``.can``, ``.light``, ``.8``, ``.opt``) cannot be read."""


def _lines(path: str | Path, what: str, max_bytes: int):
    raw = read_input(path, what, max_bytes, CanestraFileError)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise CanestraFileError(f"{path}: not a text file (byte {exc.start:,} is not UTF-8)") \
            from None
    if "\x00" in text:
        raise CanestraFileError(f"{path}: holds zero bytes: not a text {what}")
    for no, line in enumerate(text.splitlines(), start=1):
        line = line.strip()
        if line and not line.startswith("#"):
            yield no, line


def _numbers(path, no: int, tokens: Sequence[str], what: str) -> list[float]:
    out = []
    for tok in tokens:
        try:
            value = number(tok)
        except ValueError:
            raise CanestraFileError(f"{path}: line {no}: {what} {tok[:30]!r} is not a number") \
                from None
        if not np.isfinite(value):
            raise CanestraFileError(f"{path}: line {no}: {what} is {tok}")
        out.append(value)
    return out


def read_can(path: str | Path) -> dict[str, np.ndarray]:
    """The labelled triangles of a ``.can`` file.

    Parameters
    ----------
    path : the file

    Returns
    -------
    dict of str to (n, 3, 3) float64
        Each label's triangles, in file order (labels in the order they first appear); a
        polygon of ``k > 3`` vertices gives ``k - 2`` triangles (a fan from its first vertex).
        Coordinates are the file's, in its own unit.

    Raises
    ------
    CanestraFileError
        A line that is not a primitive (naming the line), a vertex count that does not match
        the coordinates, a coordinate that is not a finite number, a file with no primitive.
    """
    scene: dict[str, list] = {}
    for no, line in _lines(path, "Canestra scene (.can)", MAX_CAN_BYTES):
        fields = line.split()
        if fields[0] != "p":
            raise CanestraFileError(f"{path}: line {no}: a primitive starts with 'p', this line "
                                    f"with {fields[0][:20]!r}")
        try:
            n_attr = whole(fields[1])
            n_vert = whole(fields[2 + n_attr])
        except (ValueError, IndexError):
            raise CanestraFileError(f"{path}: line {no}: not 'p <attributes> <label ...> "
                                    "<vertices> x y z ...'") from None
        if n_attr < 1:
            raise CanestraFileError(f"{path}: line {no}: a primitive needs its label (0 "
                                    "attributes given)")
        if n_vert < 3:
            raise CanestraFileError(f"{path}: line {no}: a polygon of {n_vert} vertices (at "
                                    "least 3)")
        coords = fields[3 + n_attr:]
        if len(coords) != 3 * n_vert:
            raise CanestraFileError(f"{path}: line {no}: {n_vert} vertices need {3 * n_vert} "
                                    f"coordinates, the line has {len(coords)}")
        xyz = np.array(_numbers(path, no, coords, "coordinate")).reshape(n_vert, 3)
        fan = [(xyz[0], xyz[k], xyz[k + 1]) for k in range(1, n_vert - 1)]
        scene.setdefault(fields[2], []).extend(fan)
    if not scene:
        raise CanestraFileError(f"{path}: no primitive (an empty Canestra scene)")
    return {label: np.array(tris, np.float64) for label, tris in scene.items()}


def write_can(path: str | Path, scene: Mapping[object, object]) -> Path:
    """Write labelled triangles as a ``.can`` file Caribu reads (``p 1 <label> 3 ...``).

    Parameters
    ----------
    path : the file (written whole, then moved in place)
    scene : mapping of label to triangles
        Each label's triangles, (n, 3, 3) coordinates (a nested list of points works too). A
        label is written as text: Canestra barcodes (:func:`encode_label`) carry the optical
        species, plant and leaf that Caribu's ``.opt`` files refer to; other labels (ints, text
        without white space) are kept as they are.

    Returns
    -------
    Path of the file written.
    """
    from maizeviz.io.atomic import write_text

    lines = []
    for label, tris in scene.items():
        text = str(label)
        if not text or any(c.isspace() for c in text):
            raise CanestraFileError(f"{path}: the label {text!r} is empty or holds white space, "
                                    "which a .can line cannot carry")
        arr = np.asarray(tris, np.float64).reshape(-1, 3, 3)
        if not np.all(np.isfinite(arr)):
            raise CanestraFileError(f"{path}: label {text}: a coordinate is not finite")
        for tri in arr:
            lines.append(f"p 1 {text} 3 " + " ".join(f"{v:.6f}" for v in tri.ravel()))
    write_text(path, "\n".join(lines) + "\n")
    return Path(path)


def read_light(path: str | Path) -> list[tuple[float, tuple[float, float, float]]]:
    """Light sources of a ``.light`` file: ``(energy, (vx, vy, vz))`` each, as Caribu's
    ``light`` argument takes them (energy on a horizontal plane; the direction light travels).
    """
    lights = []
    for no, line in _lines(path, "Canestra light file (.light)", MAX_SMALL_BYTES):
        fields = line.split()
        if len(fields) != 4:
            raise CanestraFileError(f"{path}: line {no}: a source is 'energy vx vy vz', the line "
                                    f"has {len(fields)} fields")
        e, vx, vy, vz = _numbers(path, no, fields, "a value")
        if vx == vy == vz == 0:
            raise CanestraFileError(f"{path}: line {no}: the direction (0, 0, 0) has no way")
        lights.append((e, (vx, vy, vz)))
    if not lights:
        raise CanestraFileError(f"{path}: no light source")
    return lights


def write_light(path: str | Path, lights: Sequence[tuple[float, Sequence[float]]]) -> Path:
    """Write light sources as a ``.light`` file (see :func:`read_light`)."""
    from maizeviz.io.atomic import write_text

    rows = [" ".join(f"{v:g}" for v in (e, *d)) for e, d in lights]
    write_text(path, "\n".join(rows) + "\n")
    return Path(path)


def read_pattern(path: str | Path) -> tuple[float, float, float, float]:
    """The pattern of a ``.8`` file: ``(xmin, ymin, xmax, ymax)``."""
    pts: list[float] = []
    for no, line in _lines(path, "Canestra pattern (.8)", MAX_SMALL_BYTES):
        fields = line.split()
        if len(fields) != 2:
            raise CanestraFileError(f"{path}: line {no}: a corner is 'x y', the line has "
                                    f"{len(fields)} fields")
        pts += _numbers(path, no, fields, "a coordinate")
    if len(pts) != 4:
        raise CanestraFileError(f"{path}: a pattern is two corners, the file has "
                                f"{len(pts) // 2}")
    x0, y0, x1, y1 = pts
    if x0 == x1 or y0 == y1:
        raise CanestraFileError(f"{path}: the pattern's corners ({x0:g}, {y0:g}) and "
                                f"({x1:g}, {y1:g}) enclose no area")
    return min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1)


def write_pattern(path: str | Path, pattern: Sequence[float]) -> Path:
    """Write ``(xmin, ymin, xmax, ymax)`` as a ``.8`` file."""
    from maizeviz.io.atomic import write_text

    x0, y0, x1, y1 = (float(v) for v in pattern)
    write_text(path, f"{x0:g} {y0:g}\n{x1:g} {y1:g}\n")
    return Path(path)


def read_opt(path: str | Path) -> tuple[float, dict[int, tuple[float, ...]]]:
    """Soil reflectance and optical species of a ``.opt`` file.

    Returns
    -------
    soil_reflectance : float
    species : dict of int to (stem_reflectance, rho_lower, tau_lower, rho_upper, tau_upper)
        Species numbered from 1 in file order (the optical id of a Canestra label).
    """
    soil: float | None = None
    species: dict[int, tuple[float, ...]] = {}
    declared: int | None = None
    for no, line in _lines(path, "Canestra optics file (.opt)", MAX_SMALL_BYTES):
        fields = line.split()
        kind = fields[0]
        if kind == "n" and len(fields) == 2:
            try:
                declared = whole(fields[1])
            except ValueError:
                raise CanestraFileError(f"{path}: line {no}: the species count "
                                        f"{fields[1][:20]!r} is not a whole number") from None
        elif kind == "s" and len(fields) == 3:
            soil = _numbers(path, no, fields[2:], "the soil reflectance")[0]
        elif kind == "e" and len(fields) == 9:
            values = _numbers(path, no, [fields[i] for i in (2, 4, 5, 7, 8)], "a value")
            species[len(species) + 1] = tuple(values)
        else:
            raise CanestraFileError(f"{path}: line {no}: not an 'n', 's d <reflectance>' or "
                                    "'e d <r> d <r> <t> d <r> <t>' line")
    if soil is None:
        raise CanestraFileError(f"{path}: no soil line ('s d <reflectance>')")
    if declared is not None and declared != len(species):
        raise CanestraFileError(f"{path}: declares {declared} species ('n' line) and defines "
                                f"{len(species)}")
    return soil, species


def write_opt(path: str | Path, soil_reflectance: float,
              species: Mapping[int, Sequence[float]]) -> Path:
    """Write a ``.opt`` file: species ``1..n`` as Caribu materials (1-tuple: opaque, its
    reflectance; 2-tuple: reflectance and transmittance of both sides; 4-tuple: lower then
    upper side), in key order."""
    from maizeviz.io.atomic import write_text

    rows = [f"n {len(species)}", f"s d {soil_reflectance:g}"]
    for key in sorted(species):
        po = tuple(float(v) for v in species[key])
        if len(po) == 1:
            rows.append(f"e d {po[0]:g}   d -1 -1  d -1 -1")
        elif len(po) == 2:
            rows.append(f"e d -1   d {po[0]:g} {po[1]:g}  d {po[0]:g} {po[1]:g}")
        elif len(po) == 4:
            rows.append(f"e d -1   d {po[0]:g} {po[1]:g}  d {po[2]:g} {po[3]:g}")
        else:
            raise CanestraFileError(f"{path}: species {key}: a material is 1, 2 or 4 values, "
                                    f"got {len(po)}")
    write_text(path, "\n".join(rows) + "\n")
    return Path(path)


def encode_label(optical_id: int = 1, transparent: bool = True, plant: int = 1,
                 element: int = 1) -> str:
    """A Canestra barcode: the optical species (any digits), then plant (5 digits), leaf
    flag (3 digits: nonzero for a translucent leaf, 0 for an opaque organ) and element (3
    digits), as Caribu's ``Label`` writes them (``100001001001``: species 1, plant 1, a leaf,
    element 1)."""
    for name, value, top in (("plant", plant, 99_999), ("element", element, 999)):
        if not 0 <= int(value) <= top:
            raise MaizevizError(f"a Canestra label's {name} id is 0..{top}, got {value}",
                                quantity=name)
    if int(optical_id) < 0:
        raise MaizevizError(f"an optical id is >= 0, got {optical_id}", quantity="optical_id")
    return f"{int(optical_id)}{int(plant):05d}{int(bool(transparent)):03d}{int(element):03d}"


def decode_label(label: str) -> tuple[int, bool, int, int]:
    """``(optical_id, transparent, plant, element)`` of a Canestra barcode (at least 12
    digits; see :func:`encode_label`); MaizevizError for another label."""
    text = str(label)
    if len(text) < 12 or not text.isascii() or not text.isdigit():
        raise MaizevizError(f"{text[:30]!r} is not a Canestra label (12 or more digits)",
                            quantity="label")
    return int(text[:-11]), int(text[-6:-3]) != 0, int(text[-11:-6]), int(text[-3:])
