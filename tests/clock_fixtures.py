"""Host-stamped sessions for the clock tests: a sensor sampling on its own crystal, a link that
delivers its samples in batches, a host that stamps each row when it receives it.

:func:`ble_session` is a BLE logger as phones write them: the sensor samples at 100.05 Hz
(its crystal 500 ppm fast) and numbers each sample with a 16-bit counter; the link delivers
whatever is queued at each connection event (every 11.25 ms, a common Android interval),
one event in ten is lost and retried at the next; the host stamps each row with its wall
clock (in microseconds; or milliseconds, where rows of one batch can share a stamp) plus
its scheduling delay.  1 / median step of such stamps is the connection rate, 88.9 Hz.
"""

from __future__ import annotations

import numpy as np

from accelcal.gyro.simulate import simulate_recording

SENSOR_HZ = 100.05
EVENT_S = 0.01125


def host_stamps(t_sensor, rng, *, event_s=EVENT_S, lost=0.1, delay_ms=0.6, resolution_s=1e-6):
    """Receive times [s] of samples taken at ``t_sensor``: the first connection event after
    each sample that is not lost, plus a scheduling delay (exponential, ``delay_ms``), rounded
    down to ``resolution_s`` (1e-3: rows of one batch can share a stamp)."""
    n_events = int(np.ceil(t_sensor[-1] / event_s)) + 50
    events = 0.0027 + event_s * np.arange(n_events)
    ok = rng.random(n_events) >= lost
    events = events[ok]
    idx = np.searchsorted(events, t_sensor, side="right")
    pos = np.arange(len(idx)) - np.searchsorted(idx, idx, side="left")  # place in its batch
    delay = rng.exponential(delay_ms * 1e-3, len(events))
    recv = events[idx] + delay[idx] + 4e-5 * pos  # the rows of a batch are handled one after another
    return np.floor(recv / resolution_s) * resolution_s


def ble_session(seed: int = 7, *, counter_start: int = 61000, n_motions: int = 16, drop=(), resolution_s=1e-6):
    """(CSV text, truth) of a BLE-logged multi-position session (module docstring).

    ``drop``: sample numbers the link lost (their rows are absent, the counter says so).
    """
    rng = np.random.default_rng(seed)
    C = np.eye(3) + np.diag([0.012, -0.008, 0.015]) + 0.003 * np.array([[0, 1, 0], [0, 0, -1], [1, 0, 0]])
    sim = simulate_recording(rng, n_motions=n_motions, angle_deg=100.0, peak_rate_dps=120.0, fs=SENSOR_HZ,
                             rest_s=2.5, init_rest_s=10.0, C=C, gyro_bias=np.array([0.01, -0.02, 0.005]),
                             gyro_noise=0.002, acc_noise=0.01)
    n = len(sim["t"])
    k = np.arange(n)
    keep = np.ones(n, bool)
    keep[list(drop)] = False
    stamps = host_stamps(k / SENSOR_HZ, rng, resolution_s=resolution_s)
    counter = (counter_start + k) % 65536
    lines = ["timestamp,sample_counter,ax,ay,az,gx,gy,gz"]
    for i in np.flatnonzero(keep):
        a, g = sim["acc"][i], sim["gyro"][i]
        lines.append(f"{1_700_000_000 + stamps[i]:.6f},{counter[i]},{a[0]:.5f},{a[1]:.5f},{a[2]:.5f},{g[0]:.6f},{g[1]:.6f},"
                     f"{g[2]:.6f}")
    return "\n".join(lines) + "\n", {**sim, "n": n, "rate": SENSOR_HZ}
