"""python/examples/experiment2 without PyTorch: the data, the split, the predictions written
with the loader's helpers, ``shmgen eval`` on the held-out beams and the table, with the two
baselines as predictors, at a tiny scale (the ``ci`` scale: 6 beams × 2 views at 32²).

Checked against independent truth: the per-pixel mean baseline computed here from the
training views with NumPy and scored here by hand (AbsRel over the structure's pixels, mean
over images) gives eval's AbsRel; every held-out beam and view is scored (eval's exit code
is 0 only then).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import REPO, shmgen_binary
from shmgen_data import Dataset

EXAMPLE = REPO / "python" / "examples" / "experiment2" / "experiment2.py"


@pytest.fixture(scope="module")
def experiment2():
    spec = importlib.util.spec_from_file_location("experiment2", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["experiment2"] = module
    spec.loader.exec_module(module)
    return module


def test_the_example_runs_end_to_end_with_the_baselines(experiment2, tmp_path: Path, monkeypatch, capsys) -> None:
    monkeypatch.setenv("SHMGEN_BIN", str(shmgen_binary()))
    results = experiment2.main(["--out", str(tmp_path), "--scale", "ci", "--predictor", "constant",
                                "--predictor", "mean", "--surface-samples", "2000"])
    data = Dataset(tmp_path / "data")
    parts = data.split(by="sample", fraction=0.34)
    assert len(parts.held_out) == 2
    for name in ("constant", "mean"):
        r = results[name]
        assert r["complete"] and r["depth_counts"]["images"] == len(parts.test) == 4
        assert r["surface"]["samples"] == 2 and np.isfinite(r["surface"]["chamfer_l1"])
        assert {image["sample"] for image in r["images"]} == set(parts.held_out)
    # The per-pixel mean, by hand.
    train = parts.train
    masks = np.stack([v.mask & (v.depth > 0) for v in train])
    depths = np.stack([v.depth for v in train]).astype(np.float64)
    covered = masks.sum(axis=0)
    mean = np.where(covered > 0, (depths * masks).sum(axis=0) / np.maximum(covered, 1), depths[masks].mean())
    per_image = []
    for view in parts.test:
        inside = view.mask & (view.depth > 0)
        truth = view.depth[inside].astype(np.float64)
        per_image.append(np.mean(np.abs(mean.astype(np.float32)[inside] - truth) / truth))
    assert results["mean"]["abs_rel"] == pytest.approx(np.mean(per_image), rel=1e-6)
    printed = capsys.readouterr().out
    assert "| mean (here) |" in printed and "| custom-made (40K pairs) (paper) | 0.01468 |" in printed
