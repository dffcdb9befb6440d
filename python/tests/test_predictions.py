"""Predictions written by the loader and scored by ``shmgen eval``; back-projection of a
predicted depth; PLY files read back by trimesh; the texture prompt; deterministic splits.

The independent truths: ``shmgen eval`` itself (it reads what the helpers write, and its
AbsRel of 1.1 × the truth is 0.1); the pinhole model (a depth d·k back-projects to the camera
centre plus k times the offset of the true point); trimesh's PLY reader; BLAKE2b computed
here for the split's documented rule.
"""

from __future__ import annotations

import hashlib
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
import trimesh

from conftest import REPO, make, shmgen, shmgen_binary
from shmgen_data import (Dataset, backproject, depth_prediction_path, fuse, read_ply, write_depth_prediction,
                         write_ply, write_surface_prediction)

PROMPTS = ["A photo of rusty steel beam for construction", "A photo of plastic board for construction",
           "A photo of cracked timber for construction"]


@pytest.fixture(scope="module")
def a1(tmp_path_factory) -> Path:
    """scripts/a1_beams.rhai, 6 beams × 2 views at 48 × 48, with meshes."""
    return make(tmp_path_factory.mktemp("a1"), None, "a1", recipe=REPO / "scripts" / "a1_beams.rhai",
                settings={"samples": 6, "views": 2, "size": 48, "textures": "false",
                          "outputs": "rgb,depth,mask,mesh"})


def evaluate(data: Path, predictions: Path, *extra: str) -> tuple[int, dict]:
    """``shmgen eval`` with a JSON report: its exit code and the report."""
    report = predictions.with_suffix(".json")
    done = subprocess.run([str(shmgen_binary()), "eval", str(data), str(predictions), "--json", str(report),
                           *extra], capture_output=True, text=True)
    assert done.returncode in (0, 2), done.stderr
    return done.returncode, json.loads(report.read_text())


def test_depth_predictions_land_where_eval_reads_them(a1: Path, tmp_path: Path) -> None:
    data = Dataset(a1)
    predictions = tmp_path / "p"
    for view in data:
        path = write_depth_prediction(predictions, view, 1.1 * view.depth.astype(np.float64))
        assert path == predictions / "samples" / "0000" / f"{view.stem}.depth.npy"
        assert np.load(path).dtype == np.float32
    rc, report = evaluate(a1, predictions)
    assert rc == 0 and report["complete"]
    assert report["depth_counts"]["images"] == len(data)
    assert report["abs_rel"] == pytest.approx(0.1, abs=1e-6)
    assert len(report["images"]) == len(data)


def test_a_prediction_is_checked_before_it_is_written(a1: Path, tmp_path: Path) -> None:
    view = Dataset(a1)[0]
    p = tmp_path / "p"
    with pytest.raises(ValueError, match=r"shape \(48, 47\); the view is 48 × 48"):
        write_depth_prediction(p, view, np.ones((48, 47)))
    infinite = np.ones((48, 48))
    infinite[3, 4] = np.inf
    with pytest.raises(ValueError, match=r"pixel \(row 3, column 4\) holds inf.*NaN"):
        write_depth_prediction(p, view, infinite)
    with pytest.raises(ValueError, match="not real numbers"):
        write_depth_prediction(p, view, np.full((48, 48), "a"))
    with pytest.raises(ValueError, match="not inside the dataset"):
        write_depth_prediction(a1 / "predictions", view, np.ones((48, 48)))
    exr = depth_prediction_path(p, view).with_name(f"{view.stem}.depth.exr")
    exr.parent.mkdir(parents=True)
    exr.write_bytes(b"")
    with pytest.raises(ValueError, match="already predicts view"):
        write_depth_prediction(p, view, np.ones((48, 48)))
    assert not depth_prediction_path(p, view).exists()
    # NaN marks a pixel not predicted: written, and counted by eval as left out.
    exr.unlink()
    holes = view.depth.astype(np.float64)
    holes[view.mask] = np.nan
    write_depth_prediction(p, view, holes)
    rc, report = evaluate(a1, p)
    assert rc == 2 and report["depth_counts"]["missing"] == len(Dataset(a1)) - 1
    assert report["depth_counts"]["excluded_pixels"] == int(view.mask.sum())


def test_a_predicted_depth_back_projects_along_the_true_rays(a1: Path) -> None:
    view = Dataset(a1)[1]
    truth = backproject(view)
    same = backproject(view, depth=view.depth)
    np.testing.assert_array_equal(same.points, truth.points)
    # Twice the planar depth: the same rays, twice as far from the camera centre.
    far = backproject(view, depth=2.0 * view.depth)
    centre = view.camera.position
    np.testing.assert_allclose(far.points - centre, 2.0 * (truth.points - centre), atol=1e-12)
    # NaN and values ≤ 0 give no point.
    holes = view.depth.astype(np.float64)
    rows, cols = np.nonzero(view.depth > 0)
    holes[rows[0], cols[0]], holes[rows[1], cols[1]] = np.nan, -1.0
    assert len(backproject(view, depth=holes)) == len(truth) - 2
    with pytest.raises(ValueError, match="view 000000_01"):
        backproject(view, depth=np.ones((4, 4)))
    sample = Dataset(a1).samples[0]
    fused = fuse(sample, depths={v.stem: 2.0 * v.depth for v in sample.views})
    np.testing.assert_allclose(fused.points, fuse(sample, depths=lambda v: 2.0 * v.depth).points)
    assert len(fused) == len(fuse(sample))
    with pytest.raises(KeyError, match="no depth map given for view 000000_01"):
        fuse(sample, depths={sample.views[0].stem: sample.views[0].depth})


def test_ply_files_round_trip_through_trimesh_and_eval(a1: Path, tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    points = rng.normal(size=(50, 3))
    faces = np.array([[0, 1, 2], [2, 3, 4], [4, 5, 0]])
    colours = rng.integers(0, 256, size=(50, 3))
    path = write_ply(tmp_path / "mesh.ply", points, faces=faces, colours=colours)
    mesh = trimesh.load(path, process=False)
    np.testing.assert_array_equal(mesh.vertices, points)
    np.testing.assert_array_equal(mesh.faces, faces)
    np.testing.assert_array_equal(mesh.visual.vertex_colors[:, :3], colours)
    ours = read_ply(path)
    np.testing.assert_array_equal(ours.xyz(), points)
    cloud = trimesh.load(write_ply(tmp_path / "cloud.ply", points), process=False)
    np.testing.assert_array_equal(cloud.vertices, points)
    with pytest.raises(ValueError, match="vertex 50"):
        write_ply(tmp_path / "bad.ply", points, faces=[[0, 1, 50]])
    with pytest.raises(ValueError, match="not finite"):
        write_ply(tmp_path / "bad.ply", [[0.0, np.nan, 0.0]])
    # Each sample's own mesh as its prediction: Chamfer 0 and F-score 1 from eval; the fused
    # cloud of its true depth lies on the surface (accuracy a fraction of a millimetre).
    data = Dataset(a1)
    meshes, clouds = tmp_path / "meshes", tmp_path / "clouds"
    for sample in data.samples:
        mesh = sample.mesh()
        written = write_surface_prediction(meshes, sample, mesh.vertices, faces=mesh.faces)
        assert written == meshes / "samples" / "0000" / f"{sample.index:06}.ply"
        write_surface_prediction(clouds, sample, fuse(sample).points)
    rc, report = evaluate(a1, meshes, "--surface-samples", "2000")
    assert rc == 0 and report["surface"]["chamfer_l1"] < 1e-12 and report["surface"]["fscore"] == 1.0
    assert [s["sample"] for s in report["samples"]] == list(range(6))
    rc, report = evaluate(a1, clouds, "--surface-samples", "2000")
    assert report["surface"]["accuracy"] < 5e-4


def test_the_texture_prompt_is_a_view_label(a1: Path) -> None:
    for view in Dataset(a1):
        assert view.prompt == PROMPTS[view.sample % 3]
        assert view.prompts == {"beam": PROMPTS[view.sample % 3]}
        assert view.structures["beam"].prompt == view.prompt


def test_splits_hold_out_whole_groups_by_a_documented_rule(a1: Path) -> None:
    data = Dataset(a1)
    timber = data.split(by="prompt", holdout=PROMPTS[2])
    assert {v.prompt for v in timber.test} == {PROMPTS[2]}
    assert PROMPTS[2] not in {v.prompt for v in timber.train}
    assert len(timber.test) + len(timber.train) == len(data) and timber.held_out == [PROMPTS[2]]
    assert data.split(by="scene.structures.0.material.prompt", holdout=PROMPTS[2]).test_indices == timber.test_indices
    support = data.split(by="support", holdout="cantilever")
    assert all(v.record["scene"]["structures"][0]["support"] == "cantilever" for v in support.test)
    # By sample, half of the 6 samples: the ones first in BLAKE2b order of "0\0{index}".
    half = data.split(fraction=0.5)
    order = sorted(range(6), key=lambda k: (hashlib.blake2b(f"0\0{k}".encode(), digest_size=8).digest(), str(k)))
    assert sorted(half.held_out) == sorted(order[:3])
    assert {v.sample for v in half.test} == set(order[:3])
    assert {v.sample for v in half.train} == set(order[3:])
    assert half.test_indices == data.split(fraction=0.5).test_indices, "the same on every call"
    seeded = sorted(range(6), key=lambda k: (hashlib.blake2b(f"1\0{k}".encode(), digest_size=8).digest(), str(k)))
    assert sorted(data.split(fraction=0.5, seed=1).held_out) == sorted(seeded[:3])
    # At least one group, never all of them.
    assert len(data.split(fraction=0.01).held_out) == 1 and len(data.split(fraction=0.99).held_out) == 5
    assert data.split(by=lambda v: v.view, holdout=1).test_indices == [i for i, v in enumerate(data) if v.view == 1]
    with pytest.raises(ValueError, match="no view has that prompt"):
        data.split(by="prompt", holdout="A photo of cracked timbre")
    with pytest.raises(ValueError, match="not both"):
        data.split(holdout=1, fraction=0.1)
