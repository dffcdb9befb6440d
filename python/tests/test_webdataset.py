"""The WebDataset export in a standard pipeline: the code of docs/using-the-data.md
(python/examples/webdataset_batches.py) run with WebDataset's own decoders gives depth as
float32 metres and labels as single-channel integers, equal to what the loader reads; and a
default export of a small dataset gives each of 2 DataLoader workers shards of its own
(split as WebDataset splits them)."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest
from conftest import REPO, shmgen

from shmgen_data import Dataset, DatasetError
from shmgen_data.webdataset import MEMBERS, shard_urls

sys.path.insert(0, str(REPO / "python" / "examples"))
import webdataset_batches  # noqa: E402  (the documented snippet, as a module)


@pytest.fixture(scope="module")
def box_wds(box, tmp_path_factory):
    """The box dataset (12 views) exported with the default shard size."""
    out = tmp_path_factory.mktemp("wds") / "wds"
    shmgen("export", box, "--format", "webdataset", "--out", out)
    return out


def test_the_documented_pipeline_decodes_depth_and_labels_as_arrays(box, box_wds):
    data = {view.stem: view for view in Dataset(box)}
    seen = []
    for key, rgb, depth, mask, parts in webdataset_batches.views(str(box_wds), images="rgb"):
        view = data[key]
        assert rgb.dtype == np.float32 and rgb.shape == view.rgb.shape
        assert np.array_equal(np.rint(rgb * 255).astype(np.uint8), view.rgb)
        assert depth.dtype == np.float32 and np.array_equal(depth, view.depth), key
        assert mask.dtype == np.bool_ and np.array_equal(mask, view.mask), key
        assert parts.dtype == np.int32 and parts.ndim == 2 and np.array_equal(parts, view.parts), key
        seen.append(key)
    assert seen == list(data), "every view once, in order"


def test_a_default_export_gives_two_workers_shards_of_their_own(box, box_wds, monkeypatch):
    urls = shard_urls(box_wds)
    assert len(urls) >= 2
    keys = []
    for worker in range(2):
        # How WebDataset splits shards among DataLoader workers, without torch.
        monkeypatch.setenv("WORKER", str(worker))
        monkeypatch.setenv("NUM_WORKERS", "2")
        mine = [key for key, *_ in webdataset_batches.views(str(box_wds), images="rgb")]
        assert mine, f"worker {worker} of 2 gets no views"
        keys += mine
    assert sorted(keys) == sorted(view.stem for view in Dataset(box))


def test_export_json_lists_shards_of_known_members(box_wds, tmp_path):
    record = json.loads((box_wds / "export.json").read_text())
    assert record["shard_size"] is None and len(record["shards"]) == 12  # one per view below 16
    import webdataset

    for item in webdataset.WebDataset(shard_urls(box_wds), shardshuffle=False):
        assert {k for k in item if not k.startswith("__")} <= set(MEMBERS)
    (tmp_path / "export.json").write_text(json.dumps({"format": "colmap"}))
    with pytest.raises(DatasetError, match="format 'colmap'"):
        shard_urls(tmp_path)
    (tmp_path / "export.json").write_text(json.dumps({"format": "webdataset", "shards": [{"file": "../x.tar"}]}))
    with pytest.raises(DatasetError, match="shard-NNNNNN.tar.gz"):
        shard_urls(tmp_path)


def test_torch_batches_with_two_workers(box_wds):
    torch = pytest.importorskip("torch")
    batches = list(webdataset_batches.batches(str(box_wds), batch_size=2, num_workers=2))
    assert sum(len(keys) for keys, *_ in batches) == 12
    keys, rgb, depth, mask, parts = batches[0]
    assert rgb.shape == (2, 3, 120, 160) and rgb.dtype == torch.float32
    assert depth.shape == (2, 120, 160) and depth.dtype == torch.float32
    assert mask.dtype == torch.bool and parts.dtype == torch.int32
