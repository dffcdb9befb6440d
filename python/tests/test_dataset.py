"""Every file of every view and sample loads with the documented shape and dtype, and agrees
with the README's conventions and with an independent reader (trimesh for the meshes)."""

from __future__ import annotations

import json
import shutil
import struct

import numpy as np
import pytest
import trimesh

from conftest import REPO, make
from shmgen_data import Dataset, MissingFileError, read_ply

#: The README's file list: output → (shape after (H, W), dtype).
EXPECTED = {
    "rgb": ((3,), np.uint8),
    "rest_rgb": ((3,), np.uint8),
    "depth": ((), np.float32),
    "rest_depth": ((), np.float32),
    "ray_distance": ((), np.float32),
    "normals": ((3,), np.float32),
    "displacement": ((3,), np.float32),
    "flow": ((2,), np.float32),
    "mask": ((), np.bool_),
    "cracks": ((), np.bool_),
    "erased": ((), np.bool_),
    "valid": ((), np.bool_),
    "flow_valid": ((), np.bool_),
    "parts": ((), np.int32),
    "instances": ((), np.int32),
}


@pytest.mark.parametrize("name", ["box", "box_lens", "deformation"])
def test_every_view_loads_with_its_shape_and_dtype(name, request):
    root = request.getfixturevalue(name)
    data = Dataset(root)
    run = json.loads((root / "run.json").read_text())
    per_view = {k for k, on in run["dataset"]["outputs"].items()
                if on and k not in ("mesh", "mesh_gltf", "points")}
    if "flow" in per_view:
        per_view.add("flow_valid")  # the flow's validity comes with it
    copies = run["dataset"]["augment"]["copies"]
    assert len(data) == run["dataset"]["samples"] * run["dataset"]["views"] * (1 + copies)
    seen = 0
    for view in data:
        assert set(view.layers) == per_view, view.stem
        # The stem is the record's sample and view (and copy).
        record = view.record
        stem = f"{record['sample']:06}_{record['view']:02}"
        if record["augmentation"] is not None:
            stem += f"a{record['augmentation']['copy']}"
        assert view.stem == stem
        height, width = record["camera"]["height"], record["camera"]["width"]
        for layer in view.layers:
            values = view.load(layer)
            assert getattr(view, layer) is values, "each output is a declared attribute of View"
            tail, dtype = EXPECTED[layer]
            assert values.shape == (height, width, *tail), (view.stem, layer)
            assert values.dtype == dtype, (view.stem, layer)
            if values.dtype.kind == "f":
                assert np.all(np.isfinite(values)), (view.stem, layer)
        # README: 0 = no surface, everywhere the mask says background.
        surface = view.depth > 0
        assert np.array_equal(surface, view.mask), view.stem
        assert np.all(view.depth >= 0)
        assert np.array_equal(view.ray_distance > 0, surface)
        assert np.all(view.ray_distance >= view.depth - 1e-6 * view.depth)
        assert np.array_equal(view.parts > 0, surface)
        normals = view.normals
        length = np.linalg.norm(normals, axis=-1)
        assert np.allclose(length[surface], 1.0, atol=1e-5)
        assert np.all(length[~surface] == 0)
        assert np.all(view.flow[~view.flow_valid] == 0)
        assert not np.any(view.flow_valid & (view.rest_depth == 0)), "flow is defined on the rest image"
        # Poses: inverse of each other; OpenGL = OpenCV · diag(1, −1, −1, 1); K as documented.
        assert np.allclose(view.c2w @ view.w2c, np.eye(4), atol=1e-12)
        assert np.allclose(view.c2w_opengl, view.c2w @ np.diag([1.0, -1.0, -1.0, 1.0]), atol=0)
        assert np.allclose(view.c2w[:3, 3], record["camera"]["position"], atol=1e-12)
        K = view.K
        assert K.shape == (3, 3) and K[0, 1] == 0 and np.array_equal(K[2], [0, 0, 1])
        assert view.distortion.shape == (5,)
        assert len(view.labels) == len(record["scene"]["structures"])
        seen += 1
    assert seen == len(data)


def test_views_of_the_box_see_its_segmentation(box):
    data = Dataset(box)
    for view in data:
        table = view.record["segmentation"]
        assert table["part_ids"][0] == "background"
        assert set(np.unique(view.parts)) <= set(range(len(table["part_ids"])))
        assert set(np.unique(view.instances)) == {0, 1}  # one structure
        assert not view.cracks.any(), "a plain box has no cracks"
        if view.copy is None:
            assert not view.erased.any()
        else:
            assert view.erased.any(), "every copy erases a rectangle (probability 1)"
            assert view.record["augmentation"]["copy"] == view.copy


def test_beam_labels_come_with_the_views(deformation):
    data = Dataset(deformation)
    beams = [s for s in data.samples if "beam" in s.structures]
    assert beams, "the deformation recipe's seed draws beams"
    for sample in beams:
        labels = sample.labels["beam"]
        assert labels is not None and labels["max_deflection"] > 0
        assert labels["theory"] in ("euler_bernoulli", "timoshenko", "elastica")
        assert labels["loads"]
        # Reached by the beam's name, with its ids in the segmentation images.
        beam = sample.structures["beam"]
        assert (beam.kind, beam.index, beam.instance_id) == ("beam", 0, 1)
        assert beam.labels == labels and list(sample.labels) == ["beam"]
        for view in sample.views:
            assert view.labels == sample.labels  # shared by every view of the sample
            # The beam's part ids are where the view sees the beam (its only structure).
            assert np.array_equal(np.isin(view.parts, beam.part_ids), view.mask), view.stem


@pytest.mark.parametrize("name", ["box", "deformation"])
def test_meshes_read_as_trimesh_reads_them(name, request):
    data = Dataset(request.getfixturevalue(name))
    for sample in data.samples:
        mesh, rest = sample.mesh(), sample.rest_mesh()
        theirs = trimesh.load(sample.path("mesh.ply"), process=False)
        assert len(theirs.vertices) == len(mesh.vertices) == sample.record["mesh"]["vertices"]
        assert len(theirs.faces) == len(mesh.faces) == sample.record["mesh"]["triangles"]
        assert np.array_equal(theirs.vertices, mesh.vertices)
        assert np.array_equal(theirs.faces, mesh.faces)
        assert np.array_equal(theirs.bounds, mesh.bounds)
        # rest.ply: the same vertex count and the same faces, vertices in the same order.
        their_rest = trimesh.load(sample.path("rest.ply"), process=False)
        assert len(their_rest.vertices) == len(rest.vertices) == len(mesh.vertices)
        assert np.array_equal(their_rest.faces, mesh.faces)
        assert np.array_equal(rest.faces, mesh.faces) and np.array_equal(rest.parts, mesh.parts)
        assert np.array_equal(their_rest.vertices, rest.vertices)
        # Part ids name parts of the segmentation table.
        assert set(np.unique(mesh.parts)) <= set(range(1, len(sample.record["segmentation"]["part_ids"])))
        # The points lie on the loaded surface, with unit normals.
        points = sample.points()
        assert len(points.points) == data.run["dataset"]["points"]
        _, distance, _ = trimesh.proximity.closest_point(theirs, points.points)
        assert distance.max() < 1e-9 * np.ptp(mesh.vertices, axis=0).max()
        assert np.allclose(np.linalg.norm(points.normals, axis=1), 1.0, atol=1e-6)
        if name == "box":
            # A closed box: watertight, outward normals, its volume the analytic one.
            assert theirs.is_watertight and np.isclose(theirs.volume, 2.0 * 1.0 * 0.5)
            assert np.all(np.abs(rest.vertices) <= [1.0, 0.5, 0.25])


def _write_ply(path, header_format, vertices, faces):
    """A PLY written here with struct, independently of the reader: float x y z, a list of
    varying length per face."""
    end = "<" if header_format == "binary_little_endian" else ">"
    lines = ["ply", f"format {header_format} 1.0", "comment made by a test",
             f"element vertex {len(vertices)}", "property float x", "property float y",
             "property float z", f"element face {len(faces)}",
             "property list uchar int vertex_indices", "property short part", "end_header"]
    body = b"".join(struct.pack(end + "fff", *v) for v in vertices)
    for face, part in faces:
        body += struct.pack(end + "B", len(face)) + struct.pack(end + f"{len(face)}i", *face)
        body += struct.pack(end + "h", part)
    path.write_bytes(("\n".join(lines) + "\n").encode() + body)


@pytest.mark.parametrize("fmt", ["binary_little_endian", "binary_big_endian"])
def test_the_ply_reader_reads_both_byte_orders_and_polygons(tmp_path, fmt):
    vertices = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 0.5), (0.5, 2.0, 0.25)]
    triangles = [((0, 1, 2), 3), ((0, 2, 3), -7)]
    path = tmp_path / "t.ply"
    _write_ply(path, fmt, vertices, triangles)
    ply = read_ply(path)
    assert ply.comments == ["made by a test"]
    assert np.array_equal(ply.xyz(), np.array(vertices))
    assert ply["face"]["vertex_indices"].tolist() == [[0, 1, 2], [0, 2, 3]]
    assert ply["face"]["part"].tolist() == [3, -7]
    assert ply["face"]["part"].dtype.isnative
    mixed = [((0, 1, 2), 1), ((0, 2, 4, 3), 2)]  # a triangle and a quad
    _write_ply(path, fmt, vertices, mixed)
    faces = read_ply(path)["face"]["vertex_indices"]
    assert [f.tolist() for f in faces] == [[0, 1, 2], [0, 2, 4, 3]]
    assert read_ply(path)["face"]["part"].tolist() == [1, 2]
    path.write_bytes(path.read_bytes()[:-3])
    with pytest.raises(ValueError, match="t.ply"):
        read_ply(path)


def test_missing_and_unfinished_datasets_are_named(box, tmp_path):
    with pytest.raises(FileNotFoundError, match="run.json"):
        Dataset(tmp_path)
    copy = tmp_path / "copy"
    shutil.copytree(box, copy)
    data = Dataset(copy)
    view = data[0]
    # A file listed but deleted is named.
    missing = view.path("normals")
    missing.unlink()
    with pytest.raises(ValueError, match=missing.name):
        Dataset(copy)
    shutil.copy(box / missing.relative_to(copy), missing)
    # The manifest cut to its first sample: unfinished, unless asked for what is finished.
    manifest = copy / "manifest.jsonl"
    lines = manifest.read_text().splitlines(keepends=True)
    manifest.write_text(lines[1] + '{"sample": 0, "files": [')  # a torn append
    with pytest.raises(ValueError, match="not finished"):
        Dataset(copy)
    partial = Dataset(copy, complete=False)
    assert [s.index for s in partial.samples] == [1]
    assert all(v.sample == 1 for v in partial)
    with pytest.raises(KeyError, match="no sample 0"):
        partial.sample(0)
    # Frames of sample 0 written as a unit (`run --frames-per-unit`) are not a sample yet.
    unit = ('{"unit": {"sample": 0, "frames": [0, 2], "of": 5, "per_unit": 2}, "views": 1, '
            '"files": ["samples/0000/000000_00.json"], "hashes": {}}\n')
    manifest.write_text(lines[1] + unit)
    assert [s.index for s in Dataset(copy, complete=False).samples] == [1]
    # A sample without a points file, asked for one.
    (copy / "manifest.jsonl").write_text(
        "".join(line for line in lines if '"sample":0' in line.replace(" ", "")).replace(
            '"samples/0000/000000.points.ply",', ""))
    sample = Dataset(copy, complete=False).samples[0]
    with pytest.raises(MissingFileError, match='points.ply.*add "points"'):
        sample.points()


def test_an_output_not_written_is_named(deformation):
    view = Dataset(deformation)[0]
    with pytest.raises(MissingFileError, match=r"000000_00 .*'cracks'.*add \"cracks\""):
        view.cracks
    with pytest.raises(KeyError, match="unknown output 'colour'"):
        view.load("colour")
    assert Dataset(deformation, copies=False)[0].stem == "000000_00"


def test_every_frame_of_a_sequence_is_a_view_with_its_time_and_meshes(tmp_path):
    """scripts/monitoring.rhai, 6 frames of 2 fixed cameras: 12 views, each frame's record
    carries its time, and each frame's own meshes are kept apart (`f0003.mesh.ply`)."""
    out = make(tmp_path, None, "monitoring", recipe=REPO / "scripts" / "monitoring.rhai",
               settings={"samples": 1, "size": 32, "duration": 0.1,
                         "outputs": "rgb,depth,displacement,mesh"})
    sample = Dataset(out).samples[0]
    views = sample.views
    assert len(views) == 12
    frames = sorted((v.view, v.record["frame"]["index"]) for v in views)
    assert frames == [(view, k) for view in (0, 1) for k in range(6)]
    for v in views:
        assert v.record["frame"]["time"] == v.record["frame"]["index"] / 60.0
        assert v.displacement.shape == (32, 32, 3)
    assert {f"f{k:04}.mesh.ply" for k in range(6)} <= set(sample.files)
