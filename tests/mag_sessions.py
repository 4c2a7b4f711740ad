"""A simulated magnetometer session beside an accelerometer, shared by the magnetometer's CLI
and log-reader tests: rests of 2 s at 100 Hz with turns of 0.6 s between them, a known hard
iron B, soft iron A_INV, rotation R_TRUE and dip DIP, the field in µT (noise 0.1 µT)."""

import numpy as np

from accelcal.gyro.integrate import log_so3
from accelcal.mag.model import rotvec_to_matrix

A_INV = np.array([[35.0, 1.0, -0.5], [1.0, 33.0, 0.8], [-0.5, 0.8, 38.0]])  # µT per unit field
B = np.array([12.0, -25.0, 5.0])  # µT
R_TRUE = rotvec_to_matrix([0.02, 0.04, -0.03])  # magnetometer axes -> accelerometer axes
DIP = 60.0


def simulate_session(seed=0, rests=14, *, planar=False):
    """(t, acc, mag): ``rests`` rests, each reached by a turn from the last (about the vertical
    only with ``planar``, which leaves the field's vertical part unseen)."""
    rng = np.random.default_rng(seed)
    dip = np.radians(DIP)
    field = np.array([0, np.cos(dip), -np.sin(dip)])
    acc, mag = [], []
    Q = np.eye(3)
    for _ in range(rests):
        Qn = rotvec_to_matrix([0, 0, rng.uniform(0.5, 1.5)] if planar else rng.normal(size=3) * 1.5) @ Q
        for s in np.linspace(0, 1, 60):  # the turn from Q to Qn
            q = rotvec_to_matrix(s * log_so3(Qn @ Q.T)) @ Q
            acc.append(q @ [0, 0, 9.81])
            mag.append(R_TRUE.T @ q @ field)
        Q = Qn
        acc += [Q @ [0, 0, 9.81]] * 200
        mag += [R_TRUE.T @ Q @ field] * 200
    acc = np.array(acc) + rng.normal(size=(len(acc), 3)) * 0.01
    m = B + np.array(mag) @ A_INV.T + rng.normal(size=(len(mag), 3)) * 0.1
    return np.arange(len(acc)) / 100.0, acc, m
