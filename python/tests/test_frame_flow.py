"""The flow between consecutive frames of a sequence as the loader reads it: ``flow_next`` and
``flow_prev`` with their validity, none valid at the ends of the sequence, and each the inverse
of the other (a point carried to the next frame and read back there returns where it came
from), also as training arrays."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from conftest import make
from shmgen_data import Dataset, view_arrays

# A beam crossed by a vehicle, filmed side-on by a fixed camera whose mount shakes.
RECIPE = """
dataset(#{ name: "frames", seed: 3, samples: 1, views: 1, outputs: ["depth", "mask", "frame_flow"],
    camera: #{ width: 96, height: 72, fov_y: deg(60),
        fixed: [#{ position: [1.0, -0.6, 0.12], target: [1.0, 0.0, 0.0] }] },
    sequence: #{ duration: 0.2, fps: 30.0, mount: #{ rotation: 2e-3, translation: 1e-3 } },
    scene: |rng| beam(#{ length: 2.0, width: 0.1, height: 0.2 }).simply_supported().at(1.0, 0.0, 0.0)
        .vehicle([[0.0, 3e5]], 8.0, 0.0),
})
"""


def test_flow_to_the_next_frame_and_back_is_the_identity(tmp_path: Path) -> None:
    views = list(Dataset(make(tmp_path, RECIPE, "frames")))
    frames = sorted(views, key=lambda v: v.record["frame"]["index"])
    assert [v.record["frame"]["index"] for v in frames] == list(range(6))
    assert not frames[0].flow_prev_valid.any() and not frames[-1].flow_next_valid.any()
    h, w = frames[0].camera.height, frames[0].camera.width
    checked = 0
    for this, that in zip(frames, frames[1:]):
        forward, valid = this.flow_next, this.flow_next_valid
        assert forward.shape == (h, w, 2) and forward.dtype == np.float32
        assert np.all(forward[~valid] == 0) and valid.sum() > 0.9 * this.mask.sum()
        rows, cols = np.nonzero(valid)
        # Where each point lands in the next frame, to the nearest pixel centre there.
        u = cols + 0.5 + forward[rows, cols, 0]
        v = rows + 0.5 + forward[rows, cols, 1]
        r, c = np.floor(v).astype(int), np.floor(u).astype(int)
        inside = (r >= 0) & (r < h) & (c >= 0) & (c < w)
        back_valid = that.flow_prev_valid[r[inside], c[inside]]
        back = that.flow_prev[r[inside], c[inside]][back_valid]
        there = np.stack([u, v], axis=1)[inside][back_valid]
        pixel = np.stack([c[inside], r[inside]], axis=1)[back_valid] + 0.5
        # Back from that pixel's centre: within the flow's change across half a pixel.
        returned = pixel + back
        start = np.stack([cols, rows], axis=1)[inside][back_valid] + 0.5
        error = np.abs(returned - (start + (pixel - there))).max()
        assert error < 0.02, error
        checked += len(back)
        arrays = view_arrays(this, ("flow_next", "flow_next_valid", "flow_prev"), camera=False)
        assert np.array_equal(arrays["flow_next"].transpose(1, 2, 0), forward)
        assert arrays["flow_next_valid"].shape == (1, h, w)
    assert checked > 1000
