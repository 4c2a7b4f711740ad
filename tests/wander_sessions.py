"""One simulated accelerometer session for the wander-family tests: pose data whose sensor
noise runs through rests and motions alike, with the rests' samples (what the joint
likelihood and the ``sum`` family borrow)."""

import dataclasses

import numpy as np

from accelcal.discrepancy.fit import forward, pose_data
from accelcal.discrepancy.wander.rests import rest_allan
from accelcal.model import m_from_params
from accelcal.noise import simulate_noise
from accelcal.simulation import random_directions

FS = 100.0


def rest_session(rng, terms, sample_sd=None, n=30, rest=6.0, move=2.0, init=20.0, trim=0.25):
    """``(data, intervals, noise)`` of a session of ``n`` poses whose noise ``terms`` [counts]
    runs through rests (``rest`` s, the first ``init`` s) and motions (``move`` s) alike.

    The poses' standard errors take ``sample_sd`` [counts per sample] over each rest's
    length, or the noise's own variance when None (white plus any short part)."""
    starts, durs, t = [trim], [init - 2 * trim], init + move
    for _ in range(1, n):
        starts.append(t + trim)
        durs.append(rest - 2 * trim)
        t += rest + move
    iv = np.round(np.column_stack([starts, np.add(starts, durs)]) * FS).astype(int)
    noise = simulate_noise(rng, int(t * FS), FS, terms, size=3)
    u = random_directions(rng, n)
    M = m_from_params(415 * (1 + rng.uniform(-0.01, 0.01, 3)) - 1, np.deg2rad([0.5, -0.7, 1.1]))
    z = forward(9.80665 * u, M, np.full(3, 32768.0), {}) + np.array([noise[a:b].mean(axis=0) for a, b in iv])
    n_s = (iv[:, 1] - iv[:, 0]).astype(float)
    sd = np.sqrt(noise.var(axis=0).mean()) if sample_sd is None else sample_sd
    ms = np.repeat((sd / np.sqrt(n_s))[:, None], 3, axis=1)
    data = pose_data(z, 9.80665, ms, iv.mean(axis=1) / FS, t_start=iv[:, 0] / FS, t_end=(iv[:, 1] - 1) / FS)
    return dataclasses.replace(data, rests=rest_allan(noise, iv, FS)), iv, noise
