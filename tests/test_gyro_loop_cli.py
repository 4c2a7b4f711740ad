"""The gyro loop through the command line: `accelcal apply` corrects with the gyro's named effects
(the corrected rates lose the hidden effect), and bad input is one line while the accelerometer's
loop still runs (the tests on the reproductions' simulated sessions: tests/test_repro_gyro_loop_cli.py)."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pandas as pd
import pytest

from accelcal import cli
from accelcal.discrepancy import report


def run(*args):
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in args])
    return code, err.getvalue()


def _table(tmp_path, t, acc, gyro, name="rec.csv"):
    path = tmp_path / name
    pd.DataFrame(np.column_stack([t, acc, gyro]), columns=["t", "ax", "ay", "az", "gx", "gy", "gz"]).to_csv(
        path, index=False)
    return path


@pytest.fixture(autouse=True)
def cheap_accelerometer_loop(monkeypatch):
    monkeypatch.setattr(report, "DEFAULT_STOCHASTIC", report.StochasticSettings(n_boot=19, n_resim=1))


def test_rests_too_short_for_the_gyro_noise_say_so_in_one_line():
    from accelcal.discrepancy.gyro_loop import MIN_REST_SAMPLES, rest_noise_problem

    g = np.random.default_rng(0).standard_normal((1000, 3))
    assert rest_noise_problem(g, [(0, 100), (200, 300)], 100.0) is None
    why = rest_noise_problem(g, [(0, 100), (200, 200 + MIN_REST_SAMPLES - 1)], 100.0)
    assert why.startswith("the rests are too short to measure the gyro's noise: the shortest holds 29 samples")


def test_an_export_lists_the_gyro_effects_it_leaves_out():
    from types import SimpleNamespace

    from accelcal.export.base import effects_left_out

    gyro = SimpleNamespace(effects=[{"id": "scale_asymmetry", "params": ["a_x", "a_y", "a_z"],
                                     "values": [-0.0103, 0.0002, 0.0001]},
                                    {"id": "g_sensitivity", "params": ["G_xx"], "values": [1e-3]}])
    left = effects_left_out(SimpleNamespace(effects=(), gyro=gyro), "PX4")
    assert len(left) == 1 and "scale_asymmetry" in str(left[0]) and "a_x -0.0103" in str(left[0])
