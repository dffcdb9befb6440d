"""True point tracks of a sequence (output ``point_tracks``; docs/sequences.md), TAP-Vid style.

Each frame of a view has ``{stem}_fKKKK.tracks.npy``: float64 ``(Q, 3)``, one row per query
point of the first frame, in the same order in every frame: ``x, y`` (pixels, (0.5, 0.5) the
centre of the top-left pixel) and ``state`` (1 seen, 0 hidden or outside the frame, -1 no
image, x = y = 0). :func:`decode_tracks` reads one file as untrusted input (a plain NPY of
that dtype and shape, values finite, states known); :func:`assemble` stacks a view's frames
into TAP-Vid's ``tracks`` ``(N, T, 2)`` and ``occluded`` ``(N, T)``.
"""

from __future__ import annotations

import io

import numpy as np
from numpy.typing import NDArray

from .files import DatasetError

#: The values of the ``state`` column: seen, hidden or outside the frame, no image.
STATES = (1.0, 0.0, -1.0)


def decode_tracks(data: bytes, shown: str) -> NDArray[np.float64]:
    """One frame's tracks file as a float64 ``(Q, 3)`` array; :class:`DatasetError` naming
    ``shown`` if it is not a plain little-endian float64 NPY of that shape, or holds a
    non-finite value or an unknown state."""
    try:
        array = np.load(io.BytesIO(data), allow_pickle=False)
    except (ValueError, OSError, EOFError) as e:
        raise DatasetError(f"{shown}: not a NumPy .npy file ({e})") from None
    if not isinstance(array, np.ndarray) or array.dtype != np.dtype("<f8"):
        raise DatasetError(f"{shown}: dtype {getattr(array, 'dtype', '?')}; point tracks are float64 '<f8'")
    if array.ndim != 2 or array.shape[1] != 3:
        raise DatasetError(f"{shown}: shape {array.shape}; point tracks are (queries, 3): x, y, state")
    bad = ~np.isfinite(array).all(axis=1) | ~np.isin(array[:, 2], STATES)
    if bad.any():
        q = int(np.argmax(bad))
        raise DatasetError(
            f"{shown}: query {q} holds {array[q].tolist()}; x, y must be finite and state 1, 0 or -1"
        )
    return np.asarray(array, dtype=np.float64)


def assemble(frames: list[NDArray[np.float64]], shown: str) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """TAP-Vid ``tracks`` ``(N, T, 2)`` float64 (x, y) and ``occluded`` ``(N, T)`` bool (True
    where the point is not seen: hidden, outside the frame or without an image) from a view's
    frames in order; :class:`DatasetError` if the frames disagree on the number of queries."""
    counts = sorted({len(f) for f in frames})
    if len(counts) > 1:
        raise DatasetError(f"{shown}: the frames' tracks hold {counts} queries; every frame holds the same queries")
    if not frames:
        return np.zeros((0, 0, 2)), np.zeros((0, 0), dtype=bool)
    stacked = np.stack(frames, axis=1)
    return stacked[..., :2].copy(), stacked[..., 2] != 1.0
