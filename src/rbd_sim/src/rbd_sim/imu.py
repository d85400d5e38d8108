"""Simulated OS1 IMU: specific force and angular rate with bias, bias random walk and noise.

ROS-free. The accelerometer measures specific force f = R^T (a - g_world) with g_world =
(0, 0, -1 g), so a level sensor at rest reads +1 g on z, as the real one does. ouster-ros
publishes g-values x 9.80665 (m/s^2) and deg/s x pi/180 (rad/s); this model works in those
units directly. Lever-arm terms (the IMU sits a few cm from the body origin) are neglected.
"""

import math

import numpy as np

STANDARD_GRAVITY = 9.80665  # m/s^2 per g, the factor ouster-ros uses
#: ouster-ros covariances (os_ros.cpp): diagonal entries.
ACCEL_COVARIANCE_DIAG = 0.01
GYRO_COVARIANCE_DIAG = 6e-4


class ImuModel:
    """Accelerometer + gyroscope with constant bias, bias random walk and white noise.

    Args:
        accel_noise_std: White noise per sample [m/s^2].
        gyro_noise_std: White noise per sample [rad/s].
        accel_bias_std: Standard deviation of the turn-on bias per axis [m/s^2].
        gyro_bias_std: Standard deviation of the turn-on bias per axis [rad/s].
        accel_bias_walk: Bias random walk [m/s^2 per sqrt(s)].
        gyro_bias_walk: Bias random walk [rad/s per sqrt(s)].
        seed: Random seed.

    Raises:
        ValueError: a negative parameter.
    """

    def __init__(
        self,
        accel_noise_std: float = 0.03,
        gyro_noise_std: float = 0.003,
        accel_bias_std: float = 0.05,
        gyro_bias_std: float = 0.002,
        accel_bias_walk: float = 1e-3,
        gyro_bias_walk: float = 1e-4,
        seed: int = 0,
    ) -> None:
        params = (accel_noise_std, gyro_noise_std, accel_bias_std, gyro_bias_std, accel_bias_walk, gyro_bias_walk)
        if any(not math.isfinite(p) or p < 0 for p in params):
            raise ValueError("IMU noise parameters must be finite and >= 0")
        self.accel_noise_std, self.gyro_noise_std = float(accel_noise_std), float(gyro_noise_std)
        self.accel_bias_walk, self.gyro_bias_walk = float(accel_bias_walk), float(gyro_bias_walk)
        self.rng = np.random.default_rng(seed)
        self.accel_bias = self.rng.normal(0.0, accel_bias_std, 3) if accel_bias_std > 0 else np.zeros(3)
        self.gyro_bias = self.rng.normal(0.0, gyro_bias_std, 3) if gyro_bias_std > 0 else np.zeros(3)

    def sample(self, dt: float, rotation: np.ndarray, angular_velocity: np.ndarray, acceleration: np.ndarray) -> tuple:
        """One IMU sample.

        Args:
            dt: Time since the previous sample [s] (bias random walk).
            rotation: 3x3 rotation world <- IMU frame.
            angular_velocity: Angular velocity of the IMU frame, in the IMU frame [rad/s].
            acceleration: Linear acceleration of the IMU in the world frame [m/s^2].

        Returns:
            (linear_acceleration, angular_velocity) as 3-arrays in the IMU frame.
        """
        dt = max(0.0, float(dt))
        n = self.rng.standard_normal(12)
        if dt > 0:
            self.accel_bias = self.accel_bias + self.accel_bias_walk * math.sqrt(dt) * n[6:9]
            self.gyro_bias = self.gyro_bias + self.gyro_bias_walk * math.sqrt(dt) * n[9:12]
        g = np.array([0.0, 0.0, STANDARD_GRAVITY])
        f = np.asarray(rotation).T.dot(np.asarray(acceleration, dtype=float) + g)
        accel = f + self.accel_bias + self.accel_noise_std * n[0:3]
        gyro = np.asarray(angular_velocity, dtype=float) + self.gyro_bias + self.gyro_noise_std * n[3:6]
        return accel, gyro


class AccelerationEstimator:
    """World-frame acceleration from successive velocity samples (finite difference + low-pass).

    Args:
        time_constant: First-order low-pass time constant [s]; 0 disables smoothing.
    """

    def __init__(self, time_constant: float = 0.03) -> None:
        self.tau = max(0.0, float(time_constant))
        self._t = None
        self._v = None
        self.accel = np.zeros(3)

    def update(self, t: float, velocity_world: np.ndarray) -> np.ndarray:
        """Feed the velocity at time t [s]; returns the current acceleration estimate."""
        v = np.asarray(velocity_world, dtype=float)
        if self._t is not None:
            dt = t - self._t
            if dt <= 0.0 or dt > 1.0:  # out of order or a gap: restart
                self._t, self._v = t, v
                return self.accel
            raw = (v - self._v) / dt
            k = 1.0 if self.tau <= 0 else dt / (self.tau + dt)
            self.accel = self.accel + k * (raw - self.accel)
        self._t, self._v = t, v
        return self.accel
