"""Readers of the files a shmgen dataset holds: OpenEXR layers, PNG images and binary PLY.

Each format has a decoder of bytes already read (``decode_exr``, ``decode_png``,
``parse_ply``), which checks the header before decoding anything: an image's size against
the size expected (the view's camera, when the dataset reads it) or :class:`Limits`'s
``max_side``, the file's length against the bound that size allows, a PNG's bit depth and
colour type, an EXR's channels and sampling, a PLY's element counts against the bytes that
follow. :func:`read_exr`, :func:`read_png` and :func:`read_ply` read a file the user names
(links followed: the user chose it; FIFOs, devices and folders refused) within
``Limits.image_file_bytes`` or ``Limits.mesh_bytes``; a :class:`shmgen_data.Dataset` reads its
files through :mod:`shmgen_data.files` instead (no links, per-view bounds) and hands the
bytes to the same decoders.

Every error names the file: ``FileNotFoundError`` for a missing one, ``KeyError`` for a
missing channel, :class:`DatasetError` (a ``ValueError``) for anything else.

* EXR: the ``OpenEXR`` package's ``File`` API (OpenEXR 3.3 and later) on the bytes read
  (an in-memory stream, or a private temporary copy where the package reads files only),
  headers first, then one numpy array per channel.
* PNG: the IHDR parsed here, then Pillow; 8-bit and 16-bit grey (masks, segmentation ids),
  8-bit RGB and RGBA.
* PLY: a small reader of binary PLY (little or big endian) written here on numpy, for the
  meshes and point clouds shmgen writes (``{sample:06}.mesh.ply``, ``.rest.ply``,
  ``.points.ply``) and any other binary PLY of scalar and list properties.
"""

from __future__ import annotations

import io
import os
import struct
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO, Sequence, TypeVar, Union

import numpy as np

from .files import DatasetError, Limits, read_named

__all__ = ["read_exr", "read_png", "read_ply", "decode_exr", "decode_png", "parse_ply",
           "PngHeader", "png_header", "PNG_FORMATS", "Ply", "PlyElement"]

_ON_ITS_OWN = "an image read on its own (Limits.image_file_bytes)"

#: A PLY property's type: a numpy dtype name (``"f4"``), or a list's (count, item) dtypes.
PlyKind = Union[str, tuple[str, str]]
#: A PLY property's values: an array, or a list of arrays for lists of varying lengths.
PlyValues = Union[np.ndarray, list[np.ndarray]]
_Value = TypeVar("_Value")


def _check_size(shown: str, width: int, height: int, size: tuple[int, int] | None, limits: Limits) -> None:
    """An image header's ``width × height``: ``size`` if one is expected, else positive and
    within ``limits.max_side``."""
    if size is not None:
        if (width, height) != tuple(size):
            raise DatasetError(f"{shown}: the header says {width}×{height} pixels, the camera has {size[0]}×{size[1]}")
    elif not (0 < width <= limits.max_side and 0 < height <= limits.max_side):
        raise DatasetError(f"{shown}: the header says {width}×{height} pixels; each side must be 1…{limits.max_side} (Limits.max_side)")


def _check_length(shown: str, length: int, bound: int) -> None:
    if length > bound:
        raise DatasetError(f"{shown}: {length} bytes, more than the {bound} its header's size allows (Limits.image_bytes)")


# ---------------------------------------------------------------------------------------
# EXR


def read_exr(path: str | os.PathLike[str], channels: Sequence[str], *, limits: Limits | None = None) -> np.ndarray:
    """The named channels of the OpenEXR file at ``path`` as float32.

    One channel gives an ``(H, W)`` array, several an ``(H, W, C)`` array in the order asked
    for (``["R", "G", "B"]`` = x, y, z for normals and displacement, ``["R", "G"]`` = u, v for
    flow, ``["Y"]`` for depth; datasets of ``shmgen.view/1`` named them ``X Y Z``, ``U V`` and
    ``Z``: the view record's ``channels`` say which). Raises ``FileNotFoundError`` naming a missing file, ``KeyError`` naming the
    channel a file lacks and the channels it has, and :class:`DatasetError` for a file that
    is not a regular one, too large, or does not decode.
    """
    limits = limits or Limits()
    data, shown = read_named(path, limits.image_file_bytes, _ON_ITS_OWN)
    return decode_exr(data, shown, channels, None, limits)


def _exr_file(data: bytes, header_only: bool) -> Any:
    """``OpenEXR.File`` over the bytes ``data``: from memory where the package reads streams
    (OpenEXR 3.5), else from a private temporary copy of the same bytes."""
    import OpenEXR

    try:
        return OpenEXR.File(io.BytesIO(data), separate_channels=True, header_only=header_only)
    except TypeError:  # no stream constructor: the bytes, already bounded, go through a file
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "image.exr")
            with open(path, "wb") as copy:
                copy.write(data)
            return OpenEXR.File(path, separate_channels=True, header_only=header_only)


def _exr_open(data: bytes, shown: str, header_only: bool) -> Any:
    try:
        return _exr_file(data, header_only)
    except Exception as error:  # OpenEXR raises bare exceptions for unreadable files
        what = "its header does not parse" if header_only else "its pixels do not decode (truncated or corrupt)"
        raise DatasetError(f"{shown}: not a readable OpenEXR file: {what} ({error})") from None


def _exr_header(data: bytes, shown: str, channels: Sequence[str], size: tuple[int, int] | None,
                limits: Limits) -> tuple[int, int]:
    """The EXR's ``(width, height)`` from its header, checked with its channels before any
    pixel is decoded: one part, a data window from (0, 0), the channels asked for present,
    every channel sampled at every pixel, all channels decoded within the image bound."""
    exr = _exr_open(data, shown, header_only=True)
    if len(exr.parts) != 1:
        raise DatasetError(f"{shown}: {len(exr.parts)} parts; a one-part OpenEXR file is expected")
    header = exr.header()
    low, high = (np.asarray(corner, dtype=np.int64) for corner in header["dataWindow"])
    if np.any(low != 0):
        raise DatasetError(f"{shown}: the data window starts at {tuple(low)}, not (0, 0)")
    width, height = (int(v) + 1 for v in high)
    _check_size(shown, width, height, size, limits)
    found = {c.name: c for c in header["channels"]}
    for name in channels:
        if name not in found:
            have = ", ".join(sorted(found)) or "none"
            raise KeyError(f"{shown}: no channel {name!r} (it has {have})")
    for channel in found.values():
        if (channel.xSampling, channel.ySampling) != (1, 1):
            raise DatasetError(f"{shown}: channel {channel.name!r} is subsampled ({channel.xSampling}, {channel.ySampling})")
    bound = limits.image_bytes(width, height, len(channels), 4)
    _check_length(shown, len(data), bound)
    if len(found) * width * height * 4 > bound:
        raise DatasetError(f"{shown}: {len(found)} channels of {width}×{height} pixels decode to more than the {bound} bytes its {len(channels)} channels allow")
    return width, height


def decode_exr(data: bytes, shown: str, channels: Sequence[str], size: tuple[int, int] | None,
               limits: Limits) -> np.ndarray:
    """The ``channels`` of the EXR file ``data`` (see :func:`read_exr`), its header checked
    first; ``size`` = ``(width, height)`` it must have, or None for any within ``limits``."""
    width, height = _exr_header(data, shown, channels, size, limits)
    exr = _exr_open(data, shown, header_only=False)
    try:
        found = {name: np.asarray(channel.pixels) for name, channel in exr.channels().items()}
    except Exception as error:  # a chunk that does not read leaves the file with no parts
        raise DatasetError(f"{shown}: not a readable OpenEXR file: its pixels do not decode (truncated or corrupt: {error})") from None
    planes = []
    for name in channels:
        plane = found[name]
        if plane.shape != (height, width) or plane.dtype.kind not in "fu":
            raise DatasetError(f"{shown}: channel {name!r} decodes to {plane.dtype} {plane.shape}, not {height}×{width} values")
        planes.append(plane.astype(np.float32, copy=False))
    if len(planes) == 1:
        return planes[0]
    return np.stack(planes, axis=-1)


# ---------------------------------------------------------------------------------------
# PNG

_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_PNG_END = b"\0\0\0\0IEND\xaeB`\x82"  # the IEND chunk, which every PNG ends with

#: The PNG formats the readers accept, ``(bit depth, colour type)`` → ``(channels, bytes per
#: sample)``: 8-bit and 16-bit grey, 8-bit RGB and RGBA.
PNG_FORMATS = {(8, 0): (1, 1), (16, 0): (1, 2), (8, 2): (3, 1), (8, 6): (4, 1)}
_COLOUR_TYPES = {0: "grey", 2: "RGB", 3: "palette", 4: "grey + alpha", 6: "RGBA"}


@dataclass(frozen=True)
class PngHeader:
    """A PNG's IHDR: size, bit depth, colour type (0 grey, 2 RGB, 3 palette, 4 grey + alpha,
    6 RGBA) and interlace method."""

    width: int
    height: int
    bit_depth: int
    colour_type: int
    interlace: int

    def describe(self) -> str:
        return f"{self.bit_depth}-bit {_COLOUR_TYPES.get(self.colour_type, f'colour type {self.colour_type}')}"


def png_header(data: bytes, shown: str) -> PngHeader:
    """The IHDR of the PNG ``data``, checked to be one (signature, first chunk, methods)."""
    if len(data) < 33 or data[:8] != _PNG_SIGNATURE or data[8:16] != b"\0\0\0\x0dIHDR":
        raise DatasetError(f"{shown}: not a PNG (no PNG signature and IHDR chunk at its start)")
    width, height, depth, colour, compression, filtering, interlace = struct.unpack(">IIBBBBB", data[16:29])
    if compression != 0 or filtering != 0 or interlace not in (0, 1):
        raise DatasetError(f"{shown}: PNG methods (compression {compression}, filter {filtering}, interlace {interlace}) are not PNG's")
    return PngHeader(width, height, depth, colour, interlace)


def read_png(path: str | os.PathLike[str], *, limits: Limits | None = None) -> np.ndarray:
    """The PNG at ``path`` as a numpy array.

    RGB gives ``(H, W, 3)`` uint8, RGBA ``(H, W, 4)`` uint8; 8-bit grey ``(H, W)`` uint8;
    16-bit grey ``(H, W)`` uint16 (shmgen's segmentation ids when an id exceeds 255).
    """
    limits = limits or Limits()
    data, shown = read_named(path, limits.image_file_bytes, _ON_ITS_OWN)
    return decode_png(data, shown, PNG_FORMATS, None, limits)


def decode_png(data: bytes, shown: str, formats: dict[tuple[int, int], tuple[int, int]], size: tuple[int, int] | None,
               limits: Limits) -> np.ndarray:
    """The PNG ``data`` decoded (see :func:`read_png`) once its IHDR is checked: a format of
    ``formats`` (as :data:`PNG_FORMATS`), the ``size`` = ``(width, height)`` expected (or any
    within ``limits``) and a file length within the bound that size allows."""
    from PIL import Image

    header = png_header(data, shown)
    fmt = (header.bit_depth, header.colour_type)
    if fmt not in formats:
        allowed = " or ".join(PngHeader(0, 0, d, c, 0).describe() for d, c in formats)
        raise DatasetError(f"{shown}: a {header.describe()} PNG; {allowed} is expected")
    _check_size(shown, header.width, header.height, size, limits)
    _check_length(shown, len(data), limits.image_bytes(header.width, header.height, *formats[fmt]))
    if not data.endswith(_PNG_END):
        raise DatasetError(f"{shown}: the PNG does not end with its IEND chunk (truncated)")
    try:
        with Image.open(io.BytesIO(data), formats=["PNG"]) as image:
            image.load()
            values = np.asarray(image)
    except Exception as error:  # Pillow: OSError, SyntaxError, EOFError, zlib errors…
        raise DatasetError(f"{shown}: its PNG data does not decode (truncated or corrupt: {error})") from None
    if header.bit_depth == 16:
        values = values.astype(np.uint16)  # Pillow may open 16-bit grey as 32-bit
    if values.shape[:2] != (header.height, header.width):
        raise DatasetError(f"{shown}: decodes to shape {values.shape}, its header says {header.width}×{header.height}")
    return values


# ---------------------------------------------------------------------------------------
# PLY

_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}


def _lookup(table: dict[str, _Value], name: str, missing: str) -> _Value:
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
    properties: dict[str, PlyValues] = field(default_factory=dict)

    def __getitem__(self, name: str) -> Any:
        return _lookup(self.properties, name, f"PLY element {self.name!r} has no property {name!r}")

    def __contains__(self, name: str) -> bool:
        return name in self.properties


@dataclass
class Ply:
    """A PLY file read: its elements by name, in file order, and its comments."""

    path: Path
    elements: dict[str, PlyElement]
    comments: list[str]

    def __getitem__(self, name: str) -> PlyElement:
        return _lookup(self.elements, name, f"{self.path}: no PLY element {name!r}")

    def __contains__(self, name: str) -> bool:
        return name in self.elements

    def xyz(self) -> np.ndarray:
        """The vertices' ``x, y, z`` as an ``(N, 3)`` float64 array."""
        vertex = self["vertex"]
        return np.stack([vertex[c].astype(np.float64) for c in "xyz"], axis=1)


#: The most bytes a PLY header may have (shmgen's have a few hundred).
PLY_HEADER_BYTES = 1 << 20


#: A PLY element as its header declares it: (name, count, [(property, kind)]).
_Declared = tuple[str, int, list[tuple[str, PlyKind]]]


def _parse_header(stream: BinaryIO, path: Path) -> tuple[str, list[_Declared], list[str]]:
    if stream.readline(8).rstrip(b"\r\n") != b"ply":
        raise DatasetError(f"{path}: not a PLY file (it does not start with 'ply')")
    fmt = None
    elements: list[_Declared] = []
    comments: list[str] = []
    while True:
        line = stream.readline(max(0, PLY_HEADER_BYTES + 1 - stream.tell()))
        if not line.endswith(b"\n"):
            raise DatasetError(f"{path}: the PLY header has no end_header in its first {PLY_HEADER_BYTES} bytes")
        words = line.decode("ascii", "replace").split()
        if not words:
            continue
        key = words[0]
        if key == "end_header":
            break
        if key == "format":
            fmt = words[1] if len(words) > 1 else None
        elif key in ("comment", "obj_info"):
            comments.append(line.decode("utf-8", "replace").rstrip("\r\n")[len(key) + 1 :])
        elif key == "element":
            if len(words) != 3 or not words[2].isdigit():
                raise DatasetError(f"{path}: PLY element line {line!r} is not 'element <name> <count ≥ 0>'")
            elements.append((words[1], int(words[2]), []))
        elif key == "property":
            if not elements:
                raise DatasetError(f"{path}: PLY property before any element")
            kind: PlyKind
            try:
                if words[1] == "list":
                    kind = (_PLY_TYPES[words[2]], _PLY_TYPES[words[3]])
                    name = words[4]
                else:
                    kind = _PLY_TYPES[words[1]]
                    name = words[2]
            except (KeyError, IndexError):
                raise DatasetError(f"{path}: unsupported PLY property line {line!r}") from None
            elements[-1][2].append((name, kind))
        else:
            raise DatasetError(f"{path}: unknown PLY header line {line!r}")
    if fmt not in ("binary_little_endian", "binary_big_endian"):
        raise DatasetError(f"{path}: PLY format {fmt!r} is not supported (binary PLY only)")
    return ("<" if fmt == "binary_little_endian" else ">"), elements, comments


def _take(data: memoryview, offset: int, dtype: str, count: int, path: Path,
          name: str) -> tuple[np.ndarray, int]:
    """``count`` values of ``dtype`` at ``offset`` (a copy, native byte order) and the offset
    after them; ``ValueError`` naming the file if the data ends first."""
    end = offset + np.dtype(dtype).itemsize * count
    if end > len(data):
        raise DatasetError(f"{path}: PLY data ends inside element {name!r}")
    values = np.frombuffer(data, dtype, count, offset)
    return values.astype(values.dtype.newbyteorder("=")), end


def _read_element(data: memoryview, offset: int, order: str, name: str, count: int,
                  props: list[tuple[str, PlyKind]], path: Path) -> tuple[PlyElement, int]:
    """Reads one element's ``count`` records from ``data`` at ``offset``; returns (element,
    new offset). Records are read in one go, taking every list to have the length of the
    first record's (checked); record by record when lists vary in length."""
    element = PlyElement(name, count)
    # A structured dtype with the list lengths of the first record.
    fields: list[Any] = []
    probe = offset
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
    columns: dict[str, list[Any]] = {prop: [] for prop, _ in props}
    for _ in range(count):
        for prop, kind in props:
            if isinstance(kind, str):
                value, offset = _take(data, offset, order + kind, 1, path, name)
                columns[prop].append(value[0])
            else:
                size, offset = _take(data, offset, order + kind[0], 1, path, name)
                items, offset = _take(data, offset, order + kind[1], int(size[0]), path, name)
                columns[prop].append(items)
    for prop, kind in props:
        if isinstance(kind, str):
            element.properties[prop] = np.array(columns[prop], dtype=kind)
        else:
            element.properties[prop] = columns[prop]
    return element, offset


def _check_count(path: Path, name: str, count: int, props: list[tuple[str, PlyKind]], left: int) -> None:
    """An element's declared ``count`` fits in the ``left`` bytes that follow, each record
    taking at least its scalars and list lengths: checked before anything is allocated."""
    least = sum(np.dtype(kind if isinstance(kind, str) else kind[0]).itemsize for _, kind in props)
    if count and (least == 0 or count * least > left):
        raise DatasetError(
            f"{path}: PLY element {name!r} declares {count} records of at least {least} bytes, "
            f"{left} bytes remain"
        )


def parse_ply(data: bytes, shown: str) -> Ply:
    """The binary PLY file ``data`` (see :func:`read_ply`); ``shown`` names it in errors."""
    path = Path(shown)
    stream = io.BytesIO(data)
    order, elements, comments = _parse_header(stream, path)
    body = memoryview(data)[stream.tell():]
    offset = 0
    read: dict[str, PlyElement] = {}
    for name, count, props in elements:
        _check_count(path, name, count, props, len(body) - offset)
        read[name], offset = _read_element(body, offset, order, name, count, props, path)
    if offset != len(body):
        raise DatasetError(f"{path}: {len(body) - offset} bytes follow the last PLY element")
    return Ply(path, read, comments)


def read_ply(path: str | os.PathLike[str], *, limits: Limits | None = None) -> Ply:
    """Reads the binary PLY file at ``path`` (little or big endian), of at most
    ``Limits.mesh_bytes``.

    shmgen's meshes (``mesh.ply``, ``rest.ply``) have ``vertex`` with double ``x, y, z`` and
    ``face`` with ``vertex_indices`` (an ``(M, 3)`` array for triangles) and ``part``; its
    point clouds (``points.ply``) have ``vertex`` with ``x, y, z`` and float ``nx, ny, nz``.
    Raises ``ValueError`` naming the file for ASCII PLY, unknown types or truncated data.
    """
    limits = limits or Limits()
    data, shown = read_named(path, limits.mesh_bytes, "a PLY file (Limits.mesh_bytes)")
    return parse_ply(data, shown)
