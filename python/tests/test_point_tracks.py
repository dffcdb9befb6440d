"""The true point tracks of a sequence as the loader reads them: TAP-Vid's ``tracks`` (N, T, 2)
and ``occluded`` (N, T), the queries being the first frame's structure pixels on the stride
grid (at their centres at frame 0), and a tampered tracks file refused with what it holds."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from conftest import make
from shmgen_data import Dataset, DatasetError

# A beam crossed by a vehicle, filmed side-on by a fixed camera whose mount shakes.
RECIPE = """
dataset(#{ name: "tracks", seed: 3, samples: 1, views: 1, outputs: ["mask", "point_tracks"],
    camera: #{ width: 96, height: 72, fov_y: deg(60),
        fixed: [#{ position: [1.0, -0.6, 0.12], target: [1.0, 0.0, 0.0] }] },
    sequence: #{ duration: 0.2, fps: 30.0, track_stride: 4,
                 mount: #{ rotation: 2e-3, translation: 1e-3 } },
    scene: |rng| beam(#{ length: 2.0, width: 0.1, height: 0.2 }).simply_supported().at(1.0, 0.0, 0.0)
        .vehicle([[0.0, 3e5]], 8.0, 0.0),
})
"""


@pytest.fixture(scope="module")
def tracked(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return make(tmp_path_factory.mktemp("tracks"), RECIPE, "tracks")


def test_tracks_are_tap_vid_arrays_starting_at_the_query_pixels(tracked: Path) -> None:
    dataset = Dataset(tracked)
    tracks, occluded = dataset.point_tracks(0, view=0)
    first = dataset.sample(0).views[0]
    rows, cols = np.nonzero(first.mask[2::4, 2::4])
    queries = np.stack([cols * 4 + 2.5, rows * 4 + 2.5], axis=1)
    assert tracks.shape == (len(queries), 6, 2) and occluded.shape == (len(queries), 6)
    assert tracks.dtype == np.float64 and occluded.dtype == np.bool_
    assert len(queries) > 50
    np.testing.assert_allclose(tracks[:, 0], queries, atol=1e-6)
    # Side-on, nothing hides the beam; the points move (the beam and the shaken camera).
    assert not occluded.any()
    assert np.abs(tracks[:, -1] - tracks[:, 0]).max() > 0.2
    assert first.record["point_tracks"]["stride"] == 4


def test_a_tampered_tracks_file_is_refused_with_what_it_holds(tracked: Path) -> None:
    view = Dataset(tracked).sample(0).views[2]
    path = view.files["tracks.npy"]
    data = bytearray(path.read_bytes())
    # The last row's state becomes 2 (same size, so the manifest's size check passes).
    data[-8:] = np.float64(2.0).tobytes()
    path.write_bytes(bytes(data))
    with pytest.raises(DatasetError, match=r"query \d+ holds .*state 1, 0 or -1"):
        view.tracks
