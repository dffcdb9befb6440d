"""Datasets the tests read, made by running the shmgen binary.

The binary is ``$SHMGEN_BIN`` if set, else ``target/release/shmgen`` in the repository
(``cargo build --release`` builds it). Each dataset is made once per test session, in a
temporary folder.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]

#: Half extents of the box the box recipes show: 2 × 1 × 0.5 m, centred on the origin.
BOX_HALF = np.array([1.0, 0.5, 0.25])

#: Every per-view output the box datasets write (a plain box has no cracks, but the file is
#: written all the same).
BOX_OUTPUTS = ["rgb", "depth", "mask", "parts", "instances", "cracks", "erased", "valid",
               "normals", "displacement", "flow", "rest_rgb", "rest_depth", "ray_distance",
               "mesh", "points"]

BOX_RECIPE = """
let lens = param("lens", false);
let camera = #{ width: 160, height: 120, pitch: [0.3, 0.9], yaw: [0.2, 1.3] };
if lens {
    camera.distortion = #{ k1: [-0.12, -0.05], k2: 0.01, p1: 0.001, p2: -0.001, k3: [0.001, 0.003] };
}
dataset(#{ name: "box", seed: 4, samples: 2, views: 3,
    outputs: OUTPUTS,
    camera: camera,
    augment: #{ copies: 1, keep_clean: param("keep_clean", true), operations: [
        #{ op: "warp", zoom: [1.1, 1.3], rotation: [-3.0, 3.0], shift_x: [-0.03, 0.03], shift_y: [-0.03, 0.03], probability: 1.0 },
        #{ op: "erase", count: 1, area: [0.02, 0.05], aspect: [0.3, 1.0], probability: 1.0 },
    ] },
    scene: |rng| assembly("box", [shape::box(2.0, 1.0, 0.5)]),
})
""".replace("OUTPUTS", repr(BOX_OUTPUTS).replace("'", '"'))


def shmgen_binary() -> Path:
    """The shmgen binary the tests run: ``$SHMGEN_BIN`` or the repository's release build."""
    path = Path(os.environ.get("SHMGEN_BIN", REPO / "target" / "release" / "shmgen"))
    if not path.is_file():
        pytest.exit(
            f"no shmgen binary at {path}: build it with `cargo build --release` in {REPO}, "
            "or point SHMGEN_BIN at one",
            returncode=2,
        )
    return path


def shmgen(*args) -> subprocess.CompletedProcess:
    """Runs shmgen with ``args``; fails the test with its output if it fails."""
    done = subprocess.run([str(shmgen_binary()), *map(str, args)], capture_output=True, text=True)
    if done.returncode != 0:
        pytest.fail(f"shmgen {' '.join(map(str, args))} failed:\n{done.stdout}\n{done.stderr}")
    return done


def make(tmp: Path, recipe_text: str | None, name: str, *, recipe: Path | None = None,
         settings: dict | None = None) -> Path:
    """Runs a recipe (given as text, or as a file) into ``tmp/name``; returns the dataset."""
    if recipe is None:
        recipe = tmp / f"{name}.rhai"
        recipe.write_text(recipe_text)
    out = tmp / name
    args = ["run", recipe, "--out", out, "--quiet"]
    for key, value in (settings or {}).items():
        args += ["--set", f"{key}={value}"]
    shmgen(*args)
    return out


@pytest.fixture(scope="session")
def box(tmp_path_factory) -> Path:
    """The box through pinhole cameras, 2 samples × 3 views, each with an exact augmented copy."""
    return make(tmp_path_factory.mktemp("box"), BOX_RECIPE, "box")


@pytest.fixture(scope="session")
def box_lens(tmp_path_factory) -> Path:
    """The box through distorting lenses (OpenCV's model, k3 ≠ 0), with augmented copies."""
    return make(tmp_path_factory.mktemp("box_lens"), BOX_RECIPE, "box_lens", settings={"lens": "true"})


@pytest.fixture(scope="session")
def deformation(tmp_path_factory) -> Path:
    """scripts/deformation.rhai at 240 × 240: bent beams (samples 0, 1, 3) and a damaged
    water silo (sample 2), 3 views each, every ground-truth output."""
    return make(tmp_path_factory.mktemp("deformation"), None, "deformation",
                recipe=REPO / "scripts" / "deformation.rhai",
                settings={"samples": 4, "views": 3, "size": 240})


def off_box(points: np.ndarray, half=BOX_HALF) -> np.ndarray:
    """Signed distance-like measure of points from the box surface: max_k(|p_k| − h_k),
    0 on a face, negative inside, positive outside (exact distance within a face's span)."""
    return np.max(np.abs(points) - half, axis=1)
