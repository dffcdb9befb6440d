"""Writing predictions where ``shmgen eval`` reads them, and PLY files.

Owns: the names, formats and checks of the files a model's user writes for ``shmgen eval``
(docs/metrics.md). Must not touch: the dataset (predictions go in a folder of their own,
never inside it).

Layout under a predictions folder ``P`` (what ``shmgen eval DATA P`` reads):

* a view's depth: ``P/samples/NNNN/{stem}.depth.npy``, the dataset's folder and stem of the
  view, float32 ``(H, W)`` planar depth in metres at the view's size; NaN marks a pixel not
  predicted (eval leaves it out and counts it);
* a sample's surface: ``P/samples/NNNN/{sample:06}.ply``, binary PLY: a point cloud (a fused
  back-projection, say) or a triangle mesh.

Each writer checks what it is given against the view (size, real finite values) before
writing, and writes through a temporary file renamed into place, so an interrupted run
leaves no half-written prediction.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .dataset import Sample, View
from .geometry import checked_depth

__all__ = ["depth_prediction_path", "surface_prediction_path", "write_depth_prediction",
           "write_surface_prediction", "write_ply"]

#: The other depth formats eval reads: two files for one view are an error there.
_OTHER_DEPTH_KINDS = ("depth.exr", "depth.png", "depth_mm.png")


def _folder(root: Path, files: dict[str, Path], shown: str) -> str:
    """The dataset folder (``samples/0000``) holding a view's or sample's files."""
    for path in files.values():
        return path.relative_to(root).parent.as_posix()
    raise ValueError(f"{shown} has no files: its folder is unknown")


def _outside(predictions: Path, dataset: Path) -> Path:
    """``predictions``, refused if it is the dataset or lies inside it."""
    predictions = Path(predictions)
    p, d = predictions.resolve(), dataset.resolve()
    if p == d or d in p.parents:
        raise ValueError(f"{predictions}: predictions must go in a folder of their own, not inside the "
                         f"dataset {dataset}")
    return predictions


def depth_prediction_path(predictions: str | os.PathLike[str], view: View) -> Path:
    """Where ``shmgen eval`` reads the depth prediction of ``view`` under ``predictions``."""
    folder = _folder(view.root, view.files, f"view {view.stem}")
    return _outside(Path(predictions), view.root) / folder / f"{view.stem}.depth.npy"


def surface_prediction_path(predictions: str | os.PathLike[str], sample: Sample) -> Path:
    """Where ``shmgen eval`` reads the surface prediction of ``sample`` under ``predictions``."""
    files = dict(sample.files)
    for view in sample.views[:1]:
        files.update(view.files)
    folder = _folder(sample.root, files, f"sample {sample.index}")
    return _outside(Path(predictions), sample.root) / folder / f"{sample.index:06}.ply"


def _write_atomic(path: Path, write: object) -> Path:
    """Runs ``write(file)`` on a temporary file beside ``path``, then renames it to ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".partial")
    try:
        with os.fdopen(handle, "wb") as file:
            write(file)  # type: ignore[operator]
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise
    return path


def write_depth_prediction(predictions: str | os.PathLike[str], view: View, depth: ArrayLike) -> Path:
    """Writes ``depth`` (planar depth in metres, ``(H, W)`` or ``(H, W, 1)`` at the view's
    size; NaN = not predicted) as the view's prediction under ``predictions``, float32, where
    ``shmgen eval`` reads it. Returns the file's path.

    ``ValueError`` for a map of another size, of values that are not real numbers, with ±inf
    (or values beyond float32), for a folder inside the dataset, or when another format of the
    same view's prediction is already there (eval would refuse the pair).
    """
    path = depth_prediction_path(predictions, view)
    array = checked_depth(depth, view)
    with np.errstate(over="ignore", invalid="ignore"):
        as_float32 = array.astype(np.float32)
    infinite = np.isinf(as_float32)
    if infinite.any():
        row, column = np.unravel_index(int(np.argmax(infinite)), infinite.shape)
        raise ValueError(f"a depth map for view {view.stem}: pixel (row {row}, column {column}) holds "
                         f"{array[row, column]}, not a float32 depth; mark a pixel not predicted with NaN")
    for kind in _OTHER_DEPTH_KINDS:
        other = path.with_name(f"{view.stem}.{kind}")
        if other.exists():
            raise ValueError(f"{other} already predicts view {view.stem}; remove it first (eval reads one file per view)")
    return _write_atomic(path, lambda file: np.save(file, as_float32, allow_pickle=False))


def write_surface_prediction(predictions: str | os.PathLike[str], sample: Sample, points: ArrayLike,
                             faces: ArrayLike | None = None, colours: ArrayLike | None = None) -> Path:
    """Writes a predicted surface of ``sample`` under ``predictions`` where ``shmgen eval``
    reads it (for Chamfer distance and F-score): ``points`` ``(N, 3)`` world metres, and
    ``faces`` ``(M, 3)`` for a mesh (a point cloud without). See :func:`write_ply`."""
    return write_ply(surface_prediction_path(predictions, sample), points, faces=faces, colours=colours)


def _ply_arrays(points: ArrayLike, faces: ArrayLike | None, colours: ArrayLike | None
                ) -> tuple[NDArray[np.float64], NDArray[np.int32] | None, NDArray[np.uint8] | None]:
    """The checked arrays of :func:`write_ply`."""
    xyz = np.asarray(points, dtype=np.float64)
    if xyz.ndim != 2 or xyz.shape[1] != 3:
        raise ValueError(f"points have shape {xyz.shape}; expected (N, 3)")
    if not np.isfinite(xyz).all():
        raise ValueError(f"point {int(np.argmax(~np.isfinite(xyz).all(axis=1)))} is not finite")
    triangles = None
    if faces is not None:
        f = np.asarray(faces)
        if f.ndim != 2 or f.shape[1] != 3 or not np.issubdtype(f.dtype, np.integer):
            raise ValueError(f"faces have shape {f.shape} and type {f.dtype}; expected (M, 3) integers")
        if f.size and (f.min() < 0 or f.max() >= len(xyz)):
            raise ValueError(f"a face refers to vertex {int(f.max() if f.max() >= len(xyz) else f.min())}; "
                             f"the vertices are 0…{len(xyz) - 1}")
        triangles = f.astype(np.int32)
    rgb = None
    if colours is not None:
        c = np.asarray(colours)
        if c.shape != xyz.shape or (c.size and (c.min() < 0 or c.max() > 255)):
            raise ValueError(f"colours have shape {c.shape}; expected {xyz.shape} values 0…255")
        rgb = c.astype(np.uint8)
    return xyz, triangles, rgb


def write_ply(path: str | os.PathLike[str], points: ArrayLike, *, faces: ArrayLike | None = None,
              colours: ArrayLike | None = None) -> Path:
    """Writes a binary little-endian PLY: ``vertex`` with double ``x, y, z`` (and uchar
    ``red, green, blue`` given ``colours`` ``(N, 3)`` 0…255), and given ``faces`` ``(M, 3)``
    vertex indices, ``face`` with ``list uchar int vertex_indices``. What shmgen's own meshes
    hold, readable by :func:`shmgen_data.read_ply`, trimesh, Open3D and ``shmgen eval``.
    ``ValueError`` for non-finite points or faces beyond the vertices."""
    xyz, triangles, rgb = _ply_arrays(points, faces, colours)
    vertex_fields = [("x", "<f8"), ("y", "<f8"), ("z", "<f8")]
    if rgb is not None:
        vertex_fields += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    vertices = np.empty(len(xyz), dtype=vertex_fields)
    for k, axis in enumerate("xyz"):
        vertices[axis] = xyz[:, k]
    if rgb is not None:
        for k, channel in enumerate(("red", "green", "blue")):
            vertices[channel] = rgb[:, k]
    header = ["ply", "format binary_little_endian 1.0", "comment written by shmgen_data.write_ply",
              f"element vertex {len(xyz)}", "property double x", "property double y", "property double z"]
    if rgb is not None:
        header += ["property uchar red", "property uchar green", "property uchar blue"]
    body = [vertices.tobytes()]
    if triangles is not None:
        header += [f"element face {len(triangles)}", "property list uchar int vertex_indices"]
        rows = np.empty(len(triangles), dtype=[("n", "u1"), ("v", "<i4", (3,))])
        rows["n"], rows["v"] = 3, triangles
        body.append(rows.tobytes())
    header.append("end_header")
    data = ("\n".join(header) + "\n").encode("ascii") + b"".join(body)
    return _write_atomic(Path(path), lambda file: file.write(data))
