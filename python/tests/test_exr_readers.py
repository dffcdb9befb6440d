"""Every EXR layer a dataset holds, read by the three readers training code uses — OpenCV 4.x
(``cv2.imread(path, cv2.IMREAD_UNCHANGED)``), imageio (its ``opencv`` plugin, the one that reads
EXR without downloading anything) and the OpenEXR package — each as docs/outputs.md says, and
checked against independent truth: the analytic box for depth, ray distance and normals, the
camera's projection for flow and displacement, and the three readers against each other, to
the bit.

OpenCV's EXR decoder maps only the channels R, G, B, A and Y: the layers are written as ``Y``
(one value per pixel), ``R G B`` (x, y, z) and ``R G`` (flow u, v). OpenCV returns colour
channels as B, G, R (B = 0 for flow); imageio's plugin turns them back to R, G, B.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

os.environ.setdefault("OPENCV_IO_ENABLE_OPENEXR", "1")  # read when OpenCV first opens an EXR

import cv2  # noqa: E402
import imageio.v3 as iio  # noqa: E402
import numpy as np  # noqa: E402
import OpenEXR  # noqa: E402
import pytest  # noqa: E402
from conftest import BOX_HALF, off_box, shmgen_binary  # noqa: E402

from shmgen_data import Dataset  # noqa: E402

#: The EXR layers of a view and how many components each holds per pixel.
LAYERS = {"depth": 1, "rest_depth": 1, "ray_distance": 1, "normals": 3, "displacement": 3, "flow": 2}


# ---------------------------------------------------------------------------------------
# The three readers, each called as docs/outputs.md tells a user to: components last, in
# component order ((x, y, z) or (u, v)), float32.


def by_opencv(path: Path, components: int) -> np.ndarray:
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    assert image is not None, f"OpenCV cannot read {path}"
    return from_colour_reader(path, image, components, bgr=True)


def by_imageio(path: Path, components: int) -> np.ndarray:
    image = iio.imread(path, plugin="opencv", flags=cv2.IMREAD_UNCHANGED)
    return from_colour_reader(path, image, components, bgr=False)


def from_colour_reader(path: Path, image: np.ndarray, components: int, bgr: bool) -> np.ndarray:
    """The components of what OpenCV (channels B, G, R) or imageio (R, G, B) returns: a grey
    image as it is, x, y, z from R, G, B, and u, v from R, G with B = 0."""
    assert image.dtype == np.float32, (path, image.dtype)
    if components == 1:
        assert image.ndim == 2, (path, image.shape)
        return image
    assert image.shape[2:] == (3,), (path, image.shape)
    rgb = image[..., ::-1] if bgr else image
    if components == 2:
        assert not rgb[..., 2].any(), f"{path}: the B of a flow file reads as 0"
        return rgb[..., :2]
    return rgb


def by_openexr(path: Path, components: int) -> np.ndarray:
    with OpenEXR.File(str(path)) as exr:  # R, G and B together as "RGB", as by default
        channels = {name: channel.pixels for name, channel in exr.channels().items()}
    if components == 1:
        assert list(channels) == ["Y"], (path, list(channels))
        image = channels["Y"]
    elif components == 2:
        assert sorted(channels) == ["G", "R"], (path, list(channels))
        image = np.stack([channels["R"], channels["G"]], axis=-1)
    else:
        assert list(channels) == ["RGB"], (path, list(channels))
        image = channels["RGB"]
    assert image.dtype == np.float32, (path, image.dtype)
    return image


READERS = {"opencv": by_opencv, "imageio": by_imageio, "openexr": by_openexr}


def read(reader: str, view, layer: str) -> np.ndarray:
    """``layer`` of ``view`` through ``reader``, shaped (H, W) or (H, W, components)."""
    image = READERS[reader](view.path(layer), LAYERS[layer])
    shape = (view.camera.height, view.camera.width) + ((LAYERS[layer],) if LAYERS[layer] > 1 else ())
    assert image.shape == shape, (view.path(layer), image.shape)
    return image


# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["box", "deformation"])
def test_the_three_readers_read_every_layer_alike_to_the_bit(name, request):
    """Every EXR of every view, clean or augmented copy: OpenCV, imageio and OpenEXR give the
    same float32 values (a depth OpenCV read as zeros, or a vector it read as one channel, fails
    here), and the values are not all zero where a surface is seen."""
    data = Dataset(request.getfixturevalue(name))
    copies = 0
    for view in data:
        copies += "a" in view.stem
        for layer in LAYERS:
            if layer not in view.layers:
                continue
            images = {reader: read(reader, view, layer) for reader in READERS}
            for reader, image in images.items():
                assert np.array_equal(image, images["openexr"]), (view.stem, layer, reader)
                assert np.isfinite(image).all()
            if layer != "displacement" and layer != "flow":  # a still box neither moves nor flows
                assert np.abs(images["opencv"]).max() > 0.1, (view.stem, layer)
            with OpenEXR.File(str(view.path(layer)), header_only=True) as exr:
                note = next(v for k, v in exr.header().items() if k.startswith("shmgen_"))
            assert note.startswith({1: "Y = ", 2: "R, G = u, v", 3: "R, G, B = x, y, z"}[LAYERS[layer]]), note
    assert copies > 0 or name != "box", "the box's augmented copies are read too"


def back_project(view, depth: np.ndarray):
    """World points of the pixels with depth (a pinhole camera: ``K``, ``c2w_opencv`` of the
    record), with their (row, column)."""
    record = view.record["camera"]
    assert record["model"] == "pinhole"
    K, c2w = np.array(record["K"]), np.array(record["c2w_opencv"])
    i, j = np.nonzero(depth)
    z = depth[i, j].astype(np.float64)
    rays = np.linalg.solve(K, np.stack([j + 0.5, i + 0.5, np.ones_like(z)]))
    return (rays * z).T @ c2w[:3, :3].T + c2w[:3, 3], (i, j)


@pytest.mark.parametrize("reader", list(READERS))
def test_depth_distance_and_normals_of_each_reader_fit_the_analytic_box(box, reader):
    """The box's views (clean and copies), read by ``reader``: depth and rest depth (the box
    bears no load) back-project onto the 2 × 1 × 0.5 m box exactly where the mask is; the ray
    distance is the distance of that point from the camera; the normals are unit vectors
    whose x, y, z, turned to world axes, are the outward normal of the face the point lies on
    (components in the wrong order, as OpenCV's B, G, R unreversed, fail)."""
    for view in Dataset(box):
        camera = np.array(view.record["camera"]["c2w_opencv"])
        for layer in ("depth", "rest_depth"):
            depth = read(reader, view, layer)
            assert np.array_equal(depth > 0, view.mask), (view.stem, layer)
            points, _ = back_project(view, depth)
            assert np.abs(off_box(points)).max() < 1e-5 * np.linalg.norm(camera[:3, 3]), (view.stem, layer)
        points, (i, j) = back_project(view, read(reader, view, "depth"))
        distance = read(reader, view, "ray_distance")
        assert np.allclose(distance[i, j], np.linalg.norm(points - camera[:3, 3], axis=1), rtol=1e-6)
        assert not distance[~view.mask].any()
        normals = read(reader, view, "normals").astype(np.float64)
        assert np.allclose(np.linalg.norm(normals[i, j], axis=1), 1, atol=1e-6)
        assert not normals[~view.mask].any()
        face = np.argmax(np.abs(points) / BOX_HALF, axis=1)
        outward = np.zeros_like(points)
        outward[np.arange(len(face)), face] = np.sign(points[np.arange(len(face)), face])
        edge = np.sort(np.abs(points) / BOX_HALF, axis=1)[:, -2] > 1 - 1e-4
        world = normals[i, j] @ camera[:3, :3].T
        assert np.abs(world - outward)[~edge].max() < 1e-5, view.stem


def project(view, points: np.ndarray) -> np.ndarray:
    """Pixel coordinates (x along a row, y down) of world points in a pinhole view."""
    record = view.record["camera"]
    K, w2c = np.array(record["K"]), np.array(record["w2c_opencv"])
    camera = points @ w2c[:3, :3].T + w2c[:3, 3]
    pixels = camera @ K.T
    return pixels[:, :2] / pixels[:, 2:]


@pytest.mark.parametrize("reader", list(READERS))
def test_flow_and_displacement_of_each_reader_carry_rest_points_to_the_loaded_image(deformation, reader):
    """Bent beams and a damaged silo, read by ``reader``: a flow-valid pixel p of the unloaded
    image sees the rest point r (rest depth back-projected); p + flow is where it lands in the
    loaded image, the pixel q there sees r moved by its displacement d (read at q: the field
    is smooth, so q's point is within a pixel's footprint of r's), and r + d projects to
    p + flow. Flow's (u, v) or displacement's (x, y, z) in another order miss by pixels."""
    checked = 0
    for view in Dataset(deformation):
        if view.record["camera"]["model"] != "pinhole":
            continue
        flow = read(reader, view, "flow").astype(np.float64)
        displacement = read(reader, view, "displacement").astype(np.float64)
        depth = read(reader, view, "depth")
        rest, (i, j) = back_project(view, np.where(view.flow_valid, read(reader, view, "rest_depth"), 0))
        assert not flow[~view.flow_valid].any()
        landed = np.stack([j + 0.5, i + 0.5], axis=1) + flow[i, j]
        qi, qj = np.floor(landed[:, 1]).astype(int), np.floor(landed[:, 0]).astype(int)
        # A valid flow lands on the structure, but may land in a silhouette pixel whose centre
        # ray misses it: those have no displacement to read.
        seen = depth[qi, qj] > 0
        assert seen.mean() > 0.95, (view.stem, seen.mean())
        moved = rest[seen] + displacement[qi[seen], qj[seen]]
        error = np.linalg.norm(project(view, moved) - landed[seen], axis=1)
        # Right: 95 % within 0.1 px (the displacement's change over the pixel's footprint);
        # flow or displacement components in another order: 0.56 to 9 px.
        assert np.quantile(error, 0.95) < 0.15, (view.stem, np.quantile(error, 0.95))
        assert np.abs(flow[i, j]).max() > 0.5, "the structure moves in the image"
        checked += 1
    assert checked >= 6


def test_a_dataset_with_the_channel_names_of_view_1_still_loads(box, tmp_path):
    """A dataset as shmgen.view/1 wrote it (depth Z, vectors X Y Z, flow U V; the records say
    so) loads in the Python loader with the same values, and `shmgen export --format png16`
    reads its depth as it reads today's."""
    old = tmp_path / "old"
    shutil.copytree(box, old)
    entries = [json.loads(line) for line in (old / "manifest.jsonl").read_text().splitlines()]
    for entry in entries:
        entry.pop("hashes", None)  # as an older shmgen wrote the manifest
    (old / "manifest.jsonl").write_text("".join(json.dumps(e) + "\n" for e in entries))
    legacy = {1: ["Z"], 2: ["U", "V"], 3: ["X", "Y", "Z"]}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for view in Dataset(old):
        for layer, components in LAYERS.items():
            image = by_openexr(view.path(layer), components).reshape(*view.mask.shape, components)
            names = ["Y"] if layer == "ray_distance" else legacy[components]
            planes = {n: np.ascontiguousarray(image[..., k]) for k, n in enumerate(names)}
            OpenEXR.File(header, planes).write(str(view.path(layer)))
        record_path = view.files["json"]
        record = json.loads(Path(record_path).read_text())
        record["schema"] = "shmgen.view/1"
        record["depth"]["channel"] = "Z"
        for key in ("normals", "displacement", "flow"):
            record[key]["channels"] = legacy[LAYERS[key]]
        Path(record_path).write_text(json.dumps(record))
    for before, after in zip(Dataset(box), Dataset(old)):
        assert after.record["schema"] == "shmgen.view/1"
        for layer in LAYERS:
            assert np.array_equal(before.load(layer), after.load(layer)), (after.stem, layer)
    exports = {}
    for name, root in (("new", box), ("old", old)):
        out = tmp_path / f"png16-{name}"
        done = subprocess.run([str(shmgen_binary()), "export", str(root), "--format", "png16", "--out", str(out)],
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        exports[name] = {p.relative_to(out): p.read_bytes() for p in out.rglob("*.png")}
    assert exports["old"] == exports["new"] and len(exports["new"]) >= 6
