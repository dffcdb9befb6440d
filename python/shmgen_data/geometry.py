"""Depth back to 3-D: the points a view's depth sees, and the fused cloud of a sample.

A pixel ``(i, j)`` with planar depth ``z`` (camera-frame z, not the distance along the ray)
sees the camera-frame point ``z · (x, y, 1)``, where ``(x, y)`` are the undistorted
normalised coordinates of its centre ``(u, v) = (j + 0.5, i + 0.5)``: ``K⁻¹ (u, v, 1)``, and
for a distorting lens that undone with OpenCV's Brown–Conrady model
(:func:`shmgen_data.camera.undistort`). The world point is ``c2w · (X_cam, 1)``.

The depth back-projected is the view's own (``view.depth``) or, given ``depth=``, any map of
the view's size in the same convention: a network's prediction back-projects through the
view's camera exactly as the truth does (pixels with depth ≤ 0 or not finite give no point).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .dataset import Sample, View

#: The depth maps :func:`fuse` back-projects instead of the views' own: by view stem, or a
#: function of the view (a network's forward pass, say).
Depths = Union[Mapping[str, ArrayLike], Callable[[View], ArrayLike]]

__all__ = ["Cloud", "backproject", "fuse"]


@dataclass
class Cloud:
    """A point cloud from depth: ``points`` ``(N, 3)`` float64 world metres, ``colours``
    ``(N, 3)`` uint8 (the RGB pixel each point was seen at, or None without RGB),
    ``pixels`` ``(N, 2)`` int64 ``(i, j)`` row and column, and ``views`` ``(N,)`` int64 — the
    position of the point's view in the list fused (all 0 for one view)."""

    points: np.ndarray
    colours: np.ndarray | None
    pixels: np.ndarray
    views: np.ndarray

    def __len__(self) -> int:
        return len(self.points)


def backproject(view: View, *, rest: bool = False, where: np.ndarray | None = None,
                depth: ArrayLike | None = None) -> Cloud:
    """The world points a view's depth sees, with their colours.

    Every pixel with depth > 0 (and ``where`` True, if given: an ``(H, W)`` bool mask such as
    ``view.valid`` or ``view.flow_valid``) gives one point. ``rest=True`` back-projects the
    unloaded structure (``rest_depth``, coloured by ``rest_rgb``) through the same camera.
    ``depth``, if given, is back-projected instead of the view's file: an ``(H, W)`` map of
    planar depth in metres, such as a network's prediction (NaN, ±inf and values ≤ 0 give no
    point). Colours are None when the view has no RGB file.
    """
    camera = view.camera
    if depth is None:
        depth = view.rest_depth if rest else view.depth
    else:
        depth = checked_depth(depth, view)
    with np.errstate(invalid="ignore"):
        keep = np.isfinite(depth) & (depth > 0)
    if where is not None:
        where = np.asarray(where, dtype=bool)
        if where.shape != depth.shape:
            raise ValueError(f"where has shape {where.shape}, the view's images {depth.shape}")
        keep &= where
    rows, cols = np.nonzero(keep)
    c = camera.pixel_center
    x, y = camera.normalised(cols + c, rows + c)
    z = depth[rows, cols].astype(np.float64)
    cam = np.stack([x * z, y * z, z], axis=1)
    points = cam @ camera.c2w[:3, :3].T + camera.c2w[:3, 3]
    rgb_name = "rest_rgb" if rest else "rgb"
    colours = view.load(rgb_name)[rows, cols] if view.has(rgb_name) else None
    pixels = np.stack([rows, cols], axis=1).astype(np.int64)
    return Cloud(points, colours, pixels, np.zeros(len(points), dtype=np.int64))


def checked_depth(depth: ArrayLike, view: View) -> NDArray[np.float64]:
    """``depth`` as a float64 ``(H, W)`` array of the view's size; ``ValueError`` naming the
    view and the shape otherwise."""
    array = np.asarray(depth)
    if array.ndim == 3 and array.shape[-1] == 1:
        array = array[..., 0]
    size = (view.camera.height, view.camera.width)
    if array.shape != size:
        raise ValueError(f"a depth map for view {view.stem} has shape {array.shape}; the view is "
                         f"{size[0]} × {size[1]} (H, W)")
    if not np.issubdtype(array.dtype, np.number) or np.iscomplexobj(array):
        raise ValueError(f"a depth map for view {view.stem} holds {array.dtype}, not real numbers")
    return array.astype(np.float64)


def _depth_of(depths: Depths, view: View) -> Any:
    """The depth map ``depths`` gives for ``view``: ``KeyError`` naming the view if a mapping
    has none for it."""
    if callable(depths):
        return depths(view)
    try:
        return depths[view.stem]
    except KeyError:
        raise KeyError(f"no depth map given for view {view.stem}") from None


def fuse(sample: Sample, *, copies: bool = False, rest: bool = False,
         depths: Depths | None = None) -> Cloud:
    """The fused cloud of a sample: every view's :func:`backproject` in one cloud.

    Clean views only by default (an exact augmented copy sees the same surface again);
    ``copies=True`` adds the augmented copies, restricted to their ``valid`` pixels where
    they have that mask. ``Cloud.views`` gives each point's position in ``sample.views``
    (or in ``sample.clean_views()`` without copies). Raises ``ValueError`` for a sample with
    no view to fuse (all clean views left out by ``keep_clean: false``: pass ``copies=True``).
    ``depths`` fuses other depth maps than the views' own: by view stem (``{"000003_01": map}``)
    or a function of the :class:`View` (each map as ``backproject``'s ``depth``).
    """
    views = sample.views if copies else sample.clean_views()
    if not views:
        raise ValueError(
            f"sample {sample.index} has no clean views to fuse (the dataset keeps only augmented "
            "copies); pass copies=True"
        )
    clouds = [backproject(v, rest=rest, where=v.valid if v.has("valid") else None,
                          depth=None if depths is None else _depth_of(depths, v)) for v in views]
    colours = None
    if all(c.colours is not None for c in clouds):
        colours = np.concatenate([c.colours for c in clouds])
    return Cloud(
        np.concatenate([c.points for c in clouds]),
        colours,
        np.concatenate([c.pixels for c in clouds]),
        np.concatenate([np.full(len(c), k, dtype=np.int64) for k, c in enumerate(clouds)]),
    )
