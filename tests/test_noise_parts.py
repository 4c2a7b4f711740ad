"""`accelcal noise` on part of a recording (--start/--end, pooled --intervals), the quoted units and the
record-length planner in its summary, and allan_variance_ros's reading computed as its source does."""

from __future__ import annotations

import contextlib
import io
import json
import math

import numpy as np
import pytest

from accelcal import cli
from accelcal.noise.avr import avr_adev, avr_lines, avr_reading
from accelcal.noise.planner import plan
from accelcal.noise.report import analyse_noise
from accelcal.recording import Recording

FS = 50.0


def _cli(*args) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in args])
    return code, err.getvalue()


def _white(n, seed=0, sigma=0.01):
    return np.random.default_rng(seed).normal(scale=sigma, size=(n, 3))


def _table(path, acc):
    t = np.arange(len(acc)) / FS
    np.savetxt(path, np.column_stack([t, acc]), delimiter=",", header="t,ax,ay,az", comments="", fmt="%.9g")
    return path


def test_start_end_analyse_one_stretch_and_the_summary_quotes_units_and_plans(tmp_path):
    n = int(600 * FS)
    acc = [0, 0, 9.81] + _white(n)
    acc[n // 2:] = [0, 9.81, 0] + _white(n - n // 2, 1)  # turned over half-way: the whole is not static
    p = _table(tmp_path / "r.csv", acc)
    code, err = _cli("noise", p, "--out", tmp_path / "all.json")
    assert code == 2 and "not a static recording" in err and "--start/--end" in err
    code, err = _cli("noise", p, "--out", tmp_path / "a.json", "--start", "0", "--end", "290")
    assert code == 0, err
    d = json.loads((tmp_path / "a.json").read_text())
    assert d["n_samples"] == int(290 * FS) + 1
    assert "analysed 1 stretch(es) of the recording, 290 s" in err
    assert "velocity random walk" in err and "m/s/sqrt(h)" in err and "mg (x, y, z)" in err
    assert "record for +-25 % (95 % intervals, worst axis): noise density" in err
    for bad in (("--start", "400", "--end", "300"), ("--start", "700"), ("--start", "0", "--end", "0.02")):
        code, err = _cli("noise", p, "--out", tmp_path / "b.json", *bad)
        assert code == 2 and len(err.splitlines()) == 1, err
    assert not (tmp_path / "b.json").exists()


def test_intervals_pool_rests_in_different_orientations(tmp_path):
    n = int(300 * FS)
    acc = np.vstack([[0, 0, 9.81] + _white(n), [9.81, 0, 0] + _white(n, 2)])
    p = _table(tmp_path / "r.csv", acc)
    (tmp_path / "iv.csv").write_text(f"start,end\n0,{n / FS - 1}\n{n / FS + 1},{2 * n / FS - 1}\n")
    code, err = _cli("noise", p, "--out", tmp_path / "a.json", "--intervals", tmp_path / "iv.csv")
    assert code == 0, err
    assert "analysed 2 stretch(es)" in err
    d = json.loads((tmp_path / "a.json").read_text())
    nd = d["sensors"]["accelerometer"]["axes"]["x"]["noise_density"]["value"]
    assert nd == pytest.approx(0.01 / math.sqrt(FS), rel=0.1)  # white noise of sigma 0.01 at 50 Hz
    code, err = _cli("noise", p, "--out", tmp_path / "b.json", "--intervals", tmp_path / "iv.csv", "--start", "0")
    assert code == 2 and "either --intervals or --start/--end" in err


def test_the_planner_follows_the_white_noise_law():
    """White noise: the interval shrinks as 1/sqrt(T), so half the width needs four times the record."""
    n = int(2000 * FS)
    rec = Recording(np.arange(n) / FS, [0, 0, 9.81] + _white(n, 3), None, "sim", unit="m/s^2")
    report = analyse_noise(rec, n_boot=100)
    s = report.sensors["accelerometer"]
    w = s.terms[0]["white"]
    h0 = (w.hi - w.lo) / (2 * w.value)
    now = plan(s, report.duration_s, width=h0)["white"][0][0]
    half = plan(s, report.duration_s, width=h0 / 2)["white"][0][0]
    assert now == pytest.approx(report.duration_s, rel=0.15)
    assert half / now == pytest.approx(4.0, rel=0.2)


def _avr_loop(x, fs, period):
    """allan_variance_ros's AllanVarianceComputor.cpp lines 149-224 (commit 1d54b60), transcribed literally."""
    period_time = period * 0.1
    max_bin_size = int(period_time * fs)
    averages = []
    j = 0
    while j < len(x) - max_bin_size:
        averages.append(sum(x[j + m] for m in range(max_bin_size)) / max_bin_size)
        j += max_bin_size
    k = len(averages)
    return math.sqrt(sum((averages[i + 1] - averages[i]) ** 2 for i in range(k - 1)) / (2 * (k - 1)))


def test_avr_adev_is_the_tools_own_loop():
    x = np.random.default_rng(4).normal(size=1234)
    taus, adev = avr_adev(x, 37.0)
    for period in (1, 3, 7, 20, 33):
        i = int(np.flatnonzero(np.isclose(taus, period * 0.1))[0])
        assert adev[i, 0] == pytest.approx(_avr_loop(x.tolist(), 37.0, period), rel=1e-12)
    assert taus[-1] < 1234 / 37.0 / 2  # only tau it can average twice


def test_avr_reading_of_white_noise_and_the_line_that_explains_a_gap():
    n = int(2100 * FS)
    x = _white(n, 5, sigma=0.02)
    r = avr_reading(x, FS)
    assert r["complete"] and np.allclose(r["noise_density"], 0.02 / math.sqrt(FS), rtol=0.05)
    # white noise has no random walk, yet the +1/2 line through the whole curve reads one
    assert min(r["random_walk"]) > 0
    lines = avr_lines("accelerometer", "m/s^2", r, [0.02 / math.sqrt(FS)] * 3, [min(r["random_walk"]) / 10] * 3)
    assert len(lines) == 1 and "+1/2 slope to every tau from 0.1 s to 999.9 s" in lines[0]
    assert avr_lines("accelerometer", "m/s^2", r, r["noise_density"], r["random_walk"]) == []


def test_avr_adev_short_bins_one_by_one_long_bins_together_are_the_tools_loop():
    """The short bins (>= 2000 means, computed one by one) and the long ones (batched) both
    equal the tool's loop; τ that truncate to one bin size (1 Hz: 1.0 … 1.9 s) share it."""
    x = np.random.default_rng(5).normal(size=(25_000, 2))
    taus, adev = avr_adev(x, 100.0)
    for period in (1, 2, 30, 700):  # bins of 10, 20 (one by one); 300, 7000 samples (together)
        i = int(np.flatnonzero(np.isclose(taus, period * 0.1))[0])
        for j in range(2):
            assert adev[i, j] == pytest.approx(_avr_loop(x[:, j].tolist(), 100.0, period), rel=1e-12)
    taus1, adev1 = avr_adev(x[:5000], 1.0)
    one, two = adev1[np.isclose(taus1, 1.0)][0], adev1[np.isclose(taus1, 2.0)][0]
    assert np.array_equal(adev1[np.isclose(taus1, 1.5)][0], one) and not np.array_equal(one, two)
    assert one[0] == pytest.approx(_avr_loop(x[:5000, 0].tolist(), 1.0, 15), rel=1e-12)
