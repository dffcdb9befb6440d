"""Flow, points and COLMAP tracks read back by other people's readers: OpenCV reads the
Middlebury ``.flo`` files and the KITTI PNGs (in its BGR order, decoded with the KITTI devkit's
formula) of ``shmgen export --format flow``, compared with the dataset's ``flow.exr`` read by
the OpenEXR package; trimesh reads the colours of ``points.ply``; COLMAP's text model is
parsed here and its 2-D points checked against OpenCV's own projection (``cv2.projectPoints``,
its lens model) of the 3-D points."""

from __future__ import annotations

import functools
import json

import cv2
import numpy as np
import OpenEXR
import pytest
import trimesh
from conftest import make, shmgen
from PIL import Image

from shmgen_data import Dataset

#: KITTI's flow PNG: 64 steps a pixel around 2¹⁵ (devkit: flow_u = (R − 2¹⁵) / 64).
KITTI_SCALE, KITTI_ZERO = 64.0, 2.0**15


def exr_channels(path) -> dict[str, np.ndarray]:
    """Every channel of an EXR file, through the OpenEXR package."""
    with OpenEXR.File(str(path), separate_channels=True) as f:
        return {name: np.array(c.pixels) for name, c in f.channels().items()}


def views_with_flow(root):
    """Every view stem of the dataset at ``root`` that has a flow, with its folder."""
    for path in sorted((root / "samples").glob("*/*.flow.exr")):
        yield path.parent.relative_to(root), path.name.split(".")[0]


def test_flow_exports_read_back_by_opencv_as_the_exr_holds_them(deformation, tmp_path):
    out = tmp_path / "flow"
    shmgen("export", deformation, "--format", "flow", "--out", out)
    record = json.loads((out / "export.json").read_text())
    assert record["format"] == "flow"
    assert record["flow"]["kitti_out_of_range_pixels"] == 0
    moved = 0
    for folder, stem in views_with_flow(deformation):
        exr = exr_channels(deformation / folder / f"{stem}.flow.exr")
        exr = {"U": exr["R"], "V": exr["G"]}  # flow's channels R, G hold U, V
        u, v = exr["U"].astype(np.float64), exr["V"].astype(np.float64)
        with Image.open(deformation / folder / f"{stem}.flow_valid.png") as image:
            valid = np.array(image) == 255
        assert valid.any(), stem

        flo = cv2.readOpticalFlow(str(out / folder / f"{stem}.flo"))
        assert flo.shape == (*u.shape, 2) and flo.dtype == np.float32
        assert np.array_equal(flo[valid, 0], exr["U"][valid]), "float32 kept exactly"
        assert np.array_equal(flo[valid, 1], exr["V"][valid])
        assert np.all(flo[~valid] == np.float32(1e10)), "unknown flow is 1e10 (above 1e9)"

        bgr = cv2.imread(str(out / folder / f"{stem}.flow_kitti.png"), cv2.IMREAD_UNCHANGED)
        assert bgr.dtype == np.uint16 and bgr.shape == (*u.shape, 3)
        # OpenCV gives BGR: the devkit's R (u) is channel 2, G (v) channel 1, B (valid) 0.
        kitti_u = (bgr[..., 2].astype(np.float64) - KITTI_ZERO) / KITTI_SCALE
        kitti_v = (bgr[..., 1].astype(np.float64) - KITTI_ZERO) / KITTI_SCALE
        assert np.array_equal(bgr[..., 0] == 1, valid)
        assert np.all(bgr[..., 0] <= 1)
        assert np.all(bgr[~valid] == 0), "invalid pixels are (0, 0, 0), as the devkit writes"
        half_step = 0.5 / KITTI_SCALE + 1e-9
        assert np.abs(kitti_u - u)[valid].max() <= half_step
        assert np.abs(kitti_v - v)[valid].max() <= half_step
        moved += int((np.hypot(u, v)[valid] > 0.5).sum())

        # The pair the flow relates, beside it.
        for kind in ("rest_rgb", "rgb"):
            exported = np.array(Image.open(out / folder / f"{stem}.{kind}.png"))
            assert np.array_equal(exported, np.array(Image.open(deformation / folder / f"{stem}.{kind}.png")))
    assert moved > 1000, "bent beams and a damaged silo move many pixels by more than half a pixel"


#: Two plain boxes side by side, colours that are whole sRGB levels: 204, 51, 25 and 25, 102, 229.
TWO_BOXES = """
dataset(#{ name: "two", seed: 2, samples: 1, views: 3, outputs: ["rgb", "depth", "mask", "points"],
    points: 4000, camera: #{ width: 96, height: 72, pitch: [0.3, 0.8] },
    scene: |rng| [
        assembly("left", [shape::box(1.0, 1.0, 1.0).translate(-1.0, 0.0, 0.0)]).colour([0.8, 0.2, 0.09803921568627451]),
        assembly("right", [shape::box(1.0, 1.0, 1.0).translate(1.0, 0.0, 0.0)]).colour([0.09803921568627451, 0.4, 0.8980392156862745]),
    ],
})
"""


def test_points_carry_the_colour_of_the_surface_they_lie_on(tmp_path):
    root = make(tmp_path, TWO_BOXES, "two")
    cloud = trimesh.load(root / "samples" / "0000" / "000000.points.ply")
    assert isinstance(cloud, trimesh.PointCloud)
    colours = np.asarray(cloud.colors)[:, :3]
    x = np.asarray(cloud.vertices)[:, 0]
    assert len(x) == 4000
    assert np.all(np.abs(np.abs(x) - 1.0) <= 0.5 + 1e-9), "every point on one of the boxes"
    assert np.all(colours[x < 0] == [204, 51, 25])
    assert np.all(colours[x > 0] == [25, 102, 229])
    # The loader reads them too.
    assert np.array_equal(Dataset(root).samples[0].points().colours, colours)


def read_points3d(path):
    """points3D.txt: {id: (xyz, rgb, error, [(image id, point2D index)])}."""
    points = {}
    for line in path.read_text().splitlines():
        if line.startswith("#"):
            continue
        w = line.split()
        track = [(int(w[i]), int(w[i + 1])) for i in range(8, len(w), 2)]
        points[int(w[0])] = (np.array(w[1:4], float), np.array(w[4:7], int), float(w[7]), track)
    return points


def read_images(path):
    """images.txt: {id: (name, camera id, rotation vector, t, [(x, y, point3D id)])}."""
    lines = [l for l in path.read_text().splitlines() if not l.startswith("#")]
    images = {}
    for pose, observations in zip(lines[0::2], lines[1::2], strict=True):
        w = pose.split()
        rvec = quaternion_vector(*map(float, w[1:5]))
        o = observations.split()
        obs = [(float(o[i]), float(o[i + 1]), int(o[i + 2])) for i in range(0, len(o), 3)]
        images[int(w[0])] = (w[9], int(w[8]), rvec, np.array(w[5:8], float), obs)
    return images


def quaternion_vector(w, x, y, z) -> np.ndarray:
    """The rotation vector (axis × angle) of a unit Hamilton quaternion, for cv2.Rodrigues."""
    s = np.sqrt(x * x + y * y + z * z)
    angle = 2.0 * np.arctan2(s, w)
    return np.zeros(3) if s == 0 else np.array([x, y, z]) / s * angle


def read_cameras(path):
    """cameras.txt: {id: (K, OpenCV's distortion coefficients k1 k2 p1 p2 k3)}."""
    cameras = {}
    for line in path.read_text().splitlines():
        if line.startswith("#"):
            continue
        w = line.split()
        p = [float(v) for v in w[4:]]
        K = np.array([[p[0], 0, p[2]], [0, p[1], p[3]], [0, 0, 1]])
        lens = {"PINHOLE": [0.0] * 5, "OPENCV": p[4:8] + [0.0], "FULL_OPENCV": p[4:9]}[w[1]]
        cameras[int(w[0])] = (K, np.array(lens))
    return cameras


@functools.cache
def rgb_of(path) -> np.ndarray:
    with Image.open(path) as image:
        return np.array(image)


@pytest.mark.parametrize("name", ["box", "box_lens"])
def test_colmap_tracks_are_opencv_projections_coloured_by_their_pixels(name, request, tmp_path):
    root = request.getfixturevalue(name)
    out = tmp_path / "colmap"
    shmgen("export", root, "--format", "colmap", "--out", out)
    for scene in sorted(p for p in out.iterdir() if p.is_dir()):
        sparse = scene / "sparse" / "0"
        points, images = read_points3d(sparse / "points3D.txt"), read_images(sparse / "images.txt")
        cameras = read_cameras(sparse / "cameras.txt")
        assert len(points) > 100, "the box's points seen by the views"
        # Each track entry names a 2-D point that names the track's 3-D point back.
        entries = 0
        for pid, (_, _, error, track) in points.items():
            assert track and error == 0.0
            for image_id, index in track:
                assert images[image_id][4][index][2] == pid
                entries += 1
        assert entries == sum(len(image[4]) for image in images.values()), \
            "every 2-D point belongs to one track entry"
        # Each 2-D point is OpenCV's projection of its 3-D point; colours are the mean of the
        # pixels the 2-D points fall in.
        sums = {pid: np.zeros(3) for pid in points}
        for name_, camera_id, rvec, t, obs in images.values():
            xy = np.array([(x, y) for x, y, _ in obs])
            xyz = np.array([points[pid][0] for _, _, pid in obs])
            K, lens = cameras[camera_id]
            projected, _ = cv2.projectPoints(xyz, rvec, t, K, lens)
            # COLMAP's and shmgen's pixel centres are at +0.5, as OpenCV's K here says.
            assert np.abs(projected.reshape(-1, 2) - xy).max() < 1e-3, name_
            rgb = rgb_of(scene / "images" / name_)
            for (x, y, pid) in obs:
                sums[pid] += rgb[int(np.floor(y)), int(np.floor(x))]
        for pid, (_, colour, _, track) in points.items():
            # The mean over the track, halves rounded up.
            assert np.array_equal(colour, np.floor(sums[pid] / len(track) + 0.5)), pid
