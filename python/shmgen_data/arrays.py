"""A view as the arrays a training loop wants: channels first, floats, fixed keys.

:func:`view_arrays` does all the work of :class:`shmgen_data.torch.ViewDataset` (which only
turns its arrays into tensors), so it is usable, and tested, without PyTorch.
"""

from __future__ import annotations

from typing import Any, Sequence, Union

import numpy as np
from numpy.typing import NDArray

from .dataset import LAYERS, View

__all__ = ["view_arrays", "CAMERA_KEYS"]

#: The camera arrays :func:`view_arrays` adds, float32.
CAMERA_KEYS = ("K", "c2w", "w2c", "c2w_opengl", "distortion")

#: What :func:`view_arrays` gives: arrays, and the view's indices, stem and whether it is a copy.
Item = dict[str, Union[NDArray[Any], int, str, bool]]

_MASKS = {"mask", "cracks", "erased", "valid", "flow_valid", "flow_next_valid", "flow_prev_valid"}
_IDS = {"parts", "instances"}
_COLOURS = {"rgb", "rest_rgb"}


def layer_array(view: View, name: str) -> np.ndarray:
    """One output of ``view`` in training layout:

    * ``rgb``, ``rest_rgb``: ``(3, H, W)`` float32 in [0, 1];
    * ``depth``, ``rest_depth``, ``ray_distance``: ``(1, H, W)`` float32 metres, 0 = no surface;
    * ``normals``, ``displacement``: ``(3, H, W)`` float32; ``flow``, ``flow_next``,
      ``flow_prev``: ``(2, H, W)`` float32;
    * masks (``mask``, ``cracks``, ``erased``, ``valid`` and the flows' ``…_valid``):
      ``(1, H, W)`` bool;
    * ``parts``, ``instances``: ``(H, W)`` int64 ids (a segmentation target).
    """
    values = view.load(name)
    if name in _COLOURS:
        colours = np.ascontiguousarray(values.transpose(2, 0, 1), dtype=np.float32)
        return np.asarray(colours / np.float32(255), dtype=np.float32)
    if name in _IDS:
        return values.astype(np.int64)
    if values.ndim == 2:
        return np.ascontiguousarray(values[None])
    return np.ascontiguousarray(values.transpose(2, 0, 1))


def view_arrays(view: View, layers: Sequence[str] = ("rgb", "depth", "mask"), *,
                camera: bool = True) -> Item:
    """``view``'s ``layers`` (see :func:`layer_array`) by name, plus, with ``camera``, its
    ``K`` (3 × 3), ``c2w`` and ``w2c`` (OpenCV axes) and ``c2w_opengl`` (4 × 4) and
    ``distortion`` (``k1, k2, p1, p2, k3``), all float32, and its ``sample``, ``view`` and
    ``copy`` (−1 for a clean view) indices, ``is_copy`` and ``stem``.

    Raises :class:`shmgen_data.MissingFileError` naming the view and the output if the view
    lacks one of ``layers``, and ``KeyError`` for an unknown output name.
    """
    out: Item = {}
    for name in layers:
        if name not in LAYERS:
            raise KeyError(f"unknown output {name!r} (known: {', '.join(LAYERS)})")
        out[name] = layer_array(view, name)
    if camera:
        cam = view.camera
        for key in CAMERA_KEYS:
            out[key] = np.asarray(getattr(cam, key), dtype=np.float32)
    out["sample"] = view.sample
    out["view"] = view.view
    out["copy"] = -1 if view.copy is None else view.copy
    out["is_copy"] = view.is_copy
    out["stem"] = view.stem
    return out
