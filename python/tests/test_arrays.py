"""A view as training arrays (what the PyTorch wrapper serves), with and without torch."""

from __future__ import annotations

import numpy as np
import pytest

from shmgen_data import Dataset, view_arrays

ALL = ("rgb", "depth", "mask", "parts", "normals", "displacement", "flow", "flow_valid",
       "rest_rgb", "rest_depth", "ray_distance")


def test_view_arrays_are_channels_first_with_the_camera(deformation):
    view = Dataset(deformation)[4]
    arrays = view_arrays(view, ALL)
    h, w = view.camera.height, view.camera.width
    assert arrays["rgb"].shape == (3, h, w) and arrays["rgb"].dtype == np.float32
    assert np.array_equal(np.rint(arrays["rgb"] * 255).astype(np.uint8), view.rgb.transpose(2, 0, 1))
    assert arrays["depth"].shape == (1, h, w) and np.array_equal(arrays["depth"][0], view.depth)
    assert arrays["mask"].shape == (1, h, w) and arrays["mask"].dtype == np.bool_
    assert arrays["parts"].shape == (h, w) and arrays["parts"].dtype == np.int64
    assert arrays["normals"].shape == (3, h, w)
    assert np.array_equal(arrays["flow"].transpose(1, 2, 0), view.flow)
    assert arrays["flow_valid"].shape == (1, h, w)
    for key, shape in (("K", (3, 3)), ("c2w", (4, 4)), ("w2c", (4, 4)), ("c2w_opengl", (4, 4)),
                       ("distortion", (5,))):
        assert arrays[key].shape == shape and arrays[key].dtype == np.float32
    assert np.allclose(arrays["K"], view.record["camera"]["K"], rtol=1e-7)
    assert (arrays["sample"], arrays["view"], arrays["copy"], arrays["stem"]) == (1, 1, -1, "000001_01")
    assert arrays["is_copy"] is False
    with pytest.raises(KeyError, match="unknown output"):
        view_arrays(view, ("rgb", "colour"))


def test_torch_view_dataset_batches_views(box):
    torch = pytest.importorskip("torch")
    from torch.utils.data import DataLoader

    from shmgen_data.torch import ViewDataset

    data = ViewDataset(box, layers=("rgb", "depth", "mask", "instances"))
    assert len(data) == 12
    batch = next(iter(DataLoader(data, batch_size=4)))
    assert batch["rgb"].shape == (4, 3, 120, 160) and batch["rgb"].dtype == torch.float32
    assert batch["depth"].shape == (4, 1, 120, 160)
    assert batch["mask"].dtype == torch.bool and batch["instances"].dtype == torch.int64
    assert batch["K"].shape == (4, 3, 3) and batch["c2w"].shape == (4, 4, 4)
    assert list(batch["stem"]) == [v.stem for v in Dataset(box)[:4]]
    clean = ViewDataset(box, copies=False)
    assert len(clean) == 6 and all(item["copy"] == -1 for item in clean)
