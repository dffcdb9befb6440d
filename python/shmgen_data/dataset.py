"""A shmgen dataset as Python objects: its samples, their views and their files.

What is read comes from ``manifest.jsonl`` (one line per finished sample, listing every file)
and from each view's JSON record; file names are parsed as the layout states them:
``{sample:06}_{view:02}.{kind}`` for a view, ``…_{view:02}a{copy}.{kind}`` for an augmented
copy and ``{sample:06}.{kind}`` for a sample's own files (meshes, points).

Everything is read lazily: opening a dataset reads ``run.json`` and the manifest only (and
``lstat``s each listed file); a view's record, camera and images are read when first asked
for and kept by that :class:`View` object (so ``view.depth`` twice reads the file once). The
dataset hands out a new :class:`View` at each index access, so iterating over a large dataset
keeps nothing.

A dataset is untrusted input. Its files are opened by :mod:`shmgen_data.files` (no links
followed below the root, regular files only, reads bounded per kind by :class:`Limits`, sizes
checked against the manifest's ``hashes`` when it has them); images have their headers
checked against the view's camera before any pixel is decoded; and the values read are
checked as the layout defines them (:data:`LAYERS`): depth finite and ≥ 0, normals unit or 0,
displacement and flow finite, masks 0 or 255, ids within the record's tables, mesh
coordinates finite and faces within the vertices. :meth:`Dataset.verify` compares every
file with its BLAKE3.
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterator, Sequence, overload

import numpy as np
from numpy.typing import NDArray

from .camera import Camera
from .files import DatasetError, DatasetFiles, Limits, check_relative, parse_hashes
from .io import PNG_FORMATS, Ply, decode_exr, decode_png, parse_ply
from .structures import Augmentation, Record, Structure, Structures
from .tracks import assemble, decode_tracks

if TYPE_CHECKING:
    from .splits import Split

__all__ = ["Dataset", "Sample", "View", "Mesh", "Points", "LAYERS", "MissingFileError",
           "DatasetError", "Limits", "Verification", "Structure", "Structures", "Augmentation"]

RUN_SCHEMA = "shmgen.run/1"
VIEW_SCHEMA = "shmgen.view/2"
#: Every view record version this reader reads: ``shmgen.view/1`` differs only in its EXR
#: channel names (depth ``Z``, vectors ``X Y Z``, flow ``U V``), which its records name.
VIEW_SCHEMAS = (VIEW_SCHEMA, "shmgen.view/1")


class MissingFileError(FileNotFoundError):
    """A view or sample lacks the file asked for (the dataset was not asked to write it)."""


@dataclass(frozen=True)
class _Layer:
    """How one per-view output is stored: its file kind, and how its values are read."""

    kind: str  # the file name after the stem: "depth.exr"
    read: str  # "rgb", "binary", "ids" or "exr"
    convention: str | None = None  # the record's object naming its EXR channels
    channels: tuple[str, ...] = ()  # default EXR channels, if the record does not name them
    values: str = ""  # what the values must be: "depth", "unit", "finite", "ids" (see _VALUE_CHECKS)
    ids_table: str | None = None  # the record's segmentation table an id indexes

    @property
    def png_formats(self) -> dict[tuple[int, int], tuple[int, int]]:
        """The PNG ``(bit depth, colour type)`` the layer is written in (see PNG_FORMATS)."""
        allowed = {"rgb": [(8, 2)], "binary": [(8, 0)], "ids": [(8, 0), (16, 0)]}[self.read]
        return {fmt: PNG_FORMATS[fmt] for fmt in allowed}


#: Every per-view output, by name: ``rgb`` and ``rest_rgb`` are ``(H, W, 3)`` uint8; ``depth``,
#: ``rest_depth`` and ``ray_distance`` ``(H, W)`` float32 metres (0 = no surface); ``normals``
#: and ``displacement`` ``(H, W, 3)`` float32 (x, y, z); ``flow`` ``(H, W, 2)`` float32 pixels
#: (u, v), and in a sequence ``flow_next`` and ``flow_prev`` (this frame's image to the next
#: and previous frame's) likewise; the EXR channels are the ones the view's record names
#: (``Y``; ``R G B``; ``R G``); the masks ``mask``, ``cracks``, ``erased``, ``valid``,
#: ``flow_valid``, ``flow_next_valid`` and ``flow_prev_valid`` ``(H, W)`` bool
#: (True where the file holds 255); ``parts`` and ``instances`` ``(H, W)`` int32 ids;
#: ``damage_class`` (0 none … 6 dent, names in the record's ``damage.classes``) and
#: ``damage_instance`` (index + 1 in the structure's ``damage.items``) ``(H, W)`` int32,
#: ``crack_width`` (millimetres) and ``crack_coverage`` (0–1) ``(H, W)`` float32.
LAYERS = {
    "rgb": _Layer("rgb.png", "rgb"),
    "depth": _Layer("depth.exr", "exr", "depth", ("Y",), "depth"),
    "mask": _Layer("mask.png", "binary"),
    "parts": _Layer("parts.png", "ids", values="ids", ids_table="part_ids"),
    "instances": _Layer("instances.png", "ids", values="ids", ids_table="instance_ids"),
    "cracks": _Layer("cracks.png", "binary"),
    "erased": _Layer("erased.png", "binary"),
    "valid": _Layer("valid.png", "binary"),
    "normals": _Layer("normals.exr", "exr", "normals", ("R", "G", "B"), "unit"),
    "displacement": _Layer("displacement.exr", "exr", "displacement", ("R", "G", "B"), "finite"),
    "flow": _Layer("flow.exr", "exr", "flow", ("R", "G"), "finite"),
    "flow_valid": _Layer("flow_valid.png", "binary"),
    # Flow between consecutive frames of a sequence (output "frame_flow"; docs/sequences.md):
    # this frame's image -> the next frame's / the previous frame's, pixels.
    "flow_next": _Layer("flow_next.exr", "exr", "frame_flow", ("R", "G"), "finite"),
    "flow_next_valid": _Layer("flow_next_valid.png", "binary"),
    "flow_prev": _Layer("flow_prev.exr", "exr", "frame_flow", ("R", "G"), "finite"),
    "flow_prev_valid": _Layer("flow_prev_valid.png", "binary"),
    "rest_rgb": _Layer("rest_rgb.png", "rgb"),
    # rest_depth follows the depth convention (the record's `depth` covers both files).
    "rest_depth": _Layer("rest_depth.exr", "exr", "depth", ("Y",), "depth"),
    "ray_distance": _Layer("ray_distance.exr", "exr", "ray_distance", ("Y",), "depth"),
    # The damage layers (output "damage"; docs/damage.md): class by value, instance, crack
    # width in millimetres and its coverage of the pixel, 0-1.
    "damage_class": _Layer("damage_class.png", "ids", values="damage_class"),
    "damage_instance": _Layer("damage_instance.png", "ids"),
    "crack_width": _Layer("crack_width.exr", "exr", "damage", ("Y",), "depth"),
    "crack_coverage": _Layer("crack_coverage.exr", "exr", "damage", ("Y",), "fraction"),
}

#: How far a normal's length may be from 1 (float32 rounding of a unit vector is ~1e-7).
UNIT_TOLERANCE = 1e-3

#: A view as a sample lists it: (view index, copy index or None, stem, absolute paths by kind).
_Entry = tuple[int, int | None, str, dict[str, Path]]

# sample, then view and copy for a view's file, then frame for a sequence (docs/sequences.md).
_STEM = re.compile(r"^(\d+)(?:_(\d+)(?:a(\d+))?)?(?:_f(\d+))?$")


def _kind_of(relative: str) -> tuple[str, str]:
    """``(stem, kind)`` of a dataset file: ``("000003_01", "depth.exr")``."""
    name = relative.rsplit("/", 1)[-1]
    stem, _, kind = name.partition(".")
    return stem, kind


@dataclass
class Mesh:
    """A triangle mesh: ``vertices`` ``(N, 3)`` float64 world metres, ``faces`` ``(M, 3)``
    int64 vertex indices (counter-clockwise seen from outside) and ``parts`` ``(M,)`` int32
    part ids (names in the views' ``segmentation.part_ids``)."""

    vertices: np.ndarray
    faces: np.ndarray
    parts: np.ndarray | None = None

    @property
    def bounds(self) -> np.ndarray:
        """``[[min x, y, z], [max x, y, z]]`` of the vertices."""
        return np.stack([self.vertices.min(axis=0), self.vertices.max(axis=0)])


@dataclass
class Points:
    """Points on a surface: ``points`` ``(N, 3)`` float64 world metres, ``normals``
    ``(N, 3)`` float32 unit normals (outward for shmgen's closed shapes) and ``colours``
    ``(N, 3)`` uint8 sRGB, the material's albedo at each point (None in datasets written
    before points had colours)."""

    points: np.ndarray
    normals: np.ndarray
    colours: np.ndarray | None = None


def _first_bad(bad: NDArray[np.bool_], values: NDArray[Any], shown: str, rule: str) -> None:
    """:class:`DatasetError` naming the first pixel (row, column) where ``bad`` holds, its
    value and the ``rule`` it breaks; nothing if ``bad`` holds nowhere."""
    if not bad.any():
        return
    row, column = np.unravel_index(int(np.argmax(bad)), bad.shape)
    value = values[row, column]
    shown_value = value.tolist() if isinstance(value, np.ndarray) else value.item()
    raise DatasetError(
        f"{shown}: pixel (row {row}, column {column}) holds {shown_value}; {rule} "
        f"({int(bad.sum())} such pixels)"
    )


# Each check first reduces the whole array (no temporaries; NaN fails every comparison) and
# looks for the first bad pixel only when something is wrong.


def _check_depth(values: NDArray[Any], shown: str, record: Record, layer: _Layer) -> None:
    if not (values.min() >= 0 and values.max() < np.inf):
        _first_bad(~((values >= 0) & (values < np.inf)), values, shown,
                   "a distance must be finite and ≥ 0 (0 = no surface)")


def _unit_or_zero(squared: NDArray[np.floating[Any]]) -> NDArray[np.bool_]:
    """Where a squared length is 0, or that of a unit vector within UNIT_TOLERANCE (False
    for NaN and inf)."""
    within = (squared >= (1 - UNIT_TOLERANCE) ** 2) & (squared <= (1 + UNIT_TOLERANCE) ** 2)
    return np.asarray((squared == 0) | within, dtype=np.bool_)


def _check_unit(values: NDArray[Any], shown: str, record: Record, layer: _Layer) -> None:
    squared = np.einsum("...i,...i->...", values, values)
    _first_bad(~_unit_or_zero(squared), values, shown,
               f"a normal must be finite with length 1 (within {UNIT_TOLERANCE}) or be 0 (no surface)")


def _check_finite(values: NDArray[Any], shown: str, record: Record, layer: _Layer) -> None:
    if not np.isfinite(values).all():
        _first_bad(~np.all(np.isfinite(values), axis=-1), values, shown, "values must be finite")


def _check_ids(values: NDArray[Any], shown: str, record: Record, layer: _Layer) -> None:
    table = (record.get("segmentation") or {}).get(layer.ids_table)
    if isinstance(table, list):
        _first_bad(values >= len(table), values, shown,
                   f"an id must index segmentation.{layer.ids_table} of the view's record ({len(table)} entries)")


def _check_fraction(values: NDArray[Any], shown: str, record: Record, layer: _Layer) -> None:
    if not (values.min() >= 0 and values.max() <= 1):
        _first_bad(~((values >= 0) & (values <= 1)), values, shown, "a share must lie in [0, 1]")


def _check_damage_class(values: NDArray[Any], shown: str, record: Record, layer: _Layer) -> None:
    classes = (record.get("damage") or {}).get("classes")
    count = len(classes) if isinstance(classes, list) else 7
    _first_bad(values >= count, values, shown,
               f"a damage class must index damage.classes of the view's record ({count} entries)")


#: The value checks of :attr:`_Layer.values`: (values, file shown, record, layer) → None.
_VALUE_CHECKS: dict[str, Callable[[NDArray[Any], str, Record, _Layer], None]] = {"depth": _check_depth, "unit": _check_unit, "finite": _check_finite, "ids": _check_ids, "fraction": _check_fraction, "damage_class": _check_damage_class}


@dataclass
class Verification:
    """What :meth:`Dataset.verify` found.

    ``checked``: how many files had their size and BLAKE3 compared with the manifest's
    ``hashes``; ``problems``: relative path → what is wrong with it (truncated, altered,
    missing, a link…); ``unhashed``: the files the manifest has no hash for (a dataset written
    by a shmgen before content hashes). ``ok`` is True when every file was hashed and matched.
    """

    checked: int = 0
    problems: dict[str, str] = field(default_factory=dict)
    unhashed: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.problems and not self.unhashed

    def __str__(self) -> str:
        lines = [f"{self.checked} files checked, {len(self.problems)} with problems, "
                 f"{len(self.unhashed)} without a hash in the manifest"]
        lines += [f"  {problem}" for problem in self.problems.values()]
        return "\n".join(lines)


class _Output:
    """A per-view output declared on :class:`View` as a typed, read-only attribute:
    ``view.depth`` is ``view.load("depth")`` (see :data:`LAYERS`)."""

    def __init__(self) -> None:
        self.name = ""

    def __set_name__(self, owner: type, name: str) -> None:
        if name not in LAYERS:
            raise TypeError(f"View.{name}: no such output in LAYERS")
        self.name = name
        self.__doc__ = f"The view's {name!r} output (see LAYERS)."

    @overload
    def __get__(self, view: None, owner: type) -> _Output: ...

    @overload
    def __get__(self, view: View, owner: type) -> NDArray[Any]: ...

    def __get__(self, view: View | None, owner: type) -> _Output | NDArray[Any]:
        return self if view is None else view.load(self.name)


class _CameraMatrix:
    """One of the camera's arrays declared on :class:`View` as a typed, read-only attribute:
    ``view.K`` is ``view.camera.K``."""

    def __init__(self, doc: str) -> None:
        self.name = ""
        self.__doc__ = doc

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    @overload
    def __get__(self, view: None, owner: type) -> _CameraMatrix: ...

    @overload
    def __get__(self, view: View, owner: type) -> NDArray[np.float64]: ...

    def __get__(self, view: View | None, owner: type) -> _CameraMatrix | NDArray[np.float64]:
        if view is None:
            return self
        return np.asarray(getattr(view.camera, self.name), dtype=np.float64)


class View:
    """One view of a sample, clean or an augmented copy of it, and everything it has.

    Metadata: ``sample``, ``view``, ``copy`` (None for the clean view), ``stem``
    (``000003_01`` or ``000003_01a0``), ``files`` (absolute paths by kind: ``"rgb.png"``,
    ``"depth.exr"``, ``"json"``…), ``record`` (the view's JSON), ``camera`` (:class:`Camera`),
    and from it ``K``, ``c2w`` (OpenCV axes), ``c2w_opengl``, ``w2c`` and ``distortion``
    (``k1, k2, p1, p2, k3``).

    Clean or copy: ``is_copy`` (False for a clean view), ``clean_stem`` (the stem of the clean
    view a copy was made from: same sample, same view index, same scene) and
    ``augmentation`` (an :class:`Augmentation`: copy index, ``"exact"`` or ``"image"`` mode,
    the operations with their drawn values; None for a clean view).

    Structures by name: ``structures`` (a :class:`Structures` mapping: ``view.structures["silo"]``
    gives its ``instance_id``, ``part_ids``, ``labels``…) and ``labels`` (each structure's
    mechanics labels by name: ``view.labels["beam"]["max_deflection"]``; None for an assembly);
    ``prompt`` (the first structure's texture prompt) and ``prompts`` (each structure's).

    Images (see :data:`LAYERS` for shapes and dtypes), read on first access and kept:
    ``rgb``, ``depth``, ``mask``, ``parts``, ``instances``, ``cracks``, ``erased``, ``valid``,
    ``normals``, ``displacement``, ``flow``, ``flow_valid``, ``flow_next``, ``flow_next_valid``,
    ``flow_prev``, ``flow_prev_valid``, ``rest_rgb``, ``rest_depth``, ``ray_distance``,
    ``damage_class``, ``damage_instance``, ``crack_width``,
    ``crack_coverage``. Asking for one the view does not have raises :class:`MissingFileError`
    naming the view and the output; :meth:`has` and :attr:`layers` tell which it has.
    """

    K = _CameraMatrix("Intrinsics, 3 × 3, pixels.")
    c2w = _CameraMatrix("Camera → world, OpenCV axes, 4 × 4.")
    c2w_opengl = _CameraMatrix("Camera → world, OpenGL axes, 4 × 4.")
    w2c = _CameraMatrix("World → camera, OpenCV axes, 4 × 4.")
    distortion = _CameraMatrix("The lens: (k1, k2, p1, p2, k3).")

    rgb = _Output()
    depth = _Output()
    mask = _Output()
    parts = _Output()
    instances = _Output()
    cracks = _Output()
    erased = _Output()
    valid = _Output()
    normals = _Output()
    displacement = _Output()
    flow = _Output()
    flow_valid = _Output()
    flow_next = _Output()
    flow_next_valid = _Output()
    flow_prev = _Output()
    flow_prev_valid = _Output()
    rest_rgb = _Output()
    rest_depth = _Output()
    ray_distance = _Output()
    damage_class = _Output()
    damage_instance = _Output()
    crack_width = _Output()
    crack_coverage = _Output()

    def __init__(self, root: Path, sample: int, view: int, copy: int | None, stem: str,
                 files: dict[str, Path], source: DatasetFiles | None = None):
        self.root = root
        self.sample: int = sample
        self.view: int = view
        self.copy: int | None = copy
        self.stem: str = stem
        self.files = files
        self._source = source or DatasetFiles(root)
        self._images: dict[str, NDArray[Any]] = {}
        self._record: Record | None = None
        self._camera: Camera | None = None
        self._structures: Structures | None = None

    def __repr__(self) -> str:
        return f"View({self.stem!r}, layers={self.layers})"

    @property
    def layers(self) -> list[str]:
        """The names of the per-pixel outputs this view has files for, in :data:`LAYERS` order."""
        return [name for name, layer in LAYERS.items() if layer.kind in self.files]

    def has(self, name: str) -> bool:
        """Whether the view has the output ``name`` (``"normals"``, ``"flow"``…)."""
        return LAYERS[name].kind in self.files

    def path(self, name: str) -> Path:
        """The file of output ``name``; :class:`MissingFileError` if the view has none."""
        layer = LAYERS.get(name)
        if layer is None:
            raise KeyError(f"unknown output {name!r} (known: {', '.join(LAYERS)})")
        try:
            return self.files[layer.kind]
        except KeyError:
            raise MissingFileError(
                f"view {self.stem} of {self.root} has no {name!r} file ({self.stem}.{layer.kind}); "
                f"it has {', '.join(self.layers) or 'no images'}; add \"{name}\" to the recipe's outputs"
            ) from None

    @property
    def record(self) -> Record:
        """The view's JSON record (``shmgen.view/2``, or ``/1`` of older datasets)."""
        if self._record is None:
            try:
                path = self.files["json"]
            except KeyError:
                raise MissingFileError(f"view {self.stem} of {self.root} has no record (.json)") from None
            record = self._source.read_json(_relative(self.root, path))
            if record.get("schema") not in VIEW_SCHEMAS:
                raise DatasetError(f"{path}: schema {record.get('schema')!r}; this reader reads {' or '.join(map(repr, VIEW_SCHEMAS))}")
            self._record = record
        return self._record

    @property
    def camera(self) -> Camera:
        """The camera the view's files agree with."""
        if self._camera is None:
            try:
                self._camera = Camera.from_record(self.record)
            except (KeyError, ValueError, TypeError) as error:
                raise DatasetError(f"{self.files['json']}: {error}") from None
        return self._camera

    @property
    def is_copy(self) -> bool:
        """Whether the view is an augmented copy (its stem ends in ``a{copy}``)."""
        return self.copy is not None

    @property
    def clean_stem(self) -> str:
        """The stem of the clean view this view is, or was copied from: ``000003_01`` for
        ``000003_01`` and for its copies ``000003_01a0``, ``000003_01a1``… The clean view
        exists unless the recipe's augment had ``keep_clean: false``."""
        return f"{self.sample:06}_{self.view:02}"

    @property
    def augmentation(self) -> Augmentation | None:
        """How the copy was made (None for a clean view), checked against the file name."""
        value = self.record.get("augmentation")
        shown = str(self.files["json"])
        if value is None:
            if self.copy is not None:
                raise DatasetError(f"{shown}: a copy's record (a{self.copy}) without augmentation")
            return None
        augmentation = Augmentation.from_record(value, shown)
        if augmentation.copy != self.copy:
            raise DatasetError(f"{shown}: augmentation.copy is {augmentation.copy}, the file name says {self.copy}")
        return augmentation

    @property
    def structures(self) -> Structures:
        """The sample's structures by name, from ``scene.structures`` and ``segmentation``."""
        if self._structures is None:
            self._structures = Structures.from_record(self.record, str(self.files.get("json", self.stem)))
        return self._structures

    @property
    def labels(self) -> dict[str, Record | None]:
        """Each structure's mechanics labels by name (``max_deflection``, ``loads``,
        ``theory``…), None for a structure without them (an assembly)."""
        return self.structures.labels

    @property
    def prompts(self) -> dict[str, str | None]:
        """Each structure's texture prompt by name (``material.prompt`` of its record; None
        for a structure given a plain colour)."""
        return self.structures.prompts

    @property
    def prompt(self) -> str | None:
        """The texture prompt of the view's first structure (the only one in the paper's
        recipes): ``"A photo of cracked timber for construction"``; None without one."""
        return next(iter(self.prompts.values()), None)

    def structure_mask(self, name: str) -> NDArray[np.bool_]:
        """Where the view's ``instances`` image shows the structure ``name``."""
        structure: Structure = self.structures[name]
        return structure.mask(self.instances)

    @property
    def tracks(self) -> NDArray[np.float64]:
        """This frame's true point tracks (output ``point_tracks``; docs/sequences.md):
        float64 ``(Q, 3)``, rows ``x, y, state`` (1 seen, 0 hidden or outside, -1 no image)
        for the first frame's query points; :meth:`Sample.point_tracks` stacks the frames."""
        path = self.files.get("tracks.npy")
        if path is None:
            raise MissingFileError(
                f"view {self.stem} of {self.root} has no point tracks ({self.stem}.tracks.npy); "
                f"add \"point_tracks\" to the recipe's outputs (sequences only)"
            )
        size = self._size(self._source.limits)
        # A query per pixel at most, 24 bytes each, and NumPy's header.
        bound = 4096 + 24 * size[0] * size[1]
        data = self._source.read(_relative(self.root, path), bound, "point tracks (a query per pixel at most)")
        return decode_tracks(data, str(path))

    def load(self, name: str) -> NDArray[Any]:
        """The per-pixel output ``name`` as an array (read once, then kept)."""
        if name not in self._images:
            self._images[name] = self._read(name)
        return self._images[name]

    def _read(self, name: str) -> NDArray[Any]:
        path = self.path(name)  # raises for unknown and missing outputs
        layer = LAYERS[name]
        limits = self._source.limits
        size = self._size(limits)
        relative, shown = _relative(self.root, path), str(path)
        values: NDArray[Any]
        if layer.read == "exr":
            convention = self.record.get(layer.convention or "") or {}
            channels = convention.get("channels") or (
                [convention["channel"]] if "channel" in convention else list(layer.channels)
            )
            data = self._read_image(relative, size, len(channels), 4)
            values = decode_exr(data, shown, channels, size, limits)
        else:
            formats = layer.png_formats
            data = self._read_image(relative, size, *max(formats.values(), key=lambda f: f[0] * f[1]))
            values = decode_png(data, shown, formats, size, limits)
            if layer.read == "binary":
                _first_bad((values != 0) & (values != 255), values, shown, "a mask holds 0 and 255 only")
                values = values == 255
            elif layer.read == "ids":
                values = values.astype(np.int32)
        if layer.values:
            _VALUE_CHECKS[layer.values](values, shown, self.record, layer)
        return values

    def _size(self, limits: Limits) -> tuple[int, int]:
        """The camera's ``(width, height)``, the size every image of the view must have."""
        camera = self.camera
        if not (camera.width <= limits.max_side and camera.height <= limits.max_side):
            raise DatasetError(
                f"{self.files['json']}: camera {camera.width}×{camera.height} pixels; each side "
                f"must be at most {limits.max_side} (Limits.max_side)"
            )
        return camera.width, camera.height

    def _read_image(self, relative: str, size: tuple[int, int], channels: int, sample_bytes: int) -> bytes:
        """The bytes of an image file of the view, bounded by what its size allows."""
        bound = self._source.limits.image_bytes(*size, channels, sample_bytes)
        what = f"a {size[0]}×{size[1]} image of {channels} × {sample_bytes}-byte samples (Limits.image_bytes)"
        return self._source.read(relative, bound, what)


def _relative(root: Path, path: Path) -> str:
    """``path`` below ``root`` as the manifest names it."""
    return path.relative_to(root).as_posix()


class Sample:
    """One sample: its views (clean and augmented copies, in file-name order) and its own
    files: ``mesh()`` and ``rest_mesh()`` (loaded and unloaded meshes, the same faces over
    vertices in the same order) and ``points()`` (points uniform by area on the loaded
    surface). ``record`` is its first view's JSON (the scene, labels and light are the
    sample's); ``structures`` and ``labels`` as for :class:`View`."""

    def __init__(self, root: Path, index: int, entries: list[_Entry], files: dict[str, Path],
                 source: DatasetFiles | None = None):
        self.root = root
        self.index = index
        self._entries = entries  # (view, copy, stem, files) in order
        self.files = files  # absolute paths by kind: "mesh.ply", …
        self._source = source or DatasetFiles(root)

    def __repr__(self) -> str:
        return f"Sample({self.index}, views={len(self._entries)}, files={sorted(self.files)})"

    @property
    def views(self) -> list[View]:
        """Every view of the sample, clean views and copies (new :class:`View` objects)."""
        return [View(self.root, self.index, v, c, stem, files, self._source)
                for v, c, stem, files in self._entries]

    def clean_views(self) -> list[View]:
        """The sample's clean (not augmented) views."""
        return [v for v in self.views if not v.is_copy]

    def copies(self) -> list[View]:
        """The sample's augmented copies."""
        return [v for v in self.views if v.is_copy]

    def clean_view(self, view: View) -> View:
        """The clean view ``view`` is a copy of (``view`` itself if it is clean):
        :class:`MissingFileError` if the dataset kept no clean views (``keep_clean: false``)."""
        for candidate in self.clean_views():
            if candidate.stem == view.clean_stem:
                return candidate
        raise MissingFileError(
            f"sample {self.index} of {self.root} has no clean view {view.clean_stem} "
            f"(the recipe's augment has keep_clean: false); {view.stem} is all there is"
        )

    @cached_property
    def record(self) -> Record:
        """Its first view's JSON record (the scene, labels and light are the sample's)."""
        if not self._entries:
            raise MissingFileError(f"sample {self.index} of {self.root} has no views")
        return self.views[0].record

    @cached_property
    def structures(self) -> Structures:
        """The sample's structures by name (see :class:`View`)."""
        return self.views[0].structures if self._entries else Structures([])

    @property
    def labels(self) -> dict[str, Record | None]:
        """Each structure's mechanics labels by name (None for an assembly)."""
        return self.structures.labels

    def path(self, kind: str) -> Path:
        """The sample's file of ``kind`` (``"mesh.ply"``, ``"rest.ply"``, ``"mesh.glb"``,
        ``"points.ply"``); :class:`MissingFileError` naming the output if it has none."""
        try:
            return self.files[kind]
        except KeyError:
            output = {"mesh.ply": "mesh", "rest.ply": "mesh", "mesh.glb": "mesh_gltf",
                      "points.ply": "points"}.get(kind, kind)
            raise MissingFileError(
                f"sample {self.index} of {self.root} has no {kind} file "
                f"(it has {', '.join(sorted(self.files)) or 'none'}); add \"{output}\" to the recipe's outputs"
            ) from None

    def point_tracks(self, view: int = 0, copy: int | None = None) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """The true point tracks of view ``view`` (augmented copy ``copy``, None for the clean
        view) over the sequence, TAP-Vid style: ``tracks`` ``(N, T, 2)`` float64 (x, y in
        pixels, (0.5, 0.5) the top-left pixel's centre) and ``occluded`` ``(N, T)`` bool, for
        the N query points of the first frame over its T frames (docs/sequences.md)."""
        frames = [v for v in self.views if v.view == view and v.copy == copy]
        if not frames:
            raise MissingFileError(f"sample {self.index} of {self.root} has no view {view} (copy {copy})")
        shown = f"sample {self.index} of {self.root}, view {view}"
        return assemble([f.tracks for f in frames], shown)

    def _ply(self, kind: str) -> tuple[Ply, NDArray[np.float64]]:
        """The sample's PLY file of ``kind``, read within ``Limits.mesh_bytes``, its
        vertices checked finite."""
        path = self.path(kind)
        limits = self._source.limits
        data = self._source.read(_relative(self.root, path), limits.mesh_bytes, "a PLY file (Limits.mesh_bytes)")
        ply = parse_ply(data, str(path))
        xyz = ply.xyz()
        _first_vertex(~np.all(np.isfinite(xyz), axis=1), xyz, ply.path, "coordinates must be finite")
        return ply, xyz

    def _mesh(self, kind: str) -> Mesh:
        ply, vertices = self._ply(kind)
        faces = ply["face"]["vertex_indices"]
        if not isinstance(faces, np.ndarray) or faces.ndim != 2 or faces.shape[1] != 3:
            raise DatasetError(f"{ply.path}: faces are not all triangles")
        faces = faces.astype(np.int64)
        outside = np.any((faces < 0) | (faces >= len(vertices)), axis=1)
        if outside.any():
            face = int(np.argmax(outside))
            raise DatasetError(
                f"{ply.path}: face {face} is {faces[face].tolist()}; vertex indices must be 0…{len(vertices) - 1}"
            )
        parts = ply["face"]["part"].astype(np.int32) if "part" in ply["face"] else None
        return Mesh(vertices, faces, parts)

    def mesh(self) -> Mesh:
        """The loaded (deformed) mesh, ``{sample:06}.mesh.ply``."""
        return self._mesh("mesh.ply")

    def rest_mesh(self) -> Mesh:
        """The unloaded mesh, ``{sample:06}.rest.ply``: vertex k is where vertex k of
        :meth:`mesh` was before loading."""
        return self._mesh("rest.ply")

    def points(self) -> Points:
        """Points uniform by area on the loaded surface, ``{sample:06}.points.ply``."""
        ply, xyz = self._ply("points.ply")
        vertex = ply["vertex"]
        normals = np.stack([vertex[c] for c in ("nx", "ny", "nz")], axis=1).astype(np.float32)
        squared = np.einsum("ij,ij->i", normals, normals)
        _first_vertex(~_unit_or_zero(squared) | (squared == 0), normals, ply.path,
                      f"a normal must be finite with length 1 (within {UNIT_TOLERANCE})")
        has_colours = all(c in vertex for c in ("red", "green", "blue"))
        colours = (np.stack([vertex[c] for c in ("red", "green", "blue")], axis=1).astype(np.uint8)
                   if has_colours else None)
        return Points(xyz, normals, colours)


def _first_vertex(bad: NDArray[np.bool_], values: NDArray[Any], path: Path, rule: str) -> None:
    """:class:`DatasetError` naming the first vertex where ``bad`` holds, and its values."""
    if bad.any():
        k = int(np.argmax(bad))
        raise DatasetError(f"{path}: vertex {k} holds {values[k].tolist()}; {rule} ({int(bad.sum())} such vertices)")


class Dataset(Sequence[View]):
    """A shmgen dataset: a sequence of its views (clean views and augmented copies, as the
    manifest lists them, in sample order), with its samples.

    >>> data = Dataset("out/quickstart")
    >>> view = data[0]; view.rgb.shape, view.depth.dtype, view.K
    >>> for sample in data.samples: mesh = sample.mesh()

    ``complete=True`` (the default) refuses a dataset whose manifest does not yet list every
    sample of ``run.json`` (a run still going, or stopped); ``complete=False`` reads the
    samples finished so far. ``copies=False`` leaves augmented copies out of the sequence.
    ``limits`` bounds what is read (:class:`Limits`; the defaults suit any dataset shmgen
    writes). Raises ``FileNotFoundError`` for a folder that is not a shmgen dataset, and
    :class:`DatasetError` (a ``ValueError``) for a manifest listing files that are missing,
    not of its sample, outside the dataset, links, not regular files or not of their hashed
    size. :meth:`verify` checks every file's BLAKE3 against the manifest's ``hashes``.
    """

    def __init__(self, root: str | os.PathLike[str], *, complete: bool = True, copies: bool = True,
                 limits: Limits | None = None):
        self.root = Path(root)
        self.limits = limits or Limits()
        if not self.root.is_dir():
            raise FileNotFoundError(f"{self.root}: no such folder")
        self._files = DatasetFiles(self.root, self.limits)
        try:
            self.run = self._files.read_json("run.json")
        except FileNotFoundError:
            raise FileNotFoundError(
                f"{self.root}: not a shmgen dataset (no run.json; give the folder `shmgen run --out` wrote)"
            ) from None
        run_path = self.root / "run.json"
        if self.run.get("schema") != RUN_SCHEMA:
            raise DatasetError(f"{run_path}: schema {self.run.get('schema')!r}; this reader reads {RUN_SCHEMA!r}")
        total = (self.run.get("dataset") or {}).get("samples")
        if type(total) is not int or total < 0:
            raise DatasetError(f"{run_path}: dataset.samples is {total!r}, not a count")
        self._listed = self._read_manifest()
        first_missing = _first_missing(self._listed, total)
        if complete and first_missing is not None:
            found = sum(1 for index in self._listed if 0 <= index < total)
            raise DatasetError(
                f"{self.root}: the dataset is not finished: manifest.jsonl lists {found} "
                f"of {total} samples (sample {first_missing} is missing); run `shmgen run` again to "
                f"finish it, or pass complete=False to read the finished samples"
            )
        self.samples = [self._sample(index, self._listed[index], copies) for index in sorted(self._listed)]
        self._files.check_listed(self._listed_files())
        self._views = [(sample, entry) for sample in self.samples for entry in sample._entries]

    @property
    def name(self) -> str:
        """The dataset's name, as the recipe gave it."""
        return str(self.run["dataset"]["name"])

    @property
    def outputs(self) -> list[str]:
        """The outputs the dataset writes, by name (``rgb``, ``depth``, ``mesh``…)."""
        return [name for name, on in self.run["dataset"]["outputs"].items() if on]

    def __len__(self) -> int:
        return len(self._views)

    @overload
    def __getitem__(self, index: int) -> View: ...

    @overload
    def __getitem__(self, index: slice) -> list[View]: ...

    def __getitem__(self, index: int | slice) -> View | list[View]:
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        sample, (view, copy, stem, files) = self._views[index]
        return View(self.root, sample.index, view, copy, stem, files, self._files)

    def __iter__(self) -> Iterator[View]:
        for i in range(len(self)):
            yield self[i]

    def __repr__(self) -> str:
        return f"Dataset({str(self.root)!r}, samples={len(self.samples)}, views={len(self)})"

    def split(self, by: str | Callable[[View], Any] = "sample", *, holdout: Any = None,
              fraction: float | None = None, seed: int = 0) -> Split:
        """The views in two parts, train and test, whole groups at a time: see
        :func:`shmgen_data.splits.split` (``by`` a key name, a dotted record path or a
        function; ``holdout`` the key values held out, or ``fraction`` of the groups drawn
        deterministically)."""
        from .splits import split
        return split(self, by, holdout=holdout, fraction=fraction, seed=seed)

    def point_tracks(self, sample: int, view: int = 0, copy: int | None = None) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """The true point tracks of ``view`` of ``sample``: see :meth:`Sample.point_tracks`."""
        return self.sample(sample).point_tracks(view, copy)

    def sample(self, index: int) -> Sample:
        """The sample with index ``index`` (its number, not its position)."""
        for sample in self.samples:
            if sample.index == index:
                return sample
        raise KeyError(f"{self.root}: no sample {index} in the manifest")

    def _read_manifest(self) -> dict[int, list[str]]:
        """Sample index → the files its line lists (the first line of a sample counts), read
        line by line within ``Limits.manifest_bytes`` and ``manifest_line_bytes``; each
        line's ``hashes``, if it has them, go to the files' expected sizes and BLAKE3s."""
        path = self.root / "manifest.jsonl"
        limits = self.limits
        listed = {}
        try:
            manifest = self._files.open("manifest.jsonl", limits.manifest_bytes, "manifest.jsonl (Limits.manifest_bytes)")
        except FileNotFoundError:
            raise FileNotFoundError(f"{self.root}: the dataset has no manifest.jsonl (no sample finished yet)") from None
        with manifest:
            # What follows the final newline (a line being appended) is left out by lines().
            for number, line in enumerate(manifest.lines(limits.manifest_line_bytes, "a manifest line (Limits.manifest_line_bytes)"), start=1):
                where = f"{path}: line {number}"
                try:
                    entry = json.loads(line)
                    if isinstance(entry, dict) and "unit" in entry and "sample" not in entry:
                        # Frames of a sample not finished yet (`run --frames-per-unit`): the
                        # sample's own line follows once all its frames are written.
                        continue
                    index, files = int(entry["sample"]), entry["files"]
                    if not isinstance(files, list) or not all(isinstance(f, str) for f in files):
                        raise TypeError("files is not a list of names")
                except (ValueError, KeyError, TypeError, RecursionError):
                    raise DatasetError(f"{where} does not parse as a manifest line") from None
                if index in listed:
                    continue
                for relative in files:
                    check_relative(relative, f"{path}: sample {index}")
                listed[index] = files
                if "hashes" in entry:
                    self._files.hashes.update(parse_hashes(entry["hashes"], files, where))
        return listed

    def _listed_files(self) -> list[str]:
        """Every file the manifest lists for the samples read, once each, in sample order."""
        return [relative for sample in self.samples for relative in sorted(set(self._listed[sample.index]))]

    def verify(self) -> Verification:
        """Compares every file the manifest lists (for the samples read) with its ``hashes``
        entry: its size, then its BLAKE3 (the whole file is read, in chunks). Returns a
        :class:`Verification` naming the truncated, altered or missing files, and the files
        without a hash (a dataset written before shmgen hashed its files)."""
        result = Verification()
        for relative in self._listed_files():
            if relative not in self._files.hashes:
                result.unhashed.append(relative)
                continue
            result.checked += 1
            problem = self._files.hash_problem(relative)
            if problem is not None:
                result.problems[relative] = problem
        return result

    def _sample(self, index: int, files: list[str], copies: bool) -> Sample:
        views: dict[tuple[int, int, int], _Entry] = {}
        own: dict[str, Path] = {}
        where = f"{self.root}/manifest.jsonl: sample {index}"
        for relative in sorted(set(files)):  # plain relative paths (checked by _read_manifest)
            path = self.root / relative
            stem, kind = _kind_of(relative)
            match = _STEM.match(stem)
            if match is None or int(match.group(1)) != index:
                raise DatasetError(f"{where} lists {relative}, not a file of sample {index}")
            frame = -1 if match.group(4) is None else int(match.group(4))
            if match.group(2) is None:
                # A frame's own files (meshes) are keyed by frame: "f0042.mesh.ply".
                own[kind if frame < 0 else f"f{frame:04}.{kind}"] = path
                continue
            view = int(match.group(2))
            copy = None if match.group(3) is None else int(match.group(3))
            key = (view, -1 if copy is None else copy, frame)
            views.setdefault(key, (view, copy, stem, {}))[3][kind] = path
        entries = [views[key] for key in sorted(views) if copies or views[key][1] is None]
        return Sample(self.root, index, entries, own, self._files)


def _first_missing(listed: dict[int, list[str]], total: int) -> int | None:
    """The first sample index below ``total`` that ``listed`` lacks (without counting up to
    ``total``, which comes from run.json and could be anything)."""
    expected = 0
    for index in sorted(i for i in listed if 0 <= i < total):
        if index != expected:
            return expected
        expected += 1
    return expected if expected < total else None
