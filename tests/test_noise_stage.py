"""The noise stage's library (accelcal_repro.noise): the datasheet table and its claims, the
coverage count and its rule; each rule shown able to fail (the stage's config checks are in
tests/test_config_schemas.py)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from accelcal.noise import analyse_noise, simulate_noise
from accelcal.recording import Recording
from accelcal_repro.claims import validate_rows
from accelcal_repro.noise.adis import DATASHEET, FLICKER_FLOOR, datasheet_table, figure_references
from accelcal_repro.noise.claims import coverage_claim, coverage_rule_minimum, datasheet_claims, noise_claims
from accelcal_repro.noise.coverage import coverage_rows

FS = 100.0
#: The datasheet's values in SI units: white noise densities and bias stabilities.
N_ACC, N_GYRO = 0.2 / 60.0, math.radians(2.0 / 60.0)
FLOOR_ACC, FLOOR_GYRO = 0.2e-3 * 9.80665, math.radians(0.007)


def _record(seed: int, gyro_scale: float = 1.0, n: int = 2**17) -> Recording:
    """A static record whose white noise and flicker floor are the datasheet's (gyro white x ``gyro_scale``)."""
    rng = np.random.default_rng(seed)
    acc = np.array([0.0, 0.0, -9.8]) + simulate_noise(
        rng, n, FS, {"white": N_ACC, "bias_instability": FLOOR_ACC / FLICKER_FLOOR}, size=3)
    gyro = simulate_noise(rng, n, FS, {"white": gyro_scale * N_GYRO, "bias_instability": FLOOR_GYRO / FLICKER_FLOOR},
                          size=3)
    return Recording(np.arange(n) / FS, acc, None, "sim", unit="m/s^2", gyro=gyro, gyro_unit="rad/s")


@pytest.fixture(scope="module")
def reports():
    return {scale: analyse_noise(_record(4, scale), n_boot=100) for scale in (1.0, 3.0)}


@pytest.fixture(scope="module")
def tables(reports):
    return {scale: datasheet_table(r) for scale, r in reports.items()}


def test_the_datasheet_table_reads_white_noise_and_the_adev_minimum(reports, tables):
    t = tables[1.0]
    assert len(t) == 3 * len(DATASHEET) and set(t.axis) == {"x", "y", "z"}
    white = t[(t.reading == "white N") & (t.sensor == "gyroscope")]
    assert np.allclose(white.ratio, 1.0, rtol=0.05)  # the simulated white noise is the datasheet's
    for sensor in ("accelerometer", "gyroscope"):
        s = reports[1.0].sensors[sensor]
        adev_min = t[(t.reading == "ADEV minimum") & (t.sensor == sensor)]
        assert np.array_equal(adev_min.fitted, s.allan.adev.min(axis=0))
        assert np.array_equal(adev_min.tau_s, s.allan.taus[np.argmin(s.allan.adev, axis=0)])
        floor = t[(t.reading == "flicker floor 0.664 B") & (t.sensor == sensor)]
        assert np.allclose(floor.fitted, [FLICKER_FLOOR * a["bias_instability"].value for a in s.terms])
    assert np.all(t.interval_low <= t.fitted) and np.all(t.fitted <= t.interval_high)
    assert t.primary.sum() == 12
    refs = figure_references(t)
    assert refs["gyroscope"] == {"white": N_GYRO, "floor": FLOOR_GYRO}


def test_a_datasheet_claim_fails_when_an_axis_is_outside_the_factor(tables):
    rows = {r["claim_id"]: r for r in datasheet_claims(tables[1.0], factor=2.0)}
    assert all(r["verdict"] == "reproduced" for r in rows.values()), rows
    tripled = {r["claim_id"]: r for r in datasheet_claims(tables[3.0], factor=2.0)}
    assert tripled["adis16405_gyro_angle_random_walk"]["verdict"] == "not_reproduced"
    assert tripled["adis16405_accel_velocity_random_walk"]["verdict"] == "reproduced"
    # the same table passes a wider factor: the factor is the rule, not the data
    wide = {r["claim_id"]: r for r in datasheet_claims(tables[3.0], factor=4.0)}
    assert wide["adis16405_gyro_angle_random_walk"]["verdict"] == "reproduced"


def test_the_coverage_rule_and_the_least_sample_at_which_it_can_fail():
    assert coverage_rule_minimum(0.90).needed == 2  # 1 - 0.025**(1/2) = 0.84 < 0.90 < 1 - 0.025 = 0.975
    assert 1 - 0.025 ** (1 / 1) >= 0.90 > 1 - 0.025 ** (1 / 2)
    assert coverage_rule_minimum(0.95).needed == 2 and coverage_rule_minimum(0.99).needed == 1

    def table(covered, axes=90):
        return pd.DataFrame({"configuration": ["c"], "term": ["white"], "true": [1.0], "present": [True],
                             "axes": [axes], "covered": [covered], "coverage": [covered / axes],
                             "coverage_low": [np.nan], "coverage_high": [_upper(covered, axes)], "samples": [1024]})

    assert coverage_claim(table(85), 0.90, 0.95)["verdict"] == "reproduced"
    assert coverage_claim(table(70), 0.90, 0.95)["verdict"] == "not_reproduced"
    small = coverage_claim(table(0, axes=1), 0.90, 0.95)  # no hit, yet the upper end is 0.975
    assert small["verdict"] == "not_testable_at_this_scale" and "n 1 (axes per configuration and term), needs n " \
        ">= 2" in small["evidence"]


def _upper(k, n):
    from accelcal_repro.discrepancy.scoring import clopper_pearson

    return float(clopper_pearson(np.array(k), np.array(n))[1])


def test_coverage_rows_count_every_axis_and_are_reproducible():
    kw = dict(records=2, samples=2**14, fs=FS, seed=3, index=1, level=0.95, n_boot=60)
    a = coverage_rows("walk", {"white": 2e-3, "random_walk": 1e-4}, **kw)
    b = coverage_rows("walk", {"white": 2e-3, "random_walk": 1e-4}, **kw)
    pd.testing.assert_frame_equal(a, b)
    assert list(a.term) == ["quantization", "white", "bias_instability", "random_walk", "drift_ramp"]
    assert set(a["axes"]) == {6} and list(a.present) == [False, True, False, True, False]
    assert np.all((a.coverage_low <= a.coverage) & (a.coverage <= a.coverage_high))
    rows = noise_claims(datasheet_table(analyse_noise(_record(4), n_boot=60)), a, factor=2.0, floor=0.9, level=0.95)
    validate_rows(rows)
    assert list(rows.claim_id)[-1] == "term_interval_coverage"
