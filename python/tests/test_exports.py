"""`shmgen export` read back independently: nerfstudio's transforms.json and COLMAP's text
model parsed here, WebDataset shards read with the `webdataset` package; each gives the
view JSONs' K, lens and poses, and every file."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
import webdataset
from conftest import shmgen
from PIL import Image

from shmgen_data import Dataset


def export(root, fmt, out, *extra):
    shmgen("export", root, "--format", fmt, "--out", out, *extra)
    return out


def png(path_or_bytes) -> np.ndarray:
    source = io.BytesIO(path_or_bytes) if isinstance(path_or_bytes, bytes) else path_or_bytes
    with Image.open(source) as image:
        return np.array(image)


def exported_scenes(request, name, fmt, tmp_path):
    """Exports the dataset fixture ``name`` as ``fmt`` (copies included); yields each
    sample's scene folder and its views by stem."""
    data = Dataset(request.getfixturevalue(name))
    out = export(data.root, fmt, tmp_path / fmt, "--with-copies")
    for sample in data.samples:
        yield out / f"{sample.index:06}", {v.stem: v for v in sample.views}


def assert_intrinsics(view, width, height, fx, fy, cx, cy):
    """The exported image size and pinhole intrinsics are the view's, to the bit."""
    K = view.K
    assert (width, height) == (view.camera.width, view.camera.height)
    assert [fx, fy, cx, cy] == [K[0, 0], K[1, 1], K[0, 2], K[1, 2]], view.stem


@pytest.mark.parametrize("name", ["box", "box_lens"])
def test_nerfstudio_frames_carry_the_views_cameras_and_files(name, request, tmp_path):
    for folder, views in exported_scenes(request, name, "nerfstudio", tmp_path):
        transforms = json.loads((folder / "transforms.json").read_text())
        frames = {f["file_path"].rsplit("/", 1)[-1].split(".")[0]: f for f in transforms["frames"]}
        assert sorted(frames) == sorted(views), "one frame per view and copy"
        for stem, frame in frames.items():
            view = views[stem]
            assert_intrinsics(view, frame["w"], frame["h"], frame["fl_x"], frame["fl_y"],
                              frame["cx"], frame["cy"])
            assert np.array_equal(np.array(frame["transform_matrix"]), view.c2w_opengl)
            model = frame.get("camera_model", transforms.get("camera_model"))
            if view.camera.model == "pinhole":
                assert model == "PINHOLE"
            else:
                assert model == "OPENCV"
                lens = [frame.get(k, transforms.get(k)) for k in ("k1", "k2", "p1", "p2", "k3")]
                assert np.array_equal(lens, view.distortion)
            # Every file of the frame is there: the image is the view's RGB, the mask its
            # mask, the depth its depth in whole millimetres (scale 0.001).
            assert np.array_equal(png(folder / frame["file_path"]), view.rgb)
            assert np.array_equal(png(folder / frame["mask_path"]) == 255, view.mask)
            mm = png(folder / frame["depth_file_path"]).astype(np.float64)
            metres = view.depth.astype(np.float64)
            scale = transforms["depth_unit_scale_factor"]
            assert np.array_equal(mm == 0, metres == 0)
            assert np.abs(mm * scale - metres)[metres > 0].max() <= 0.5 * scale + 1e-9


def quaternion_to_matrix(w, x, y, z) -> np.ndarray:
    """COLMAP's qvec2rotmat (Hamilton, w first)."""
    return np.array([
        [1 - 2 * y * y - 2 * z * z, 2 * x * y - 2 * w * z, 2 * z * x + 2 * w * y],
        [2 * x * y + 2 * w * z, 1 - 2 * x * x - 2 * z * z, 2 * y * z - 2 * w * x],
        [2 * z * x - 2 * w * y, 2 * y * z + 2 * w * x, 1 - 2 * x * x - 2 * y * y],
    ])


def read_colmap(folder):
    """cameras.txt and images.txt of a COLMAP text model: {id: (model, w, h, params)} and
    {name: (qvec, tvec, camera id)}."""
    cameras, images = {}, {}
    for line in (folder / "cameras.txt").read_text().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        words = line.split()
        cameras[int(words[0])] = (words[1], int(words[2]), int(words[3]), [float(w) for w in words[4:]])
    lines = [l for l in (folder / "images.txt").read_text().splitlines() if not l.startswith("#")]
    for line in lines[0::2]:  # each image: a pose line, then its (here empty) 2-D points
        words = line.split()
        q = [float(w) for w in words[1:5]]
        t = [float(w) for w in words[5:8]]
        images[words[9]] = (q, t, int(words[8]))
    return cameras, images


#: COLMAP's parameter order per model.
COLMAP_PARAMS = {
    "PINHOLE": ["fx", "fy", "cx", "cy"],
    "OPENCV": ["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"],
    "FULL_OPENCV": ["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"],
}


@pytest.mark.parametrize("name", ["box", "box_lens"])
def test_colmap_models_carry_the_views_cameras_and_images(name, request, tmp_path):
    for folder, views in exported_scenes(request, name, "colmap", tmp_path):
        cameras, images = read_colmap(folder / "sparse" / "0")
        assert (folder / "sparse" / "0" / "points3D.txt").is_file()
        assert sorted(n.split(".")[0] for n in images) == sorted(views)
        for image_name, (q, t, camera_id) in images.items():
            view = views[image_name.split(".")[0]]
            model, width, height, params = cameras[camera_id]
            values = dict(zip(COLMAP_PARAMS[model], params, strict=True))
            assert_intrinsics(view, width, height, values["fx"], values["fy"], values["cx"],
                              values["cy"])
            lens = dict(zip(("k1", "k2", "p1", "p2", "k3"), view.distortion))
            if view.camera.model == "pinhole":
                assert model == "PINHOLE"
            else:
                assert model == ("FULL_OPENCV" if lens["k3"] != 0 else "OPENCV")
                for key, value in lens.items():
                    assert values.get(key, 0.0) == value, key
                assert values.get("k4", 0) == values.get("k5", 0) == values.get("k6", 0) == 0
            # The pose is world → camera in OpenCV axes: the view's w2c.
            R = quaternion_to_matrix(*q)
            assert np.allclose(R, view.w2c[:3, :3], atol=1e-12)
            assert np.allclose(t, view.w2c[:3, 3], atol=1e-12)
            assert np.array_equal(png(folder / "images" / image_name), view.rgb)


#: What the WebDataset export writes each per-view output as: the dataset's PNG, or an array.
WDS_DTYPES = {"rgb": None, "rest_rgb": None, "depth": np.float32, "rest_depth": np.float32,
              "ray_distance": np.float32, "normals": np.float32, "displacement": np.float32,
              "flow": np.float32, "mask": np.bool_, "cracks": np.bool_, "erased": np.bool_,
              "valid": np.bool_, "flow_valid": np.bool_, "parts": np.int32, "instances": np.int32}


@pytest.mark.parametrize("name", ["box_lens", "deformation"])
def test_webdataset_shards_hold_every_layer_of_every_view(name, request, tmp_path):
    data = Dataset(request.getfixturevalue(name))
    out = export(data.root, "webdataset", tmp_path / "wds", "--shard-size", "5")
    shards = sorted(str(p) for p in out.glob("shard-*.tar.gz"))
    assert len(shards) == -(-len(data) // 5)
    items = list(webdataset.WebDataset(shards, shardshuffle=False))
    assert [item["__key__"] for item in items] == [view.stem for view in data]
    for item, view in zip(items, data):
        kinds = {k for k in item if not k.startswith("__")}
        expected = {"json"} | {f"{layer}.png" if WDS_DTYPES[layer] is None else f"{layer}.npy"
                               for layer in view.layers}
        assert kinds == expected, view.stem
        for layer in view.layers:
            if WDS_DTYPES[layer] is None:  # colour images: the dataset's bytes
                assert item[f"{layer}.png"] == view.path(layer).read_bytes(), (view.stem, layer)
                continue
            # Arrays, read by numpy itself: the loader's values, dtype and shape, to the bit.
            array = np.load(io.BytesIO(item[f"{layer}.npy"]), allow_pickle=False)
            assert array.dtype == WDS_DTYPES[layer], (view.stem, layer)
            assert array.shape == view.load(layer).shape, (view.stem, layer)
            assert np.array_equal(array, view.load(layer)), (view.stem, layer)
        assert item["json"] == view.files["json"].read_bytes()
        record = json.loads(item["json"])
        assert record == view.record
        K = np.array(record["camera"]["K"])
        assert np.array_equal(K, view.K)
        assert np.array_equal(np.array(record["camera"]["c2w_opencv"]), view.c2w)
        assert np.array_equal(png(item["rgb.png"]), view.rgb)
