"""PyTorch batches from `shmgen export --format webdataset` shards, with WebDataset's own
decoders: depth as float32 metres, masks as bool, part ids as int32; nothing of ours decodes.
docs/using-the-data.md shows this code; python/tests/test_webdataset.py runs it.

    python python/examples/webdataset_batches.py out/qs-wds     # pip install -e "python/[torch,webdataset]"
"""

from __future__ import annotations

import sys
from typing import Any

import webdataset as wds

from shmgen_data.webdataset import shard_urls

LAYERS = ("__key__", "rgb.png", "depth.npy", "mask.npy", "parts.npy")


def views(export: str, images: str = "torch") -> Any:
    """The export's views as (key, rgb, depth, mask, parts) tuples; ``images="torch"`` gives
    rgb as a (3, H, W) float tensor, ``"rgb"`` as an (H, W, 3) float32 array."""
    return (wds.WebDataset(shard_urls(export), shardshuffle=False)  # shardshuffle=100 to train
            .decode(images)
            .to_tuple(*LAYERS))


def batches(export: str, batch_size: int = 4, num_workers: int = 2) -> Any:
    """A DataLoader over the views: each worker reads whole shards (the export makes enough)."""
    from torch.utils.data import DataLoader

    return DataLoader(views(export), batch_size=batch_size, num_workers=num_workers)


if __name__ == "__main__":
    for keys, rgb, depth, mask, parts in batches(sys.argv[1]):
        # (4, 3, H, W) float32, (4, H, W) float32 metres, (4, H, W) bool, (4, H, W) int32
        print(keys, rgb.shape, depth.dtype, mask.dtype, parts.dtype)
