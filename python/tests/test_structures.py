"""Views say whether they are clean or augmented copies and of which clean view, and reach
structures by name; checked against what the record promises, seen in the pixels: a copy's
camera is its clean view's moved by the recorded warp, a photometric copy keeps its clean
view's geometry, and each named structure's pixels back-project onto where the recipe put it."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import make

from shmgen_data import Dataset, backproject

#: Two boxes of the same name, 3 m apart along x, and a pier between them: names, instance
#: ids and parts are told apart by where their pixels lie in the world.
NAMED_RECIPE = """
dataset(#{ name: "named", seed: 2, samples: 1, views: 2,
    outputs: ["rgb", "depth", "mask", "parts", "instances"],
    camera: #{ width: 160, height: 120, pitch: [0.5, 0.6], yaw: [1.4, 1.7], distance: 12.0 },
    scene: |rng| [
        assembly("box", [shape::box(1.0, 1.0, 1.0).part("block")]).translate(-3.0, 0.0, 0.0),
        assembly("box", [shape::box(1.0, 1.0, 1.0).part("block")]).translate(3.0, 0.0, 0.0),
        assembly("pier", [shape::box(0.6, 0.6, 2.0).part("shaft"),
                          shape::box(1.2, 1.0, 0.3).translate(0.0, 0.0, 1.15).part("cap")]),
    ],
})
"""

#: Copies made by colour operations only: the camera and the geometry are the clean view's.
PHOTOMETRIC_RECIPE = """
dataset(#{ name: "photometric", seed: 5, samples: 1, views: 2,
    outputs: ["rgb", "depth", "mask", "instances"],
    camera: #{ width: 96, height: 64 },
    augment: #{ copies: 2, operations: [
        #{ op: "colour_jitter", brightness: [0.6, 0.7], contrast: [0.8, 1.2], saturation: [0.8, 1.2], hue: [-0.1, 0.1], probability: 1.0 },
    ] },
    scene: |rng| assembly("box", [shape::box(2.0, 1.0, 0.5)]),
})
"""


def similarity(uv: np.ndarray, warp: dict) -> np.ndarray:
    """The record's warp of pixel coordinates: x′ = zoom·R(angle)·(x − centre) + centre + shift
    (docs/schema/view.schema.json, Similarity), R turning the picture clockwise on screen."""
    c, s = np.cos(warp["angle"]), np.sin(warp["angle"])
    rotation = np.array([[c, -s], [s, c]])
    centre = np.array(warp["centre"])
    return warp["zoom"] * (uv - centre) @ rotation.T + centre + np.array(warp["shift"])


def test_a_copy_is_its_clean_view_seen_through_the_recorded_warp(box):
    data = Dataset(box)
    copies = [view for view in data if view.is_copy]
    assert len(copies) == len(data) // 2 and copies, "one copy per view"
    for sample in data.samples:
        for copy in sample.copies():
            clean = sample.clean_view(copy)
            assert not clean.is_copy and clean.augmentation is None and clean.clean_stem == clean.stem
            assert (clean.sample, clean.view, clean.stem) == (copy.sample, copy.view, copy.clean_stem)
            augmentation = copy.augmentation
            assert augmentation is not None and augmentation.copy == copy.copy == 0
            assert augmentation.mode == "exact" and augmentation.geometric
            warp = next(op for op in augmentation.operations if op["op"] == "warp")
            # The same camera centre (an exact warp turns and zooms the camera, never moves it)…
            assert np.allclose(copy.camera.position, clean.camera.position, atol=1e-9)
            # …and every surface point the clean view sees lands, in the copy, where the warp
            # takes the clean pixel.
            points = backproject(clean).points
            uv_clean, _ = clean.camera.project(points)
            uv_copy, z = copy.camera.project(points)
            assert np.all(z > 0)
            assert np.abs(uv_copy - similarity(uv_clean, warp)).max() < 1e-6, copy.stem


def test_a_photometric_copy_keeps_its_clean_views_geometry(tmp_path):
    data = Dataset(make(tmp_path, PHOTOMETRIC_RECIPE, "photometric"))
    sample = data.samples[0]
    assert [v.stem for v in sample.clean_views()] == ["000000_00", "000000_01"]
    assert [v.stem for v in sample.copies()] == ["000000_00a0", "000000_00a1", "000000_01a0", "000000_01a1"]
    for copy in sample.copies():
        clean = sample.clean_view(copy)
        augmentation = copy.augmentation
        assert augmentation is not None and not augmentation.geometric
        assert [op["op"] for op in augmentation.operations] == ["colour_jitter"]
        assert np.array_equal(copy.depth, clean.depth) and np.array_equal(copy.instances, clean.instances)
        assert np.array_equal(copy.K, clean.K) and np.array_equal(copy.c2w, clean.c2w)
        # Brightness drawn in 0.6–0.7: the copy is darker where the structure is.
        surface = clean.mask
        assert copy.rgb[surface].mean() < 0.8 * clean.rgb[surface].mean()


def test_structures_by_name_are_their_pixels_in_the_world(tmp_path):
    data = Dataset(make(tmp_path, NAMED_RECIPE, "named"))
    for view in data:
        structures = view.structures
        assert list(structures) == ["box#0", "box#1", "pier"]
        assert [s.instance_id for s in structures.values()] == [1, 2, 3]
        part_ids = view.record["segmentation"]["part_ids"]
        assert structures["pier"].parts == ("shaft", "cap")
        assert [part_ids[i] for i in structures["pier"].part_ids] == ["shaft", "cap"]
        assert structures["box#1"].parts == ("block",) and structures["box#1"].labels is None
        # Where each named structure is, in the world: its pixels back-project into its box.
        centres = {"box#0": (-3.0, 0.5), "box#1": (3.0, 0.5), "pier": (0.0, 0.6)}
        seen = np.zeros_like(view.mask)
        for name, (x, half) in centres.items():
            where = view.structure_mask(name)
            assert where.sum() > 20, (view.stem, name)
            points = backproject(view, where=where).points
            assert np.all(np.abs(points[:, 0] - x) <= half + 1e-6), (view.stem, name)
            assert set(np.unique(view.parts[where])) <= set(structures[name].part_ids)
            assert structures.by_instance(structures[name].instance_id).name == name
            seen |= where
        assert np.array_equal(seen, view.mask), "the named structures are the whole mask"
        with pytest.raises(KeyError, match="no structure named 'box'.*'box#0', 'box#1', 'pier'"):
            structures["box"]

