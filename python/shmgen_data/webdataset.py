"""Shards of ``shmgen export --format webdataset`` in a WebDataset pipeline.

Owns: finding an export's shards (from its ``export.json``) and saying what each member of a
shard decodes to. Must not touch: the decoding itself, which WebDataset's own decoders do:
the export writes members they read as training arrays (see ``docs/using-the-data.md``):

* ``rgb.png``, ``rest_rgb.png``: colour PNG, as in the dataset (``.decode("torch")``:
  ``(3, H, W)`` float in [0, 1]; ``.decode("rgb")``: ``(H, W, 3)`` float32);
* ``depth.npy``, ``rest_depth.npy``, ``ray_distance.npy``: ``(H, W)`` float32 metres, 0 = no
  surface; ``normals.npy``, ``displacement.npy`` ``(H, W, 3)``, ``flow.npy`` (and in a
  sequence ``flow_next.npy``, ``flow_prev.npy``) ``(H, W, 2)`` float32;
* ``mask.npy``, ``cracks.npy``, ``erased.npy``, ``valid.npy``, ``flow_valid.npy`` (and
  ``flow_next_valid.npy``, ``flow_prev_valid.npy``): ``(H, W)`` bool; ``parts.npy``, ``instances.npy``: ``(H, W)`` int32 ids (the record's
  ``segmentation`` tables name them);
* ``json``: the view's record (a dict), whose ``augmentation`` is None for a clean view.

>>> import webdataset as wds
>>> from shmgen_data.webdataset import shard_urls
>>> views = wds.WebDataset(shard_urls("out/qs-wds"), shardshuffle=False).decode("torch")
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from .files import DatasetError, Limits, parse_json, read_named

__all__ = ["shard_urls", "MEMBERS"]

#: Every member a view's key may have, by the name WebDataset gives it, and what it holds.
MEMBERS = {
    "rgb.png": "colour image (H, W, 3), 8-bit",
    "rest_rgb.png": "colour image of the unloaded structure (H, W, 3), 8-bit",
    "depth.npy": "float32 (H, W) planar depth, metres, 0 = no surface",
    "rest_depth.npy": "float32 (H, W) planar depth of the unloaded structure",
    "ray_distance.npy": "float32 (H, W) distance along the ray, metres",
    "normals.npy": "float32 (H, W, 3) unit normals, camera OpenCV axes, 0 = no surface",
    "displacement.npy": "float32 (H, W, 3) world displacement, metres",
    "flow.npy": "float32 (H, W, 2) rest → loaded pixel motion (U, V)",
    "mask.npy": "bool (H, W) the structures",
    "cracks.npy": "bool (H, W) cracks",
    "erased.npy": "bool (H, W) pixels an augmentation erased",
    "valid.npy": "bool (H, W) pixels whose labels hold",
    "flow_valid.npy": "bool (H, W) where flow is defined",
    "flow_next.npy": "float32 (H, W, 2) this frame → next frame pixel motion (U, V)",
    "flow_next_valid.npy": "bool (H, W) where flow_next is defined",
    "flow_prev.npy": "float32 (H, W, 2) this frame → previous frame pixel motion (U, V)",
    "flow_prev_valid.npy": "bool (H, W) where flow_prev is defined",
    "parts.npy": "int32 (H, W) part ids (segmentation.part_ids)",
    "instances.npy": "int32 (H, W) instance ids (segmentation.instance_ids)",
    "json": "the view's record (shmgen.view/2)",
}

_SHARD = re.compile(r"shard-\d{6}\.tar\.gz")


def shard_urls(folder: str | os.PathLike[str], *, limits: Limits | None = None) -> list[str]:
    """The paths of the shards of the export at ``folder``, in order, as its ``export.json``
    lists them; each must be a ``shard-NNNNNN.tar.gz`` file in the folder.

    Raises ``FileNotFoundError`` for a folder without ``export.json`` or a listed shard
    missing, and :class:`DatasetError` for an export of another format or a listing that
    does not read as one.
    """
    root = Path(folder)
    limits = limits or Limits()
    data, shown = read_named(root / "export.json", limits.record_bytes, "export.json (Limits.record_bytes)")
    record = parse_json(data, shown)
    if record.get("format") != "webdataset":
        raise DatasetError(f"{shown}: format {record.get('format')!r}; a webdataset export is expected "
                           "(shmgen export D --format webdataset --out …)")
    shards = record.get("shards")
    if not isinstance(shards, list):
        raise DatasetError(f"{shown}: 'shards' is not a list")
    urls = []
    for entry in shards:
        name = entry.get("file") if isinstance(entry, dict) else None
        if not isinstance(name, str) or not _SHARD.fullmatch(name):
            raise DatasetError(f"{shown}: shard entry {entry!r} does not name a shard-NNNNNN.tar.gz file")
        path = root / name
        if not path.is_file():
            raise FileNotFoundError(f"{path}: listed in export.json, missing")
        urls.append(str(path))
    return urls
