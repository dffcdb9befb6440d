"""A PyTorch ``Dataset`` over a shmgen dataset's views (needs ``torch``, which the package
does not depend on: ``pip install torch``).

>>> from torch.utils.data import DataLoader
>>> from shmgen_data.torch import ViewDataset
>>> loader = DataLoader(ViewDataset("out/quickstart", layers=("rgb", "depth", "mask")), batch_size=4)
>>> batch = next(iter(loader)); batch["rgb"].shape, batch["K"].shape   # (4, 3, H, W), (4, 3, 3)

Each item is :func:`shmgen_data.view_arrays` with every array made a tensor; all the logic
is there.
"""

from __future__ import annotations

import os
from typing import Any, Callable, Sequence

import numpy as np

try:
    import torch
    from torch.utils.data import Dataset as _TorchDataset
except ImportError as error:  # pragma: no cover - exercised only without torch
    raise ImportError(
        "shmgen_data.torch needs PyTorch (pip install torch); the rest of shmgen_data works without it"
    ) from error

from .arrays import view_arrays
from .dataset import Dataset

__all__ = ["ViewDataset"]


class ViewDataset(_TorchDataset):
    """The views of a shmgen dataset (a path or a :class:`shmgen_data.Dataset`) as dicts of
    tensors: ``layers`` channels first (``rgb`` ``(3, H, W)`` float in [0, 1], ``depth``
    ``(1, H, W)``, masks ``(1, H, W)`` bool, ids ``(H, W)`` int64…), ``K``, ``c2w``, ``w2c``,
    ``c2w_opengl``, ``distortion`` (float32), ``sample``, ``view``, ``copy`` and ``stem``.
    ``transform``, if given, is applied to each item dict. ``copies=False`` leaves augmented
    copies out.
    """

    def __init__(self, data: str | os.PathLike[str] | Dataset,
                 layers: Sequence[str] = ("rgb", "depth", "mask"), *, copies: bool = True,
                 transform: Callable[[dict[str, Any]], Any] | None = None):
        if isinstance(data, (str, os.PathLike)):
            data = Dataset(data, copies=copies)
        elif not copies:
            data = Dataset(data.root, copies=False, limits=data.limits)
        self.data = data
        self.layers = tuple(layers)
        self.transform = transform

    def __len__(self) -> int:
        return len(self.data)

    def __getitem__(self, index: int) -> Any:
        arrays = view_arrays(self.data[index], self.layers)
        item = {k: torch.from_numpy(v) if isinstance(v, np.ndarray) else v for k, v in arrays.items()}
        return self.transform(item) if self.transform is not None else item
