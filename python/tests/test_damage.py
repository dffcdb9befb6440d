"""The damage layers through the loader: a beam with a placed flexural crack seen face-on
loads with the documented dtypes, the crack's pixels carry its class, instance and width, the
coverage sums to w/f along a row (f = depth / f_x, the footprint of a face seen face-on)."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import make
from shmgen_data import Dataset

RECIPE = """
dataset(#{ name: "crack", seed: 1, samples: 1, views: 1,
    outputs: ["rgb", "depth", "damage"],
    camera: #{ width: 160, height: 120, fov_y: deg(30), distance: [4.5, 4.5],
               pitch: [0.0, 0.0], yaw: [deg(-90), deg(-90)] },
    scene: |rng| beam(#{ length: 4.0, width: 0.3, height: 0.5 })
        .point_force(2.0, 1.0e3)
        .crack(#{ kind: "flexural", at: 2.0, face: "bottom", width_mm: 0.3, depth: 0.4 }),
})
"""


@pytest.fixture(scope="module")
def cracked(tmp_path_factory):
    return make(tmp_path_factory.mktemp("crack"), RECIPE, "crack")


def test_the_damage_layers_load_with_their_dtypes_and_agree(cracked):
    view = Dataset(cracked)[0]
    assert {"damage_class", "damage_instance", "crack_width", "crack_coverage"} <= set(view.layers)
    cls, inst = view.damage_class, view.damage_instance
    width, cover = view.crack_width, view.crack_coverage
    assert cls.dtype == np.int32 and inst.dtype == np.int32
    assert width.dtype == np.float32 and cover.dtype == np.float32
    crack = cls == 1
    assert crack.any()
    assert view.record["damage"]["classes"][1] == "flexural_crack"
    assert np.all(inst[crack] == 1) and np.allclose(width[crack], 0.3)
    assert np.all(cover[~crack] == 0) and np.all(width[~crack] == 0)
    # A row through the middle of the crack: coverage sums to w / f, f = depth / fx.
    rows = np.nonzero(crack.any(axis=1))[0]
    row = rows[len(rows) // 2]
    fx = view.record["camera"]["K"][0][0]
    f = view.depth[row, crack[row]].mean() / fx
    assert cover[row].sum() == pytest.approx(0.3e-3 / f, rel=0.01)
