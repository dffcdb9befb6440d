"""A shmgen dataset as Python objects: its samples, their views and their files.

What is read comes from ``manifest.jsonl`` (one line per finished sample, listing every file)
and from each view's JSON record; file names are parsed as the layout states them:
``{sample:06}_{view:02}.{kind}`` for a view, ``…_{view:02}a{copy}.{kind}`` for an augmented
copy and ``{sample:06}.{kind}`` for a sample's own files (meshes, points).

Everything is read lazily: opening a dataset reads ``run.json`` and the manifest only; a
view's record, camera and images are read when first asked for and kept by that
:class:`View` object (so ``view.depth`` twice reads the file once). The dataset hands out a
new :class:`View` at each index access, so iterating over a large dataset keeps nothing.
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Iterator, Sequence

import numpy as np

from .camera import Camera
from .io import read_exr, read_ply, read_png

__all__ = ["Dataset", "Sample", "View", "Mesh", "Points", "LAYERS", "MissingFileError"]

RUN_SCHEMA = "shmgen.run/1"
VIEW_SCHEMA = "shmgen.view/1"


class MissingFileError(FileNotFoundError):
    """A view or sample lacks the file asked for (the dataset was not asked to write it)."""


@dataclass(frozen=True)
class _Layer:
    """How one per-view output is stored: its file kind, and how its values are read."""

    kind: str  # the file name after the stem: "depth.exr"
    read: str  # "rgb", "binary", "ids" or "exr"
    convention: str | None = None  # the record's object naming its EXR channels
    channels: tuple = ()  # default EXR channels, if the record does not name them


#: Every per-view output, by name: ``rgb`` and ``rest_rgb`` are ``(H, W, 3)`` uint8; ``depth``,
#: ``rest_depth`` and ``ray_distance`` ``(H, W)`` float32 metres (0 = no surface); ``normals``
#: and ``displacement`` ``(H, W, 3)`` float32; ``flow`` ``(H, W, 2)`` float32 pixels (U, V);
#: the masks ``mask``, ``cracks``, ``erased``, ``valid`` and ``flow_valid`` ``(H, W)`` bool
#: (True where the file holds 255); ``parts`` and ``instances`` ``(H, W)`` int32 ids.
LAYERS = {
    "rgb": _Layer("rgb.png", "rgb"),
    "depth": _Layer("depth.exr", "exr", "depth", ("Z",)),
    "mask": _Layer("mask.png", "binary"),
    "parts": _Layer("parts.png", "ids"),
    "instances": _Layer("instances.png", "ids"),
    "cracks": _Layer("cracks.png", "binary"),
    "erased": _Layer("erased.png", "binary"),
    "valid": _Layer("valid.png", "binary"),
    "normals": _Layer("normals.exr", "exr", "normals", ("X", "Y", "Z")),
    "displacement": _Layer("displacement.exr", "exr", "displacement", ("X", "Y", "Z")),
    "flow": _Layer("flow.exr", "exr", "flow", ("U", "V")),
    "flow_valid": _Layer("flow_valid.png", "binary"),
    "rest_rgb": _Layer("rest_rgb.png", "rgb"),
    # rest_depth follows the depth convention (the record's `depth` covers both files).
    "rest_depth": _Layer("rest_depth.exr", "exr", "depth", ("Z",)),
    "ray_distance": _Layer("ray_distance.exr", "exr", "ray_distance", ("Y",)),
}

_STEM = re.compile(r"^(\d+)(?:_(\d+)(?:a(\d+))?)?$")


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
    """Points on a surface: ``points`` ``(N, 3)`` float64 world metres and ``normals``
    ``(N, 3)`` float32 unit normals (outward for shmgen's closed shapes)."""

    points: np.ndarray
    normals: np.ndarray


def _read_json(path: Path) -> dict:
    try:
        with open(path, "rb") as f:
            return json.load(f)
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: no such file") from None
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: does not parse as JSON ({error})") from None


class View:
    """One view of a sample (or one augmented copy of it) and everything it has.

    Metadata: ``sample``, ``view``, ``copy`` (None for the clean view), ``stem``
    (``000003_01`` or ``000003_01a0``), ``files`` (absolute paths by kind: ``"rgb.png"``,
    ``"depth.exr"``, ``"json"``…), ``record`` (the view's JSON), ``camera`` (:class:`Camera`),
    and from it ``K``, ``c2w`` (OpenCV axes), ``c2w_opengl``, ``w2c`` and ``distortion``
    (``k1, k2, p1, p2, k3``). ``structures`` and ``labels``: the sample's structures as
    recorded, and the mechanics' labels of each (``max_deflection``, ``loads``, ``theory``…;
    None for a structure without labels).

    Images (see :data:`LAYERS` for shapes and dtypes), read on first access and kept:
    ``rgb``, ``depth``, ``mask``, ``parts``, ``instances``, ``cracks``, ``erased``, ``valid``,
    ``normals``, ``displacement``, ``flow``, ``flow_valid``, ``rest_rgb``, ``rest_depth``,
    ``ray_distance``. Asking for one the view does not have raises :class:`MissingFileError`
    naming the view and the output; :meth:`has` and :attr:`layers` tell which it has.
    """

    def __init__(self, root: Path, sample: int, view: int, copy: int | None, stem: str,
                 files: dict):
        self.root = root
        self.sample = sample
        self.view = view
        self.copy = copy
        self.stem = stem
        self.files = files
        self._cache: dict = {}

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
    def record(self) -> dict:
        """The view's JSON record (``shmgen.view/1``)."""
        if "record" not in self._cache:
            try:
                path = self.files["json"]
            except KeyError:
                raise MissingFileError(f"view {self.stem} of {self.root} has no record (.json)") from None
            record = _read_json(path)
            if record.get("schema") != VIEW_SCHEMA:
                raise ValueError(f"{path}: schema {record.get('schema')!r}; this reader reads {VIEW_SCHEMA!r}")
            self._cache["record"] = record
        return self._cache["record"]

    @property
    def camera(self) -> Camera:
        """The camera the view's files agree with."""
        if "camera" not in self._cache:
            try:
                self._cache["camera"] = Camera.from_record(self.record)
            except (KeyError, ValueError) as error:
                raise ValueError(f"{self.files['json']}: {error}") from None
        return self._cache["camera"]

    K = property(lambda self: self.camera.K, doc="Intrinsics, 3 × 3, pixels.")
    c2w = property(lambda self: self.camera.c2w, doc="Camera → world, OpenCV axes, 4 × 4.")
    c2w_opengl = property(lambda self: self.camera.c2w_opengl, doc="Camera → world, OpenGL axes.")
    w2c = property(lambda self: self.camera.w2c, doc="World → camera, OpenCV axes, 4 × 4.")
    distortion = property(lambda self: self.camera.distortion, doc="(k1, k2, p1, p2, k3).")

    @property
    def structures(self) -> list[dict]:
        """The sample's structures as recorded (``scene.structures``)."""
        return self.record["scene"]["structures"]

    @property
    def labels(self) -> list[dict | None]:
        """Per structure, the mechanics' labels (``max_deflection``, ``loads``, ``theory``…),
        None for a structure without them (an assembly)."""
        return [s.get("labels") for s in self.structures]

    def load(self, name: str) -> np.ndarray:
        """The per-pixel output ``name`` as an array (read once, then kept)."""
        if name not in self._cache:
            self._cache[name] = self._read(name)
        return self._cache[name]

    def _read(self, name: str) -> np.ndarray:
        path = self.path(name)  # raises for unknown and missing outputs
        layer = LAYERS[name]
        if layer.read == "exr":
            convention = self.record.get(layer.convention) or {}
            channels = convention.get("channels") or (
                [convention["channel"]] if "channel" in convention else list(layer.channels)
            )
            values = read_exr(path, channels)
        else:
            values = read_png(path)
            if layer.read == "rgb":
                if values.ndim != 3 or values.shape[2] != 3:
                    raise ValueError(f"{path}: an RGB image is expected, it has shape {values.shape}")
            elif values.ndim != 2:
                raise ValueError(f"{path}: a one-channel image is expected, it has shape {values.shape}")
            elif layer.read == "binary":
                if np.any((values != 0) & (values != 255)):
                    raise ValueError(f"{path}: a mask holds 0 and 255 only")
                values = values == 255
            else:
                values = values.astype(np.int32)
        expected = (self.camera.height, self.camera.width)
        if values.shape[:2] != expected:
            raise ValueError(f"{path}: {values.shape[1]}×{values.shape[0]} pixels, the camera has {expected[1]}×{expected[0]}")
        return values


def _layer_property(name: str):
    return property(lambda self: self.load(name), doc=f"The view's {name!r} output (see LAYERS).")


for _name in LAYERS:
    setattr(View, _name, _layer_property(_name))


class Sample:
    """One sample: its views (clean and augmented copies, in file-name order) and its own
    files: ``mesh()`` and ``rest_mesh()`` (loaded and unloaded meshes, the same faces over
    vertices in the same order) and ``points()`` (points uniform by area on the loaded
    surface). ``record`` is its first view's JSON (the scene, labels and light are the
    sample's); ``structures`` and ``labels`` as for :class:`View`."""

    def __init__(self, root: Path, index: int, entries: list, files: dict):
        self.root = root
        self.index = index
        self._entries = entries  # (view, copy, stem, files) in order
        self.files = files  # absolute paths by kind: "mesh.ply", …

    def __repr__(self) -> str:
        return f"Sample({self.index}, views={len(self._entries)}, files={sorted(self.files)})"

    @property
    def views(self) -> list[View]:
        """Every view of the sample, clean views and copies (new :class:`View` objects)."""
        return [View(self.root, self.index, v, c, stem, files) for v, c, stem, files in self._entries]

    def clean_views(self) -> list[View]:
        """The sample's clean (not augmented) views."""
        return [v for v in self.views if v.copy is None]

    @cached_property
    def record(self) -> dict:
        if not self._entries:
            raise MissingFileError(f"sample {self.index} of {self.root} has no views")
        return self.views[0].record

    @property
    def structures(self) -> list[dict]:
        return self.record["scene"]["structures"]

    @property
    def labels(self) -> list[dict | None]:
        return [s.get("labels") for s in self.structures]

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

    def _mesh(self, kind: str) -> Mesh:
        ply = read_ply(self.path(kind))
        faces = ply["face"]["vertex_indices"]
        if not isinstance(faces, np.ndarray) or faces.ndim != 2 or faces.shape[1] != 3:
            raise ValueError(f"{ply.path}: faces are not all triangles")
        parts = ply["face"]["part"].astype(np.int32) if "part" in ply["face"] else None
        return Mesh(ply.xyz(), faces.astype(np.int64), parts)

    def mesh(self) -> Mesh:
        """The loaded (deformed) mesh, ``{sample:06}.mesh.ply``."""
        return self._mesh("mesh.ply")

    def rest_mesh(self) -> Mesh:
        """The unloaded mesh, ``{sample:06}.rest.ply``: vertex k is where vertex k of
        :meth:`mesh` was before loading."""
        return self._mesh("rest.ply")

    def points(self) -> Points:
        """Points uniform by area on the loaded surface, ``{sample:06}.points.ply``."""
        ply = read_ply(self.path("points.ply"))
        vertex = ply["vertex"]
        normals = np.stack([vertex[c] for c in ("nx", "ny", "nz")], axis=1).astype(np.float32)
        return Points(ply.xyz(), normals)


class Dataset(Sequence):
    """A shmgen dataset: a sequence of its views (clean views and augmented copies, as the
    manifest lists them, in sample order), with its samples.

    >>> data = Dataset("out/quickstart")
    >>> view = data[0]; view.rgb.shape, view.depth.dtype, view.K
    >>> for sample in data.samples: mesh = sample.mesh()

    ``complete=True`` (the default) refuses a dataset whose manifest does not yet list every
    sample of ``run.json`` (a run still going, or stopped); ``complete=False`` reads the
    samples finished so far. ``copies=False`` leaves augmented copies out of the sequence.
    Raises ``FileNotFoundError`` for a folder that is not a shmgen dataset, and
    ``ValueError`` for a manifest listing files that are missing or not of its sample.
    """

    def __init__(self, root: str | os.PathLike, *, complete: bool = True, copies: bool = True):
        self.root = Path(root)
        if not self.root.is_dir():
            raise FileNotFoundError(f"{self.root}: no such folder")
        run_path = self.root / "run.json"
        if not run_path.is_file():
            raise FileNotFoundError(
                f"{self.root}: not a shmgen dataset (no run.json; give the folder `shmgen run --out` wrote)"
            )
        self.run = _read_json(run_path)
        if self.run.get("schema") != RUN_SCHEMA:
            raise ValueError(f"{run_path}: schema {self.run.get('schema')!r}; this reader reads {RUN_SCHEMA!r}")
        total = int(self.run["dataset"]["samples"])
        listed = self._read_manifest()
        missing = [s for s in range(total) if s not in listed]
        if complete and missing:
            raise ValueError(
                f"{self.root}: the dataset is not finished: manifest.jsonl lists {total - len(missing)} "
                f"of {total} samples (sample {missing[0]} is missing); run `shmgen run` again to "
                f"finish it, or pass complete=False to read the finished samples"
            )
        self.samples = [self._sample(index, listed[index], copies) for index in sorted(listed)]
        self._views = [(sample, entry) for sample in self.samples for entry in sample._entries]

    @property
    def name(self) -> str:
        """The dataset's name, as the recipe gave it."""
        return self.run["dataset"]["name"]

    @property
    def outputs(self) -> list[str]:
        """The outputs the dataset writes, by name (``rgb``, ``depth``, ``mesh``…)."""
        return [name for name, on in self.run["dataset"]["outputs"].items() if on]

    def __len__(self) -> int:
        return len(self._views)

    def __getitem__(self, index):
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        sample, (view, copy, stem, files) = self._views[index]
        return View(self.root, sample.index, view, copy, stem, files)

    def __iter__(self) -> Iterator[View]:
        for i in range(len(self)):
            yield self[i]

    def __repr__(self) -> str:
        return f"Dataset({str(self.root)!r}, samples={len(self.samples)}, views={len(self)})"

    def sample(self, index: int) -> Sample:
        """The sample with index ``index`` (its number, not its position)."""
        for sample in self.samples:
            if sample.index == index:
                return sample
        raise KeyError(f"{self.root}: no sample {index} in the manifest")

    def _read_manifest(self) -> dict:
        path = self.root / "manifest.jsonl"
        if not path.is_file():
            raise FileNotFoundError(f"{self.root}: the dataset has no manifest.jsonl (no sample finished yet)")
        listed = {}
        with open(path, "rb") as f:
            lines = f.read().split(b"\n")
        # The last piece is what follows the final newline: empty, or a line being appended.
        for number, line in enumerate(lines[:-1], start=1):
            try:
                entry = json.loads(line)
                listed.setdefault(int(entry["sample"]), list(entry["files"]))
            except (ValueError, KeyError, TypeError):
                raise ValueError(f"{path}: line {number} does not parse as a manifest line") from None
        return listed

    def _sample(self, index: int, files: list, copies: bool) -> Sample:
        views: dict = {}
        own = {}
        for relative in sorted(set(files)):
            if ".." in relative.split("/") or relative.startswith("/") or "\\" in relative:
                raise ValueError(f"{self.root}/manifest.jsonl: sample {index} lists {relative!r}, outside the dataset")
            path = self.root / relative
            if not path.is_file():
                raise ValueError(f"{self.root}: {relative} is listed in manifest.jsonl but missing")
            stem, kind = _kind_of(relative)
            match = _STEM.match(stem)
            if match is None or int(match.group(1)) != index:
                raise ValueError(
                    f"{self.root}/manifest.jsonl: sample {index} lists {relative}, not a file of sample {index}"
                )
            if match.group(2) is None:
                own[kind] = path
                continue
            view = int(match.group(2))
            copy = None if match.group(3) is None else int(match.group(3))
            views.setdefault((view, -1 if copy is None else copy), (view, copy, stem, {}))[3][kind] = path
        entries = [views[key] for key in sorted(views) if copies or views[key][1] is None]
        return Sample(self.root, index, entries, own)
