"""Virtual sensor files as NumPy reads them: the .npy loads with ``np.load`` as float64
``[samples, sensors + 1]`` and holds exactly the CSV's numbers, and a step load's settled
mid-span deflection is the closed form P L^3 / (48 E I)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from conftest import make

RECIPE = """
dataset(#{ name: "sensors", seed: 1, samples: 1, views: 1, outputs: ["mask"],
    camera: #{ width: 16, height: 16 },
    sequence: #{ duration: 3.0, fps: 10.0 },
    scene: |rng| beam(#{ length: 10.0, width: 0.2, height: 0.5 })
        .ramp(5.0, 1e4, 0.5, 0.0).damping(0.6)
        .sensor(#{ name: "mid", kind: "displacement", at: 5.0, rate: 50.0 })
        .sensor(#{ name: "gauge", kind: "strain_bottom", at: 5.0, rate: 50.0 }),
})
"""


def test_sensor_npy_is_numpys_float64_table_equal_to_the_csv(tmp_path: Path) -> None:
    out = make(tmp_path, RECIPE, "sensors")
    stem = out / "samples" / "0000" / "000000"
    table = np.load(f"{stem}.sensors_50hz.npy", allow_pickle=False)
    assert table.dtype == np.float64 and table.shape == (150, 3)
    header = Path(f"{stem}.sensors_50hz.csv").read_text().splitlines()[0]
    assert header == "time[s],mid:displacement[m]@5m,gauge:strain_bottom[m/m]@5m"
    csv = np.loadtxt(f"{stem}.sensors_50hz.csv", delimiter=",", skiprows=1)
    assert np.array_equal(csv, table)
    assert np.array_equal(table[:, 0], np.arange(150) / 50.0)
    ei = 210e9 * 0.2 * 0.5**3 / 12
    assert abs(table[-1, 1] / (1e4 * 10.0**3 / (48 * ei)) - 1) < 1e-9
