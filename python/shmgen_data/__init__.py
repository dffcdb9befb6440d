"""Reading shmgen datasets: views and their images, cameras, ground truth and meshes.

>>> from shmgen_data import Dataset, backproject, fuse
>>> data = Dataset("out/quickstart")
>>> view = data[0]
>>> view.rgb.shape, view.depth.shape, view.mask.dtype, view.K
>>> view.is_copy, view.clean_stem, view.augmentation   # clean view or augmented copy, and of which
>>> view.labels["beam"]["max_deflection"], view.structures["beam"].instance_id
>>> cloud = fuse(data.samples[0])        # every view's depth back to world points
>>> view.prompt                          # the texture prompt: "A photo of cracked timber …"
>>> parts = data.split(by="prompt", holdout="A photo of cracked timber for construction")
>>> parts = data.split(by="sample", fraction=0.05)   # deterministic: the same on every machine
>>> write_depth_prediction("out/predictions", view, predicted)  # where `shmgen eval` reads it
>>> cloud = backproject(view, depth=predicted)                   # a prediction back to 3-D
>>> tracks, occluded = data.point_tracks(0, view=0)  # a sequence's true tracks, TAP-Vid style

Submodules: :mod:`shmgen_data.dataset` (datasets, samples, views), :mod:`shmgen_data.structures`
(structures by name, augmentation records), :mod:`shmgen_data.camera`
(cameras and OpenCV's lens model), :mod:`shmgen_data.geometry` (back-projection, fusion, of
the dataset's depth or a predicted one), :mod:`shmgen_data.splits` (train/test splits by any
key), :mod:`shmgen_data.predictions` (predictions where ``shmgen eval`` reads them, PLY files),
:mod:`shmgen_data.io` (EXR, PNG and binary PLY readers), :mod:`shmgen_data.tracks` (a
sequence's point tracks), :mod:`shmgen_data.files` (a dataset's
files opened as untrusted input: no links, bounded reads, :class:`Limits`),
:mod:`shmgen_data.arrays` (a view as training arrays), :mod:`shmgen_data.webdataset` (shards
of ``shmgen export --format webdataset`` in WebDataset pipelines) and :mod:`shmgen_data.torch`
(a PyTorch ``Dataset``, if torch is installed). The package is typed (``py.typed``).
"""

from .arrays import view_arrays
from .camera import Camera, distort, undistort
from .dataset import LAYERS, Dataset, Mesh, MissingFileError, Points, Sample, Verification, View
from .files import DatasetError, Limits
from .geometry import Cloud, backproject, fuse
from .io import read_exr, read_ply, read_png
from .predictions import (depth_prediction_path, surface_prediction_path, write_depth_prediction, write_ply,
                          write_surface_prediction)
from .splits import Split
from .structures import Augmentation, Structure, Structures

__version__ = "0.1.0"

__all__ = [
    "Augmentation", "Structure", "Structures", "Camera", "Cloud", "Dataset", "DatasetError", "LAYERS", "Limits", "Mesh", "MissingFileError",
    "Points", "Sample", "Verification", "View", "backproject", "distort", "fuse", "read_exr",
    "read_ply", "read_png", "undistort", "view_arrays", "Split", "depth_prediction_path",
    "surface_prediction_path", "write_depth_prediction", "write_ply", "write_surface_prediction",
]
