"""Project files: one file holding a study, so it can be reopened, moved and shared.

A project is a zip archive (``.maizeviz``) with exactly these members::

    project.json   what the project is: format version, points file (path and content hash),
                   layout document, canopy and light settings, stored results (JSON)
    points.csv     the digitized points, byte for byte as they were read
    arrays.npz     numpy arrays (a .npz, read with ``allow_pickle=False``): layout cells and
                   the arrays of stored results

No pickle anywhere: JSON and plain numeric arrays only. The file is written atomically (a
temporary file in the same folder, fsync, rename), so a crash while saving leaves the previous
project intact.

Reading trusts nothing: a project from a newer maizeviz, a truncated or corrupted archive, a
member that is not one of the three above (a name with ``..`` or ``/`` included), a member or an
array larger than the limits below (zip bombs), an array header that does not match its data,
or a field of the wrong type is refused with :class:`ProjectError`, one line saying what is
wrong and what to do.

This module is below the canopy and light stages: the layout is kept as a layout document
(:func:`maizeviz.canopy.layout.layout_to_dict`) and results as JSON plus named arrays; the
caller turns them back into objects and validates them as it would any other input.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import math
import os
import re
import struct
import zipfile
import zlib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np

from maizeviz import __version__
from maizeviz.errors import MaizevizError
from maizeviz.io.atomic import atomic_path
from maizeviz.io.inputs import open_input

#: Version of the project format this maizeviz writes and reads.
PROJECT_FORMAT = 1
#: File name extension of projects.
SUFFIX = ".maizeviz"
#: The members of a project archive, nothing else.
MEMBERS = ("project.json", "points.csv", "arrays.npz")
#: Largest uncompressed size (bytes) of each member.
MAX_MEMBER_BYTES = {"project.json": 16 * 2**20, "points.csv": 256 * 2**20,
                    "arrays.npz": 2**30}
#: Largest size (bytes) of one array (all arrays together: ``MAX_MEMBER_BYTES["arrays.npz"]``).
MAX_ARRAY_BYTES = 512 * 2**20
#: A text member compressed more than this is taken for a zip bomb (CSV and JSON pack 3-20x).
MAX_RATIO = 200
#: Array element types a project may hold (no objects, no strings).
ARRAY_KINDS = "biuf"
_NAME = re.compile(r"[A-Za-z0-9_.]{1,100}")


class ProjectError(MaizevizError):
    """A project file that cannot be used; the message says what is wrong and what to do."""


@dataclass(frozen=True)
class Record:
    """One stored result: JSON metadata and named arrays.

    Attributes
    ----------
    kind : what the result is (``"light"``); readers skip kinds they do not know
    meta : JSON object (str keys; str, number, bool, None and lists/objects of those)
    arrays : name -> numeric numpy array
    """

    kind: str
    meta: dict[str, Any]
    arrays: Mapping[str, np.ndarray | StoredArray] = field(default_factory=dict)


@dataclass(frozen=True)
class Project:
    """Everything a project file holds.

    Attributes
    ----------
    points_csv : the points file's bytes
    points_path : where the points file was when the project was saved (may have moved since)
    layout : a layout document (schema of :mod:`maizeviz.canopy.layout`), or None for the
        tiling given by the settings
    settings : canopy and light settings as JSON values (``{"canopy": {...}, "light": {...}}``)
    arrays : named numeric arrays that go with the layout or settings (e.g. tiling cells)
    results : stored results, oldest first
    """

    points_csv: bytes
    points_path: str
    layout: dict[str, Any] | None = None
    settings: dict[str, Any] = field(default_factory=dict)
    arrays: Mapping[str, np.ndarray | StoredArray] = field(default_factory=dict)
    results: tuple[Record, ...] = ()

    @property
    def points_sha256(self) -> str:
        """Hex SHA-256 of the points bytes (tells whether the file on disk is still the same)."""
        return hashlib.sha256(self.points_csv).hexdigest()



class StoredArray:
    """An array of a project, read from the file only when its values are needed.

    Opening a project reads each array's header (shape and type, checked against the
    project's limits) but none of its data, so a reader can compare the declared size with
    the canopy the array belongs to before any memory is spent on it
    (:func:`maizeviz.project.study.results_on`). ``np.asarray(a)`` (or any numpy function)
    reads the data once; the file must be unchanged since it was opened.

    Attributes
    ----------
    name : str, the array's name in arrays.npz
    shape : tuple of int; dtype : numpy.dtype; ndim, nbytes, size : as numpy's
    """

    def __init__(self, source: _ArraySource, name: str, info: zipfile.ZipInfo,
                 shape: tuple[int, ...], dtype: np.dtype):
        self.name, self.shape, self.dtype = name, tuple(shape), dtype
        self._source, self._info = source, info
        self._data: np.ndarray | None = None

    ndim = property(lambda self: len(self.shape))
    size = property(lambda self: math.prod(self.shape))
    nbytes = property(lambda self: self.size * self.dtype.itemsize)

    def __len__(self) -> int:
        if not self.shape:
            raise TypeError("len() of a 0-d array")
        return self.shape[0]

    def __repr__(self) -> str:
        return f"StoredArray({self.name!r}, shape={self.shape}, dtype={self.dtype})"

    def load(self) -> np.ndarray:
        """The values (read-only), read on first use."""
        if self._data is None:
            with self._source.inner() as inner:
                self._data = _read_npy(inner, self._info, self.name, self._source.where,
                                       MAX_ARRAY_BYTES)
            self._data.flags.writeable = False
        return self._data

    def __array__(self, dtype=None, copy=None):
        a = self.load()
        if dtype is not None and np.dtype(dtype) != a.dtype:
            return a.astype(dtype)
        return a.copy() if copy else a

    def astype(self, dtype, **kwargs) -> np.ndarray:
        return self.load().astype(dtype, **kwargs)

    def __getitem__(self, key):
        return self.load()[key]


class _ArraySource:
    """Where a project's arrays.npz is: the bytes read at open (a compressed member), or the
    project file itself, reopened for each array and refused if it changed since."""

    def __init__(self, where: str, raw: bytes | None, stamp: tuple | None):
        self.where, self._raw, self._stamp = where, raw, stamp
        self._file = os.path.abspath(where)     # the same file if the working folder changes

    @contextlib.contextmanager
    def inner(self) -> Iterator[zipfile.ZipFile]:
        if self._raw is not None:
            with zipfile.ZipFile(io.BytesIO(self._raw)) as inner:
                yield inner
            return
        changed = _refuse(self.where, "the project file changed after it was opened; open it "
                                      "again")
        try:
            with open(self._file, "rb") as fh:
                if _stamp(fh) != self._stamp:
                    raise changed
                with zipfile.ZipFile(fh) as zf, zf.open("arrays.npz") as member, \
                        zipfile.ZipFile(member) as inner:
                    yield inner
        except (zipfile.BadZipFile, KeyError, zlib.error, EOFError, ValueError) as exc:
            raise _refuse(self.where, f"arrays.npz is damaged ({str(exc)[:60]})") from None
        except OSError as exc:
            raise _refuse(self.where, f"cannot be read ({exc.strerror or exc})") from None


def _stamp(fh) -> tuple:
    """What tells that an open file is the one read before: device, inode, size, mtime."""
    st = os.fstat(fh.fileno())
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)


# ---------------------------------------------------------------------------------- writing
def _check_array(name: str, a: np.ndarray | StoredArray) -> np.ndarray:
    a = np.asarray(a)
    if a.dtype.kind not in ARRAY_KINDS or a.dtype.hasobject:
        raise ProjectError(f"array '{name}' of type {a.dtype} cannot be stored in a project "
                           "(numbers and booleans only)")
    if a.nbytes > MAX_ARRAY_BYTES:
        raise ProjectError(f"array '{name}' ({a.nbytes / 2**20:.0f} MiB) is larger than a "
                           f"project holds ({MAX_ARRAY_BYTES // 2**20} MiB per array)")
    return a


def _json_text(doc: dict) -> str:
    try:
        return json.dumps(doc, indent=1, allow_nan=False, sort_keys=False) + "\n"
    except (TypeError, ValueError) as exc:
        raise ProjectError(f"the project cannot be written as JSON ({exc})") from None


def save_project(path: str | Path, project: Project) -> Path:
    """Write ``project`` to ``path`` atomically; returns the path.

    Raises
    ------
    ProjectError
        A setting or array that cannot be stored.
    MaizevizError
        The folder is missing or the file cannot be written (an existing project is left as
        it was).
    """
    arrays: dict[str, np.ndarray] = {}
    for name, a in project.arrays.items():
        if not _NAME.fullmatch(name) or "." in name:
            raise ProjectError(f"'{name}' is not a valid array name")
        arrays[f"project.{name}"] = _check_array(name, a)
    results = []
    for i, rec in enumerate(project.results):
        names = []
        for name, a in rec.arrays.items():
            if not _NAME.fullmatch(name) or "." in name:
                raise ProjectError(f"'{name}' is not a valid array name")
            arrays[f"r{i}.{name}"] = _check_array(name, a)
            names.append(name)
        results.append({"kind": rec.kind, "meta": rec.meta, "arrays": names})
    doc = {"maizeviz_project": PROJECT_FORMAT, "saved_by": f"maizeviz {__version__}",
           "points": {"path": str(project.points_path), "sha256": project.points_sha256,
                      "bytes": len(project.points_csv)},
           "layout": project.layout, "settings": project.settings,
           "arrays": sorted(k.split(".", 1)[1] for k in arrays if k.startswith("project.")),
           "results": results}
    text = _json_text(doc)
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)              # type: ignore[arg-type]
    with atomic_path(path) as tmp:
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:
            zf.writestr("project.json", text)
            zf.writestr("points.csv", project.points_csv)
            zf.writestr(zipfile.ZipInfo("arrays.npz", date_time=(1980, 1, 1, 0, 0, 0)),
                        buf.getvalue(), compress_type=zipfile.ZIP_STORED)
    return Path(path)


# ---------------------------------------------------------------------------------- reading
def _refuse(path: str, what: str) -> ProjectError:
    return ProjectError(f"{path}: {what}")


def _read_member(zf: zipfile.ZipFile, info: zipfile.ZipInfo, limit: int, where: str,
                 text: bool = True) -> bytes:
    """A member's bytes, refused beyond ``limit`` (checked against the header, then while
    reading, since a header can lie); ``text`` members also by their packing ratio."""
    if info.file_size > limit:
        raise _refuse(where, f"'{info.filename}' is {info.file_size / 2**20:.0f} MiB unpacked, "
                             f"more than a project holds ({limit / 2**20:.0f} MiB); it is not "
                             "a maizeviz project or it was tampered with")
    if text and info.file_size > 2**20 and info.file_size > MAX_RATIO * max(info.compress_size, 1):
        raise _refuse(where, f"'{info.filename}' unpacks {info.file_size // max(info.compress_size, 1)}"
                             " times its packed size (a zip bomb?); not opened")
    out = bytearray()
    with zf.open(info) as fh:
        while True:
            chunk = fh.read(1 << 20)
            if not chunk:
                break
            out += chunk
            if len(out) > info.file_size or len(out) > limit:
                raise _refuse(where, f"'{info.filename}' holds more data than its header says")
    return bytes(out)


def _members(zf: zipfile.ZipFile, where: str) -> dict[str, zipfile.ZipInfo]:
    infos = zf.infolist()
    if len(infos) > len(MEMBERS):
        raise _refuse(where, f"{len(infos)} files in the archive, a project has "
                             f"{len(MEMBERS)}; not a maizeviz project")
    found: dict[str, zipfile.ZipInfo] = {}
    for info in infos:
        name = info.filename
        if name not in MEMBERS:
            shown = name if len(name) < 60 else name[:57] + "..."
            raise _refuse(where, f"unexpected file '{shown}' in the archive; not a maizeviz "
                                 "project (or it was tampered with)")
        if name in found:
            raise _refuse(where, f"'{name}' appears twice in the archive; not opened")
        if info.flag_bits & 0x1:
            raise _refuse(where, f"'{name}' is encrypted; maizeviz projects are not")
        found[name] = info
    missing = [m for m in MEMBERS if m not in found]
    if missing:
        raise _refuse(where, f"'{missing[0]}' is missing from the archive; the project is "
                             "incomplete")
    return found


def _expect(value: Any, kind: type | tuple[type, ...], what: str, where: str) -> Any:
    ok = isinstance(value, kind) and (kind is bool or not isinstance(value, bool))
    if not ok:
        names = {dict: "an object", list: "a list", str: "text", bool: "true or false",
                 int: "a whole number", (int, float): "a number", float: "a number"}
        shown = json.dumps(value)[:40] if _jsonable(value) else "something else"
        raise _refuse(where, f"{what} must be {names.get(kind, 'something else')}, got {shown}")
    if isinstance(value, float) and not math.isfinite(value):
        shown = "a number too large" if value in (math.inf, -math.inf) else str(value)
        raise _refuse(where, f"{what} must be a finite number, got {shown}")
    if isinstance(value, str) and "\x00" in value:
        raise _refuse(where, f"{what} holds a NUL character; the project is damaged or was "
                             "tampered with")
    return value


def _jsonable(v: Any) -> bool:
    try:
        json.dumps(v)
        return True
    except (TypeError, ValueError):
        return False


#: Longest integer (digits) a project may hold; longer ones read as infinite, so the field that
#: holds one is refused by name (no setting, id or count needs more).
MAX_DIGITS = 30


def _bounded_int(text: str) -> int | float:
    digits = text.lstrip("-")
    if len(digits) > MAX_DIGITS:
        return -math.inf if text.startswith("-") else math.inf
    return int(text)


def _parse_json(raw: bytes, where: str) -> dict[str, Any]:
    try:
        doc = json.loads(raw.decode("utf-8"), parse_int=_bounded_int)
    except UnicodeDecodeError:
        raise _refuse(where, "project.json is not UTF-8 text; the project is damaged") from None
    except (ValueError, RecursionError) as exc:
        raise _refuse(where, f"project.json is not valid JSON ({str(exc)[:60]}); the project "
                             "is damaged") from None
    if not isinstance(doc, dict):
        raise _refuse(where, "project.json must be a JSON object; the project is damaged")
    version = doc.get("maizeviz_project")
    if isinstance(version, int) and not isinstance(version, bool) and version > PROJECT_FORMAT:
        raise _refuse(where, f"saved by a newer maizeviz (project format {version}; this "
                             f"maizeviz {__version__} reads format {PROJECT_FORMAT}): update "
                             "maizeviz to open it")
    if version != PROJECT_FORMAT:
        shown = json.dumps(version)[:20]
        raise _refuse(where, f"'maizeviz_project' is {shown}, not a project format this "
                             f"maizeviz reads ({PROJECT_FORMAT})")
    return doc


def _npy_header(fh: IO[bytes], name: str, where: str) -> tuple[tuple[int, ...], bool, np.dtype]:
    """Shape, Fortran order and type from the header of a .npy stream (its data unread)."""
    try:
        major, minor = np.lib.format.read_magic(fh)
        if (major, minor) == (1, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(fh)
        elif (major, minor) in ((2, 0), (3, 0)):
            shape, fortran, dtype = np.lib.format.read_array_header_2_0(fh)
        else:
            raise ValueError(f"npy version {major}.{minor}")
    except (ValueError, EOFError, SyntaxError, struct.error, OverflowError, TypeError,
            zlib.error, zipfile.BadZipFile) as exc:
        raise _refuse(where, f"array '{name}' is damaged ({str(exc)[:60]})") from None
    if dtype.hasobject or dtype.kind not in ARRAY_KINDS:
        raise _refuse(where, f"array '{name}' has type {dtype}, which projects never hold; "
                             "not opened")
    return shape, fortran, dtype


def _declared_size(fh: IO[bytes], info: zipfile.ZipInfo, name: str, shape: tuple,
                   dtype: np.dtype, where: str, budget: int) -> int:
    """Bytes the header of array ``name`` declares (``fh`` just past the header), refused
    unless they fill the member exactly and fit :data:`MAX_ARRAY_BYTES` and ``budget``."""
    size = math.prod(shape) * dtype.itemsize
    if fh.tell() + size != info.file_size:
        raise _refuse(where, f"array '{name}' says {shape} {dtype} but holds "
                             f"{info.file_size - fh.tell()} bytes; the project is damaged")
    if size > MAX_ARRAY_BYTES or size > budget:
        raise _refuse(where, f"array '{name}' says {shape} {dtype} ({size / 2**20:.0f} MiB), "
                             "more than a project holds; not opened")
    return size


def _read_npy(zf: zipfile.ZipFile, info: zipfile.ZipInfo, name: str, where: str,
              budget: int) -> np.ndarray:
    """One .npy member of arrays.npz: its header is read first and the size it declares is
    checked (:func:`_declared_size`) before the data are read, so an array claiming a huge
    shape is refused without allocating it."""
    with zf.open(info) as fh:
        shape, fortran, dtype = _npy_header(fh, name, where)
        size = _declared_size(fh, info, name, shape, dtype, where, budget)
        try:
            data = fh.read(size)
            extra = fh.read(1)
        except (zlib.error, zipfile.BadZipFile, EOFError, OSError) as exc:
            raise _refuse(where, f"array '{name}' is damaged ({str(exc)[:60]})") from None
    if len(data) != size or extra:
        raise _refuse(where, f"array '{name}' holds more or less data than its header says; "
                             "the project is damaged")
    a = np.frombuffer(data, dtype=dtype, count=math.prod(shape))
    return a.reshape(shape, order="F" if fortran else "C")


def _array_headers(source: _ArraySource) -> dict[str, StoredArray]:
    """Every array of arrays.npz, by name, with its header read and checked (shape, type,
    size against the member's bytes, :data:`MAX_ARRAY_BYTES` and, all together, the
    arrays.npz limit); no data read."""
    where = source.where
    try:
        with source.inner() as inner:
            infos = inner.infolist()
            if len(infos) > 10_000:
                raise _refuse(where, f"arrays.npz holds {len(infos)} arrays; not a maizeviz "
                                     "project")
            out: dict[str, StoredArray] = {}
            budget = MAX_MEMBER_BYTES["arrays.npz"]
            for info in infos:
                stem = info.filename[:-4] if info.filename.endswith(".npy") else ""
                if not _NAME.fullmatch(stem) or stem in out:
                    raise _refuse(where, f"arrays.npz holds an unexpected entry "
                                         f"'{info.filename[:60]}'; not opened")
                if info.flag_bits & 0x1:
                    raise _refuse(where, f"array '{stem}' is encrypted; maizeviz projects are "
                                         "not")
                if info.file_size > MAX_ARRAY_BYTES + 4096:
                    raise _refuse(where, f"array '{stem}' is {info.file_size / 2**20:.0f} MiB "
                                         "unpacked, more than a project holds; not opened")
                with inner.open(info) as fh:
                    shape, _, dtype = _npy_header(fh, stem, where)
                    size = _declared_size(fh, info, stem, shape, dtype, where, budget)
                out[stem] = StoredArray(source, stem, info, shape, dtype)
                budget -= size
    except (zipfile.BadZipFile, OSError, ValueError, EOFError, NotImplementedError,
            zlib.error) as exc:
        raise _refuse(where, f"arrays.npz is damaged ({str(exc)[:60]})") from None
    return out


def load_project(path: str | Path) -> Project:
    """Read a project file (see the module docstring for what is refused).

    Raises
    ------
    ProjectError
        One line naming the file and what is wrong with it.
    """
    where = str(path)
    fh, _ = open_input(path, "project file", ProjectError)   # a FIFO or device: refused at once
    try:
        with fh, zipfile.ZipFile(fh) as zf:
            found = _members(zf, where)
            packed = found["arrays.npz"]
            # maizeviz stores arrays.npz unpacked: its arrays are read from the file when
            # used; a packed one (another writer) is read now, within the same limit
            lazy = packed.compress_type == zipfile.ZIP_STORED and Path(where).is_file()
            raw = {name: _read_member(zf, info, MAX_MEMBER_BYTES[name], where,
                                      text=name != "arrays.npz")
                   for name, info in found.items() if not (lazy and info is packed)}
            if packed.file_size > MAX_MEMBER_BYTES["arrays.npz"]:
                raise _refuse(where, f"'arrays.npz' is {packed.file_size / 2**20:.0f} MiB, "
                                     "more than a project holds; not opened")
            source = _ArraySource(where, None if lazy else raw.pop("arrays.npz"),
                                  _stamp(fh) if lazy else None)
            arrays = _array_headers(source)
    except zipfile.BadZipFile as exc:
        text = str(exc)
        what = ("a file in it is damaged (checksum mismatch)" if "CRC" in text or "Bad" in text
                else "not a maizeviz project (not a zip archive), or it is damaged")
        raise _refuse(where, what) from None
    except (zlib.error, EOFError, ValueError, NotImplementedError, OverflowError,
            struct.error) as exc:
        raise _refuse(where, f"the archive is damaged ({str(exc)[:60]})") from None
    except OSError as exc:
        raise _refuse(where, f"cannot be read ({exc.strerror or exc})") from None
    return _project_from(raw, arrays, where)


def _project_from(raw: dict[str, bytes], arrays: dict[str, StoredArray],
                  where: str) -> Project:
    doc = _parse_json(raw["project.json"], where)
    points = _expect(doc.get("points"), dict, "'points'", where)
    points_path = _expect(points.get("path"), str, "'points.path'", where)
    sha = _expect(points.get("sha256"), str, "'points.sha256'", where)
    csv = raw["points.csv"]
    if hashlib.sha256(csv).hexdigest() != sha.lower():
        raise _refuse(where, "the points stored in the project do not match their checksum; "
                             "the project is damaged")
    layout = doc.get("layout")
    if layout is not None:
        _expect(layout, dict, "'layout'", where)
    settings = _expect(doc.get("settings", {}), dict, "'settings'", where)
    array_names = _expect(doc.get("arrays", []), list, "'arrays'", where)
    results_doc = _expect(doc.get("results", []), list, "'results'", where)

    def take(key: str, what: str) -> StoredArray:
        if key not in arrays:
            raise _refuse(where, f"{what} is listed but missing from arrays.npz; the project "
                                 "is damaged")
        return arrays[key]

    project_arrays = {}
    for name in array_names:
        _expect(name, str, "an entry of 'arrays'", where)
        project_arrays[name] = take(f"project.{name}", f"array '{name}'")
    results = []
    for i, r in enumerate(results_doc):
        _expect(r, dict, f"results[{i}]", where)
        kind = _expect(r.get("kind"), str, f"results[{i}].kind", where)
        meta = _expect(r.get("meta", {}), dict, f"results[{i}].meta", where)
        names = _expect(r.get("arrays", []), list, f"results[{i}].arrays", where)
        rec_arrays = {}
        for name in names:
            _expect(name, str, f"an entry of results[{i}].arrays", where)
            rec_arrays[name] = take(f"r{i}.{name}", f"results[{i}] array '{name}'")
        results.append(Record(kind, meta, rec_arrays))
    return Project(csv, points_path, layout, settings, project_arrays, tuple(results))


# ------------------------------------------------------------------------- typed look-ups
_REQUIRED = object()


def get(obj: dict[str, Any], key: str, kind: type | tuple[type, ...], default: Any = _REQUIRED,
        where: str = "project") -> Any:
    """``obj[key]`` checked to be of ``kind`` (a bool is not a number), or ``default`` when
    the key is absent and a default is given.

    Raises
    ------
    ProjectError
        The key is missing (and no default) or the value has the wrong type.
    """
    if key not in obj:
        if default is _REQUIRED:
            raise ProjectError(f"{where}: '{key}' is missing")
        return default
    return _expect(obj[key], kind, f"'{key}'", where)


def get_numbers(obj: dict[str, Any], key: str, default: Any = _REQUIRED,
                where: str = "project") -> tuple[float, ...]:
    """A list of finite numbers under ``key``, as a tuple of floats."""
    values = get(obj, key, list, default, where)
    return tuple(float(_expect(v, (int, float), f"an entry of '{key}'", where)) for v in values)
