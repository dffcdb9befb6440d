"""A view's camera as its JSON record states it, with OpenCV's lens model in numpy.

Conventions (shmgen's, fixed): OpenCV camera axes (x right, y down, z forward); pixel
``(i, j)`` (row ``i``, column ``j``) has its centre at ``(u, v) = (j + 0.5, i + 0.5)`` in
``K``'s coordinates; matrices are 4 × 4, metres; ``c2w_opengl = c2w · diag(1, -1, -1, 1)``
(nerfstudio's ``transform_matrix``).

Lens distortion is OpenCV's Brown–Conrady model (``camera.model == "opencv"``): a point
with normalised coordinates ``(x, y) = (X/Z, Y/Z)`` is seen at the distorted normalised
coordinates

    r² = x² + y²,  radial = 1 + k1 r² + k2 r⁴ + k3 r⁶
    x_d = x · radial + 2 p1 x y + p2 (r² + 2 x²)
    y_d = y · radial + p1 (r² + 2 y²) + 2 p2 x y

and then at pixel ``K · (x_d, y_d, 1)``. :meth:`Camera.undistort` inverts it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
from numpy.typing import NDArray

#: Lens coefficients ``(k1, k2, p1, p2, k3)``, OpenCV's order.
Coefficients = Sequence[float] | NDArray[np.float64]

__all__ = ["Camera", "distort", "undistort"]


def distort(x: np.ndarray, y: np.ndarray, coefficients: Coefficients) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV's Brown–Conrady distortion of normalised coordinates ``(x, y)``.

    ``coefficients`` are ``(k1, k2, p1, p2, k3)`` in OpenCV's order; returns ``(x_d, y_d)``.
    """
    k1, k2, p1, p2, k3 = coefficients
    r2 = x * x + y * y
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
    yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
    return xd, yd


def undistort(
    xd: np.ndarray,
    yd: np.ndarray,
    coefficients: Coefficients,
    *,
    tolerance: float = 1e-13,
    max_iterations: int = 50,
) -> tuple[np.ndarray, np.ndarray]:
    """Inverts :func:`distort`: the normalised ``(x, y)`` whose distortion is ``(xd, yd)``.

    The model is OpenCV's (what ``cv2.undistortPoints`` inverts); it is solved by Newton's
    method on the 2 × 2 system ``distort(x, y) = (xd, yd)``, starting from ``(xd, yd)``, with
    the analytic Jacobian, until every point's residual is below ``tolerance`` (normalised
    units: 1e-13 is about 1e-10 px for a focal length of 1000 px). OpenCV's own fixed-point
    iteration converges more slowly and stops after a fixed count; Newton reaches float64
    precision in a few steps for every lens shmgen renders (it refuses lenses that are not
    one-to-one over the frame). Raises ``ArithmeticError`` if some point does not converge,
    or converges to a root beyond the lens's fold (where the Jacobian's determinant or the
    radial factor is not positive): a distorted point no ray of the lens reaches.
    """
    k1, k2, p1, p2, k3 = coefficients
    xd = np.asarray(xd, dtype=np.float64)
    yd = np.asarray(yd, dtype=np.float64)
    x, y = xd.copy(), yd.copy()
    for _ in range(max_iterations + 1):
        fx, fy = distort(x, y, coefficients)
        rx, ry = fx - xd, fy - yd
        r2 = x * x + y * y
        radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
        d_radial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2)  # d radial / d r²
        a = radial + 2.0 * x * x * d_radial + 2.0 * p1 * y + 6.0 * p2 * x  # dxd/dx
        b = 2.0 * x * y * d_radial + 2.0 * p1 * x + 2.0 * p2 * y  # dxd/dy = dyd/dx
        d = radial + 2.0 * y * y * d_radial + 6.0 * p1 * y + 2.0 * p2 * x  # dyd/dy
        det = a * d - b * b
        if np.all(np.abs(rx) < tolerance) and np.all(np.abs(ry) < tolerance):
            # A root past the fold (the Jacobian turned over, or the radial factor negative:
            # the point seen through the centre) is not the ray of that pixel.
            folded = ~((det > 0) & (radial > 0))
            if np.any(folded):
                raise ArithmeticError(
                    f"undistortion: {int(folded.sum())} points lie beyond the fold of the lens "
                    f"{tuple(coefficients)}, which is not one-to-one there"
                )
            return x, y
        with np.errstate(divide="ignore", invalid="ignore"):
            x = x - (d * rx - b * ry) / det
            y = y - (a * ry - b * rx) / det
    worst = float(np.nanmax(np.maximum(np.abs(rx), np.abs(ry)), initial=0.0))
    raise ArithmeticError(
        f"undistortion did not converge in {max_iterations} Newton steps (worst residual "
        f"{worst:.3g} in normalised units): the lens {tuple(coefficients)} is not one-to-one there"
    )


def _matrix(camera: dict[str, Any], name: str, shape: tuple[int, int]) -> np.ndarray:
    try:
        value = np.array(camera[name], dtype=np.float64)
    except KeyError:
        raise KeyError(f"camera.{name} is missing") from None
    if value.shape != shape or not np.all(np.isfinite(value)):
        raise ValueError(f"camera.{name} is not a finite {shape[0]}×{shape[1]} matrix")
    return value


def _side(camera: dict[str, Any], name: str) -> int:
    try:
        value = camera[name]
    except KeyError:
        raise KeyError(f"camera.{name} is missing") from None
    if type(value) is not int or value <= 0:
        raise ValueError(f"camera.{name} is {value!r}, not a positive whole number of pixels")
    return value


@dataclass(frozen=True)
class Camera:
    """One view's camera: size, intrinsics, poses and lens.

    Attributes: ``width``, ``height`` (pixels); ``K`` (3 × 3); ``c2w`` and ``w2c`` (OpenCV
    axes, 4 × 4); ``c2w_opengl`` (OpenGL/nerfstudio axes); ``distortion`` (``(k1, k2, p1,
    p2, k3)``, OpenCV's order, all zero for a pinhole); ``model`` (``"pinhole"`` or
    ``"opencv"``); ``pixel_center`` (0.5).
    """

    width: int
    height: int
    K: np.ndarray
    c2w: np.ndarray
    w2c: np.ndarray
    c2w_opengl: np.ndarray
    distortion: np.ndarray
    model: str
    pixel_center: float = 0.5

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> "Camera":
        """The camera of a view's JSON record (its ``camera`` object)."""
        try:
            camera = record["camera"]
        except KeyError:
            raise KeyError("the view record has no camera") from None
        model = camera.get("model")
        if model == "pinhole":
            distortion = np.zeros(5)
        elif model == "opencv":
            d = camera.get("distortion") or {}
            try:
                distortion = np.array([d[k] for k in ("k1", "k2", "p1", "p2", "k3")], dtype=np.float64)
            except KeyError as missing:
                raise KeyError(f"camera.distortion.{missing.args[0]} is missing") from None
            if not np.all(np.isfinite(distortion)):
                raise ValueError(f"camera.distortion {distortion.tolist()} is not finite")
        else:
            raise ValueError(f'camera.model {model!r} is neither "pinhole" nor "opencv"')
        return cls(
            width=_side(camera, "width"),
            height=_side(camera, "height"),
            K=_matrix(camera, "K", (3, 3)),
            c2w=_matrix(camera, "c2w_opencv", (4, 4)),
            w2c=_matrix(camera, "w2c_opencv", (4, 4)),
            c2w_opengl=_matrix(camera, "c2w_opengl", (4, 4)),
            distortion=distortion,
            model=model,
            pixel_center=float(camera.get("pixel_center", 0.5)),
        )

    @property
    def position(self) -> np.ndarray:
        """The centre of projection, world metres."""
        return np.array(self.c2w[:3, 3])

    @property
    def distorted(self) -> bool:
        """Whether the lens distorts (any coefficient non-zero)."""
        return bool(np.any(self.distortion != 0.0))

    def pixel_centres(self) -> tuple[np.ndarray, np.ndarray]:
        """``(u, v)``, each ``(H, W)``: the centre of every pixel in ``K``'s coordinates."""
        u = np.arange(self.width, dtype=np.float64) + self.pixel_center
        v = np.arange(self.height, dtype=np.float64) + self.pixel_center
        return np.meshgrid(u, v)

    def normalised(self, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The undistorted normalised coordinates ``(X/Z, Y/Z)`` seen at pixel ``(u, v)``:
        ``K⁻¹ (u, v, 1)``, then the lens undone (:func:`undistort`) if it distorts."""
        kinv = np.linalg.inv(self.K)
        u = np.asarray(u, dtype=np.float64)
        v = np.asarray(v, dtype=np.float64)
        xd = kinv[0, 0] * u + kinv[0, 1] * v + kinv[0, 2]
        yd = kinv[1, 0] * u + kinv[1, 1] * v + kinv[1, 2]
        if not self.distorted:
            return xd, yd
        return undistort(xd, yd, self.distortion)

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World points ``(N, 3)`` → pixel coordinates ``(N, 2)`` (lens included) and their
        camera-frame depth ``z`` ``(N,)``; points behind the camera get ``z ≤ 0``."""
        points = np.asarray(points, dtype=np.float64)
        cam = points @ self.w2c[:3, :3].T + self.w2c[:3, 3]
        z = cam[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            x, y = cam[:, 0] / z, cam[:, 1] / z
        if self.distorted:
            x, y = distort(x, y, self.distortion)
        uv = np.stack([x, y, np.ones_like(x)], axis=1) @ self.K.T
        return uv[:, :2], z
