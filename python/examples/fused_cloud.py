"""Draws docs/fused_cloud.png: the fused cloud of one bent beam (every view's depth
back-projected) against the sample's ground-truth mesh, each point coloured by its distance
to the mesh.

    pip install -r python/requirements-docs.txt -e python
    python python/examples/fused_cloud.py                  # renders a beam with shmgen first
    python python/examples/fused_cloud.py --data out/deformation --sample 0

Without ``--data`` it runs ``scripts/deformation.rhai`` (beams only, 12 views at 480 × 480)
with the shmgen binary (``$SHMGEN_BIN`` or ``target/release/shmgen``) into a temporary folder.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import trimesh  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Line3DCollection  # noqa: E402

from shmgen_data import Dataset, fuse  # noqa: E402

REPO = Path(__file__).resolve().parents[2]


def render_beams(folder: Path) -> Path:
    """A small dataset of bent beams from scripts/deformation.rhai."""
    binary = os.environ.get("SHMGEN_BIN", str(REPO / "target" / "release" / "shmgen"))
    out = folder / "beams"
    subprocess.run([binary, "run", str(REPO / "scripts" / "deformation.rhai"), "--out", str(out),
                    "--set", "silos=0.0", "--set", "samples=1", "--set", "views=12",
                    "--set", "size=480", "--quiet"], check=True)
    return out


def edges(mesh: trimesh.Trimesh) -> np.ndarray:
    """The mesh's feature edges (where faces meet at an angle), as (E, 2, 3) segments: the
    outline of the beam without the diagonals of its flat faces."""
    sharp = mesh.face_adjacency_edges[mesh.face_adjacency_angles > np.radians(1.0)]
    return mesh.vertices[sharp]


def draw(data: Dataset, index: int, out: Path) -> None:
    sample = data.sample(index)
    cloud = fuse(sample)
    mesh = trimesh.load(sample.path("mesh.ply"), process=False)
    rest = trimesh.load(sample.path("rest.ply"), process=False)
    _, distance, _ = trimesh.proximity.closest_point(mesh, cloud.points)
    micrometres = distance * 1e6
    labels = sample.labels["beam"]
    views = len(sample.clean_views())

    rng = np.random.default_rng(0)
    shown = rng.permutation(len(cloud))[:40000]
    colour = dict(c=micrometres[shown], cmap="viridis", vmin=0.0, vmax=max(micrometres.max(), 1e-3))

    figure = plt.figure(figsize=(11, 8), dpi=110)
    grid = figure.add_gridspec(2, 2, width_ratios=(1, 0.025), height_ratios=(1, 1), hspace=0.05)
    ax = figure.add_subplot(grid[0, 0], projection="3d", computed_zorder=False)
    points = cloud.points[shown]
    dots = ax.scatter(points[:, 0], points[:, 1], points[:, 2], s=0.3, depthshade=False, **colour)
    ax.add_collection3d(Line3DCollection(edges(mesh), colors="black", linewidths=0.9))
    lo, hi = mesh.bounds
    margin = 0.03 * (hi - lo).max()
    ax.set(xlim=(lo[0] - margin, hi[0] + margin), ylim=(lo[1] - margin, hi[1] + margin),
           zlim=(lo[2] - margin, hi[2] + margin), xlabel="x (m)", ylabel="y (m)", zlabel="z (m)")
    ax.set_box_aspect(hi - lo + 2 * margin, zoom=1.0)  # true proportions
    ax.view_init(elev=28, azim=-62)
    ax.set_axis_off()
    ax.set_title(f"{len(cloud):,} points from {views} views; the loaded mesh's edges in black",
                 fontsize=10)

    exaggeration = 3.0
    side = figure.add_subplot(grid[1, 0])
    xz = lambda segments: segments[:, :, [0, 2]] * [1.0, exaggeration]  # noqa: E731
    side.scatter(cloud.points[shown, 0], cloud.points[shown, 2] * exaggeration, s=0.3, **colour)
    side.add_collection(LineCollection(xz(edges(rest)), colors="tab:red", linewidths=1.2, zorder=3,
                                       linestyles="dashed", label="unloaded mesh (rest.ply)"))
    side.add_collection(LineCollection(xz(edges(mesh)), colors="black", linewidths=1.0, zorder=3,
                                       label="loaded mesh (mesh.ply)"))
    side.set_aspect("equal")
    side.autoscale()
    heights = np.arange(np.ceil(lo[2] / 0.1), np.floor(hi[2] / 0.1) + 1) * 0.1
    side.set_yticks(heights * exaggeration, [f"{h:.1f}" for h in heights])
    side.set(xlabel="x (m)", ylabel="z (m)")
    side.legend(loc="upper center", bbox_to_anchor=(0.5, -0.25), ncol=2, fontsize=9, frameon=False)
    side.set_title(
        f"side view, heights ×{exaggeration:g}: peak deflection "
        f"{abs(labels['max_deflection']) * 1000:.0f} mm ({labels['theory'].replace('_', '–')})",
        fontsize=10)
    bar = figure.colorbar(dots, cax=figure.add_subplot(grid[:, 1]))
    bar.set_label("distance from the mesh (µm)")
    figure.suptitle(
        f"Fused depth of a bent beam against its ground-truth mesh: largest distance "
        f"{micrometres.max():.2f} µm, median {np.median(micrometres):.2f} µm (float32 depth)",
        fontsize=11, y=0.93)
    out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(out, bbox_inches="tight")
    print(f"{out}: {len(cloud)} points, largest distance {micrometres.max():.3f} µm")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, help="a dataset with depth and mesh outputs")
    parser.add_argument("--sample", type=int, default=0)
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "fused_cloud.png")
    args = parser.parse_args()
    if args.data is not None:
        draw(Dataset(args.data), args.sample, args.out)
        return
    with tempfile.TemporaryDirectory() as folder:
        draw(Dataset(render_beams(Path(folder))), args.sample, args.out)


if __name__ == "__main__":
    main()
