"""Readers of the files a shmgen dataset holds: OpenEXR layers, PNG images and binary PLY.

Every reader names the file in its errors (missing file, missing channel, unsupported
format), so a broken dataset says which file is at fault.

* EXR: the ``OpenEXR`` package's ``File`` API (OpenEXR 3.3 and later), one numpy array per
  channel.
* PNG: Pillow; 8-bit and 16-bit grey (masks, segmentation ids) and 8-bit RGB.
* PLY: a small reader of binary PLY (little or big endian) written here on numpy, for the
  meshes and point clouds shmgen writes (``{sample:06}.mesh.ply``, ``.rest.ply``,
  ``.points.ply``) and any other binary PLY of scalar and list properties.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO, Sequence

import numpy as np

__all__ = ["read_exr", "read_png", "read_ply", "Ply", "PlyElement"]


def _require_file(path: str | os.PathLike) -> Path:
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    return path


def read_exr(path: str | os.PathLike, channels: Sequence[str]) -> np.ndarray:
    """The named channels of the OpenEXR file at ``path`` as float32.

    One channel gives an ``(H, W)`` array, several an ``(H, W, C)`` array in the order asked
    for (``["X", "Y", "Z"]`` for normals and displacement, ``["U", "V"]`` for flow, ``["Z"]``
    for depth). Raises ``FileNotFoundError`` naming a missing file and ``KeyError`` naming the
    channel a file lacks and the channels it has.
    """
    import OpenEXR

    path = _require_file(path)
    try:
        with OpenEXR.File(str(path), separate_channels=True) as exr:
            found = exr.channels()
            planes = []
            for name in channels:
                if name not in found:
                    have = ", ".join(sorted(found)) or "none"
                    raise KeyError(f"{path}: no channel {name!r} (it has {have})")
                planes.append(np.asarray(found[name].pixels, dtype=np.float32))
    except KeyError:
        raise
    except Exception as error:  # OpenEXR raises bare exceptions for unreadable files
        raise ValueError(f"{path}: not a readable OpenEXR file ({error})") from error
    if len(planes) == 1:
        return planes[0]
    return np.stack(planes, axis=-1)


def read_png(path: str | os.PathLike) -> np.ndarray:
    """The PNG at ``path`` as a numpy array.

    RGB gives ``(H, W, 3)`` uint8; 8-bit grey ``(H, W)`` uint8; 16-bit grey ``(H, W)`` uint16
    (shmgen's segmentation ids when an id exceeds 255).
    """
    from PIL import Image

    path = _require_file(path)
    try:
        with Image.open(path) as image:
            mode = image.mode
            if mode in ("I;16", "I;16B", "I;16L"):
                return np.asarray(image, dtype=np.uint16)
            if mode == "I":  # some Pillow versions open 16-bit grey as 32-bit
                return np.asarray(image).astype(np.uint16)
            if mode not in ("RGB", "L", "RGBA"):
                raise ValueError(f"{path}: unexpected PNG mode {mode!r}")
            return np.asarray(image)
    except OSError as error:
        raise ValueError(f"{path}: not a readable PNG ({error})") from error


# ---------------------------------------------------------------------------------------
# PLY

_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}


def _lookup(table: dict, name: str, missing: str):
    """``table[name]``, or a ``KeyError`` saying ``missing`` and what the table has."""
    try:
        return table[name]
    except KeyError:
        raise KeyError(f"{missing} (it has {', '.join(table) or 'none'})") from None


@dataclass
class PlyElement:
    """One element of a PLY file (``vertex``, ``face``, …): its properties by name.

    A scalar property is an ``(N,)`` array; a list property whose lists all have one length
    ``k`` (triangles) is an ``(N, k)`` array, otherwise a list of ``N`` arrays.
    """

    name: str
    count: int
    properties: dict = field(default_factory=dict)

    def __getitem__(self, name: str):
        return _lookup(self.properties, name, f"PLY element {self.name!r} has no property {name!r}")

    def __contains__(self, name: str) -> bool:
        return name in self.properties


@dataclass
class Ply:
    """A PLY file read: its elements by name, in file order, and its comments."""

    path: Path
    elements: dict
    comments: list

    def __getitem__(self, name: str) -> PlyElement:
        return _lookup(self.elements, name, f"{self.path}: no PLY element {name!r}")

    def __contains__(self, name: str) -> bool:
        return name in self.elements

    def xyz(self) -> np.ndarray:
        """The vertices' ``x, y, z`` as an ``(N, 3)`` float64 array."""
        vertex = self["vertex"]
        return np.stack([vertex[c].astype(np.float64) for c in "xyz"], axis=1)


def _parse_header(stream: BinaryIO, path: Path):
    if stream.readline().rstrip(b"\r\n") != b"ply":
        raise ValueError(f"{path}: not a PLY file (it does not start with 'ply')")
    fmt = None
    elements = []  # (name, count, [(prop, dtype) or (prop, (count_dtype, item_dtype))])
    comments = []
    while True:
        line = stream.readline()
        if not line:
            raise ValueError(f"{path}: the PLY header has no end_header")
        words = line.decode("ascii", "replace").split()
        if not words:
            continue
        key = words[0]
        if key == "end_header":
            break
        if key == "format":
            fmt = words[1]
        elif key in ("comment", "obj_info"):
            comments.append(line.decode("utf-8", "replace").rstrip("\r\n")[len(key) + 1 :])
        elif key == "element":
            elements.append((words[1], int(words[2]), []))
        elif key == "property":
            if not elements:
                raise ValueError(f"{path}: PLY property before any element")
            try:
                if words[1] == "list":
                    kind = (_PLY_TYPES[words[2]], _PLY_TYPES[words[3]])
                    name = words[4]
                else:
                    kind = _PLY_TYPES[words[1]]
                    name = words[2]
            except (KeyError, IndexError):
                raise ValueError(f"{path}: unsupported PLY property line {line!r}") from None
            elements[-1][2].append((name, kind))
        else:
            raise ValueError(f"{path}: unknown PLY header line {line!r}")
    if fmt not in ("binary_little_endian", "binary_big_endian"):
        raise ValueError(f"{path}: PLY format {fmt!r} is not supported (binary PLY only)")
    return ("<" if fmt == "binary_little_endian" else ">"), elements, comments


def _take(data: memoryview, offset: int, dtype: str, count: int, path, name: str):
    """``count`` values of ``dtype`` at ``offset`` (a copy, native byte order) and the offset
    after them; ``ValueError`` naming the file if the data ends first."""
    end = offset + np.dtype(dtype).itemsize * count
    if end > len(data):
        raise ValueError(f"{path}: PLY data ends inside element {name!r}")
    values = np.frombuffer(data, dtype, count, offset)
    return values.astype(values.dtype.newbyteorder("=")), end


def _read_element(data: memoryview, offset: int, order: str, name: str, count: int, props, path):
    """Reads one element's ``count`` records from ``data`` at ``offset``; returns (element,
    new offset). Records are read in one go, taking every list to have the length of the
    first record's (checked); record by record when lists vary in length."""
    element = PlyElement(name, count)
    # A structured dtype with the list lengths of the first record.
    fields, probe = [], offset
    for prop, kind in props:
        if isinstance(kind, str):
            fields.append((prop, order + kind))
            probe += np.dtype(kind).itemsize
        else:
            count_type, item_type = kind
            length = int(_take(data, probe, order + count_type, 1, path, name)[0][0]) if count else 0
            fields.append((f"__n_{prop}", order + count_type))
            fields.append((prop, order + item_type, (length,)))
            probe += np.dtype(count_type).itemsize + length * np.dtype(item_type).itemsize
    record = np.dtype(fields)
    end = offset + record.itemsize * count
    if end <= len(data):
        table = np.frombuffer(data, record, count, offset)
        lists = [prop for prop, kind in props if not isinstance(kind, str)]
        if all(np.all(table[f"__n_{prop}"] == record[prop].shape[0]) for prop in lists):
            for prop, _ in props:
                column = np.array(table[prop])
                element.properties[prop] = column.astype(column.dtype.newbyteorder("="))
            return element, end
    # Lists of varying lengths: record by record.
    columns = {prop: [] for prop, _ in props}
    for _ in range(count):
        for prop, kind in props:
            if isinstance(kind, str):
                value, offset = _take(data, offset, order + kind, 1, path, name)
                columns[prop].append(value[0])
            else:
                length, offset = _take(data, offset, order + kind[0], 1, path, name)
                items, offset = _take(data, offset, order + kind[1], int(length[0]), path, name)
                columns[prop].append(items)
    for prop, kind in props:
        if isinstance(kind, str):
            element.properties[prop] = np.array(columns[prop], dtype=kind)
        else:
            element.properties[prop] = columns[prop]
    return element, offset


def read_ply(path: str | os.PathLike) -> Ply:
    """Reads the binary PLY file at ``path`` (little or big endian).

    shmgen's meshes (``mesh.ply``, ``rest.ply``) have ``vertex`` with double ``x, y, z`` and
    ``face`` with ``vertex_indices`` (an ``(M, 3)`` array for triangles) and ``part``; its
    point clouds (``points.ply``) have ``vertex`` with ``x, y, z`` and float ``nx, ny, nz``.
    Raises ``ValueError`` naming the file for ASCII PLY, unknown types or truncated data.
    """
    path = _require_file(path)
    with open(path, "rb") as stream:
        order, elements, comments = _parse_header(stream, path)
        data = memoryview(stream.read())
    offset = 0
    read = {}
    for name, count, props in elements:
        read[name], offset = _read_element(data, offset, order, name, count, props, path)
    if offset != len(data):
        raise ValueError(f"{path}: {len(data) - offset} bytes follow the last PLY element")
    return Ply(path, read, comments)
