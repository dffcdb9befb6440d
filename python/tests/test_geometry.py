"""Back-projection and fusion against independent truth: the analytic box, trimesh's
distances to the ground-truth mesh, and the mesh pair's vertex correspondence for the flow."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from conftest import BOX_HALF, BOX_RECIPE, make, off_box

from shmgen_data import Dataset, backproject, distort, fuse, undistort


def project(points, view):
    """World points through the view's camera, written here from the README's conventions:
    w2c, then OpenCV's Brown–Conrady distortion of (X/Z, Y/Z), then K."""
    record = view.record["camera"]
    w2c, K = np.array(record["w2c_opencv"]), np.array(record["K"])
    cam = points @ w2c[:3, :3].T + w2c[:3, 3]
    x, y = cam[:, 0] / cam[:, 2], cam[:, 1] / cam[:, 2]
    if record["model"] == "opencv":
        d = record["distortion"]
        r2 = x * x + y * y
        radial = 1 + d["k1"] * r2 + d["k2"] * r2**2 + d["k3"] * r2**3
        x, y = (x * radial + 2 * d["p1"] * x * y + d["p2"] * (r2 + 2 * x * x),
                y * radial + d["p1"] * (r2 + 2 * y * y) + 2 * d["p2"] * x * y)
    return np.stack([K[0, 0] * x + K[0, 1] * y + K[0, 2], K[1, 1] * y + K[1, 2]], axis=1)


@pytest.mark.parametrize("name", ["box", "box_lens"])
def test_depth_back_projects_onto_the_analytic_box(name, request):
    data = Dataset(request.getfixturevalue(name))
    assert len(data) == 12
    for view in data:
        cloud = backproject(view)
        assert len(cloud) == view.mask.sum() > 1000
        distance = np.linalg.norm(view.c2w[:3, 3])
        # Every point on a face of the 2 × 1 × 0.5 m box, to 1e-5 of the camera distance.
        assert np.abs(off_box(cloud.points)).max() < 1e-5 * distance, view.stem
        # ... and spread over the faces seen, not piled at one point.
        assert np.ptp(cloud.points, axis=0).max() > 1.0
        # Its distance from the camera centre is the written ray distance.
        rays = np.linalg.norm(cloud.points - view.c2w[:3, 3], axis=1)
        written = view.ray_distance[cloud.pixels[:, 0], cloud.pixels[:, 1]]
        assert np.allclose(rays, written, rtol=1e-6), view.stem
        # The normals file, turned to world axes, is the outward normal of the face the point
        # lies on, turned towards the camera.
        face = np.argmax(np.abs(cloud.points) / BOX_HALF, axis=1)
        outward = np.zeros_like(cloud.points)
        outward[np.arange(len(face)), face] = np.sign(cloud.points[np.arange(len(face)), face])
        normals = view.normals[cloud.pixels[:, 0], cloud.pixels[:, 1]].astype(np.float64)
        world = normals @ view.c2w[:3, :3].T
        # Pixels whose point lies within rounding of an edge may take either face's normal.
        edge = np.sort(np.abs(cloud.points) / BOX_HALF, axis=1)[:, -2] > 1 - 1e-4
        assert np.abs(world - outward)[~edge].max() < 1e-5, view.stem
        # The colours are the RGB pixels.
        assert np.array_equal(cloud.colours, view.rgb[cloud.pixels[:, 0], cloud.pixels[:, 1]])
        # Projected back (the projection written above, lens included), each point lands on
        # its pixel's centre.
        centres = cloud.pixels[:, ::-1] + 0.5
        assert np.abs(project(cloud.points, view) - centres).max() < 1e-6
        uv, z = view.camera.project(cloud.points)
        assert np.abs(uv - centres).max() < 1e-6 and np.all(z > 0)


def test_ignoring_the_lens_misses_the_box(box_lens):
    """The lens matters at these coefficients: back-projecting through K alone leaves the
    box by far more than the tolerance above (so that test does check the undistortion)."""
    view = Dataset(box_lens)[0]
    assert view.camera.model == "opencv"
    depth = view.depth
    i, j = np.nonzero(depth > 0)
    z = depth[i, j].astype(np.float64)
    cam = np.stack([(j + 0.5 - view.K[0, 2]) * z / view.K[0, 0],
                    (i + 0.5 - view.K[1, 2]) * z / view.K[1, 1], z], axis=1)
    world = cam @ view.c2w[:3, :3].T + view.c2w[:3, 3]
    assert np.abs(off_box(world)).max() > 1e-3


def test_undistortion_inverts_opencv_distortion():
    rng = np.random.default_rng(1)
    x, y = rng.uniform(-0.8, 0.8, (2, 10000))
    lens = (-0.12, 0.01, 0.001, -0.001, 0.003)
    xd, yd = distort(x, y, lens)
    ux, uy = undistort(xd, yd, lens)
    assert np.abs(ux - x).max() < 1e-12 and np.abs(uy - y).max() < 1e-12
    # The distortion itself, against OpenCV's documented formula at one point.
    r2 = 0.3**2 + 0.2**2
    radial = 1 - 0.12 * r2 + 0.01 * r2**2 + 0.003 * r2**3
    expected = (0.3 * radial + 2 * 0.001 * 0.06 - 0.001 * (r2 + 2 * 0.09),
                0.2 * radial + 0.001 * (r2 + 2 * 0.04) - 2 * 0.001 * 0.06)
    assert np.allclose(distort(np.array(0.3), np.array(0.2), lens), expected, atol=1e-15)
    # Barrel distortion x (1 − x²/2) peaks at x_d = 0.544 (x = 0.816): x_d = 2 is reached
    # only by x = −2, past the fold, seen through the centre; x_d = 0.6 by no real x.
    fold = (-0.5, 0.0, 0.0, 0.0, 0.0)
    for beyond in (2.0, 0.6):
        with pytest.raises(ArithmeticError, match="not one-to-one"):
            undistort(np.array([0.1, beyond]), np.array([0.0, 0.0]), fold)
    # Before the fold, the root of x − x³/2 = 0.5 nearest the centre: (√5 − 1)/2.
    assert np.isclose(undistort(np.array([0.5]), np.array([0.0]), fold)[0][0], (5**0.5 - 1) / 2, atol=1e-14)


def test_fused_beam_cloud_lies_on_the_ground_truth_mesh(deformation):
    data = Dataset(deformation)
    beams = [s for s in data.samples if "beam" in s.structures]
    sample = beams[0]
    cloud = fuse(sample)
    views = sample.clean_views()
    assert len(cloud) == sum(int(v.mask.sum()) for v in views)
    assert set(np.unique(cloud.views)) == set(range(len(views)))
    mesh = trimesh.load(sample.path("mesh.ply"), process=False)
    _, distance, _ = trimesh.proximity.closest_point(mesh, cloud.points)
    radius = sample.record["mesh"]["bounding_radius"]
    assert distance.max() < 1e-6 * radius, distance.max()
    # The views together see much of the beam: points near both ends and the soffit.
    lo, hi = mesh.bounds
    assert np.all(cloud.points.min(axis=0) < lo + 0.1 * (hi - lo))
    assert np.all(cloud.points.max(axis=0) > hi - 0.1 * (hi - lo))
    # The unloaded images back-project onto the unloaded mesh, and not onto the loaded one.
    rest_cloud = fuse(sample, rest=True)
    rest = trimesh.load(sample.path("rest.ply"), process=False)
    _, distance, _ = trimesh.proximity.closest_point(rest, rest_cloud.points)
    assert distance.max() < 1e-6 * radius
    _, off, _ = trimesh.proximity.closest_point(mesh, rest_cloud.points)
    labels = sample.labels["beam"]
    assert labels is not None and off.max() > 0.5 * abs(labels["max_deflection"])


def test_fusing_copies_adds_their_points(box, tmp_path):
    sample = Dataset(box).samples[0]
    clean, every = fuse(sample), fuse(sample, copies=True)
    assert len(every) == sum(int((v.mask & v.valid).sum()) for v in sample.views) > len(clean)
    assert np.abs(off_box(every.points)).max() < 1e-6
    # Without clean views (keep_clean: false), fusing needs the copies, and says so.
    only_copies = Dataset(make(tmp_path, BOX_RECIPE, "copies", settings={"keep_clean": "false"}))
    assert all(v.copy == 0 for v in only_copies)
    with pytest.raises(ValueError, match="no clean views.*copies=True"):
        fuse(only_copies.samples[0])
    assert np.abs(off_box(fuse(only_copies.samples[0], copies=True).points)).max() < 1e-6


def _correspondence(points, source, target):
    """Each point's place on the ``source`` mesh (trimesh's closest point and barycentric
    weights), carried over to ``target`` (the same faces over other vertices)."""
    closest, distance, triangle = trimesh.proximity.closest_point(source, points)
    weights = trimesh.triangles.points_to_barycentric(source.triangles[triangle], closest)
    return np.einsum("nk,nkd->nd", weights, target.triangles[triangle]), distance


def test_rest_point_plus_displacement_lands_at_rest_pixel_plus_flow(deformation):
    """On beams and a damaged silo: a flow-valid pixel of the unloaded image sees the rest
    point r (rest_depth back-projected); carried to the loaded mesh through the vertex
    correspondence of rest.ply and mesh.ply it is r + displacement, which projects (with K
    and w2c, written above) to the pixel centre plus the flow. And for every pixel of the
    loaded image, displacement.exr is the seen point minus its rest point."""
    data = Dataset(deformation)
    kinds = set()
    for sample in data.samples:
        mesh = trimesh.load(sample.path("mesh.ply"), process=False)
        rest = trimesh.load(sample.path("rest.ply"), process=False)
        radius = sample.record["mesh"]["bounding_radius"]
        kinds.update(structure.kind for structure in sample.structures.values())
        for view in sample.views:
            valid = view.flow_valid
            assert valid.sum() > 0.5 * (view.rest_depth > 0).sum(), view.stem
            seen = backproject(view, rest=True, where=valid)
            loaded, off = _correspondence(seen.points, rest, mesh)
            assert off.max() < 1e-6 * radius
            i, j = seen.pixels.T
            target = np.stack([j + 0.5, i + 0.5], axis=1) + view.flow[i, j]
            error = np.linalg.norm(project(loaded, view) - target, axis=1)
            assert error.max() < 1e-3, (view.stem, error.max())
            assert np.abs(view.flow[i, j]).max() > 0.5, "the structure moves in the image"

            points = backproject(view)
            before, off = _correspondence(points.points, mesh, rest)
            assert off.max() < 1e-6 * radius
            written = view.displacement[points.pixels[:, 0], points.pixels[:, 1]]
            assert np.abs(written - (points.points - before)).max() < 1e-6 * radius, view.stem
    assert kinds == {"beam", "assembly"}
