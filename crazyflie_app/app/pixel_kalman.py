"""A constant-velocity Kalman filter on the target's image position (filterpy notation, firmware structure).

State ``x = [u, v, du, dv]``: pixel column and row of the tree centre (px, continuous, (0, 0) = top-left
corner) and their rates (px/s). Time is real time in **seconds**: ``predict(dt)`` is called every control tick
with the tick's true duration, ``update(z)`` on each detection of the tracked tree. The C app predicted with
a fixed dt = 0.001 per 10 ms loop (a filter 10x slower than real time) and kept P in a 2x2 array while
indexing P[2][2] and P[3][3] out of bounds; here P is the full 4x4 covariance, kept symmetric and positive
definite by the Joseph-form update.

    predict:  x = F x               P = F P F' + Q
    update:   y = z - H x           S = H P H' + R          K = P H' S^-1
              x = x + K y           P = (I - K H) P (I - K H)' + K R K'   (Joseph: stays symmetric PSD)

Q is the discrete white-noise-acceleration model with spectral density ``accel_psd`` (px^2/s^3) per axis;
R = ``measurement_std_px``^2 I.
"""
import numpy as np

H = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])
I4 = np.eye(4)


class PixelKalmanFilter:
    """Track one target's image position. All arguments in px, px/s and seconds."""

    def __init__(self, u: float, v: float, measurement_std_px: float = 3.0, accel_psd: float = 400.0,
                 initial_velocity_std: float = 100.0):
        self.R = np.eye(2) * measurement_std_px ** 2
        self.accel_psd = float(accel_psd)
        self.x = np.array([u, v, 0.0, 0.0], dtype=float)
        self.P = np.diag([measurement_std_px ** 2, measurement_std_px ** 2,
                          initial_velocity_std ** 2, initial_velocity_std ** 2])
        self.updates = 0
        self.predictions = 0

    @property
    def position(self) -> tuple[float, float]:
        return float(self.x[0]), float(self.x[1])

    @property
    def velocity(self) -> tuple[float, float]:
        return float(self.x[2]), float(self.x[3])

    def predict(self, dt: float) -> None:
        """Propagate by ``dt`` seconds (a missed detection is just a predict without update)."""
        if dt < 0:
            raise ValueError("predict: negative dt %r" % dt)
        if dt == 0:
            return
        F = np.array([[1.0, 0.0, dt, 0.0], [0.0, 1.0, 0.0, dt], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
        q = self.accel_psd
        q11, q12, q22 = q * dt ** 3 / 3.0, q * dt ** 2 / 2.0, q * dt
        Q = np.array([[q11, 0.0, q12, 0.0], [0.0, q11, 0.0, q12], [q12, 0.0, q22, 0.0], [0.0, q12, 0.0, q22]])
        # x = F x ; P = F P F' + Q
        self.x = F @ self.x
        self.P = F @ self.P @ F.T + Q
        self.predictions += 1

    def update(self, u: float, v: float) -> np.ndarray:
        """Fuse one measured image position (px)."""
        z = np.array([u, v], dtype=float)
        # y = z - H x ; S = H P H' + R ; K = P H' S^-1
        y = z - H @ self.x
        S = H @ self.P @ H.T + self.R
        K = self.P @ H.T @ np.linalg.inv(S)
        self.x = self.x + K @ y
        # Joseph form: symmetric and positive definite whatever the rounding
        IKH = I4 - K @ H
        self.P = IKH @ self.P @ IKH.T + K @ self.R @ K.T
        self.updates += 1
        return y

    def shift(self, du: float, dv: float) -> None:
        """Move the position state by a known image displacement (ego-motion compensation)."""
        self.x[0] += du
        self.x[1] += dv
