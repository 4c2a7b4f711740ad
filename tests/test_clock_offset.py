"""The accelerometer-gyro time offset of a gyro recorded in a file of its own
(accelcal.formats.sync): measured from the motions, stated, applied; refused when the two
cannot be aligned."""

import subprocess
import sys

import numpy as np
import pytest

from accelcal.errors import RecordingError
from accelcal.formats import read
from accelcal.formats.sync import estimate_offset
from accelcal.gyro.simulate import simulate_recording


@pytest.fixture(scope="module")
def sim():
    return simulate_recording(np.random.default_rng(5), n_motions=14, fs=100.0, rest_s=2.0, init_rest_s=5.0)


def _late(sim, tau):
    """The gyro as a logger that stamps it ``tau`` late writes it."""
    t = sim["t"]
    return np.column_stack([np.interp(t - tau, t, sim["gyro"][:, j]) for j in range(3)])


@pytest.mark.parametrize("tau", [0.0, 0.013, -0.05, 0.2])
def test_the_offset_is_found_to_a_millisecond(sim, tau):
    off = estimate_offset(sim["t"], sim["acc"], _late(sim, tau))
    assert abs(off.tau - tau) < 1e-3 and off.applied == (tau != 0.0)


def test_counts_with_a_mid_scale_zero(sim, tmp_path):
    acc = tmp_path / "acc.txt"
    gyro = tmp_path / "gyro.txt"
    np.savetxt(acc, np.column_stack([sim["t"], np.round(32768 + 400 * sim["acc"])]), fmt="%.6f")
    np.savetxt(gyro, np.column_stack([sim["t"], np.round(32768 + 4000 * _late(sim, 0.03))]), fmt="%.6f")
    rec = read(acc, gyro=gyro)
    note = next(n for n in rec.notes if "time offset" in n)
    assert "offset +30" in note or "offset +29.9" in note or "offset +30.1" in note, note
    assert "applied" in note and "not applied" not in note
    # applied: the gyro now turns with the accelerometer at its own instants
    assert np.corrcoef(rec.gyro[:, 0], 32768 + 4000 * sim["gyro"][:, 0])[0, 1] > 0.999


def test_two_time_bases_that_cannot_be_aligned_are_refused(sim, tmp_path):
    acc = tmp_path / "acc.csv"
    gyro = tmp_path / "gyro.txt"
    np.savetxt(acc, np.column_stack([sim["t"], sim["acc"], ]), delimiter=",", header="t,ax,ay,az", comments="")
    np.savetxt(gyro, np.column_stack([sim["t"], _late(sim, 0.6)]))
    with pytest.raises(RecordingError, match="cannot be aligned"):
        read(acc, gyro=gyro)
    out = tmp_path / "cal.json"
    r = subprocess.run([sys.executable, "-m", "accelcal.cli", "calibrate", str(acc), "--gyro", str(gyro), "--out",
                        str(out)], capture_output=True, text=True)
    assert r.returncode == 2 and not out.exists() and len(r.stderr.strip().splitlines()) == 1, r.stderr


def test_px4_gyro_topic_late_by_20_ms_is_aligned(sim, tmp_path):
    """PX4's sensor_gyro is a topic of its own: its samples are interpolated to the accelerometer's
    instants, then shifted by the offset the motions show."""
    pytest.importorskip("pyulog")
    from accelcal.formats import px4

    from .log_fixtures import write_ulog

    t = sim["t"]
    ts = (np.round(t * 1e6) + 1_000_000).astype(np.uint64)
    late = _late(sim, 0.02)
    topics = {("sensor_accel", 0): {"timestamp": ts + 50, "timestamp_sample": ts, "device_id": np.full(t.size, 7, np.uint32),
                                    **{k: sim["acc"][:, j].astype(np.float32) for j, k in enumerate("xyz")}},
              ("sensor_gyro", 0): {"timestamp": ts + 310, "timestamp_sample": ts + 300,
                                   "device_id": np.full(t.size, 9, np.uint32),
                                   **{k: late[:, j].astype(np.float32) for j, k in enumerate("xyz")}}}
    rec = px4.read(write_ulog(tmp_path / "raw.ulg", topics))
    note = next(n for n in rec.notes if "time offset" in n)
    assert note.startswith("sensor_gyro - accelerometer time offset +20") and "not applied" not in note
    assert np.corrcoef(rec.gyro[50:-50, 2], sim["gyro"][50:-50, 2])[0, 1] > 0.999


def test_short_records_measure_no_offset_and_break_nothing(sim):
    for n in (5, 40, 120):  # inside the initial rest: no motion measures an offset, and nothing fails
        assert estimate_offset(sim["t"][:n], sim["acc"][:n], sim["gyro"][:n]) is None, n
