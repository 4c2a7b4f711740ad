"""The real sessions with gyro data (../shared/data): what the calibration must find on them,
through the command line's route (accelcal_repro.gyro.sessions)."""

import numpy as np
import pytest

from accelcal_repro.gyro.sessions import DATA, SESSIONS, calibrate_session, files_needed, local_paths

pytestmark = pytest.mark.skipif(not (DATA / "imu_tk_xsens").is_dir(), reason="shared data not present")


def _calibrate(name):
    return calibrate_session(SESSIONS[name], local_paths([name]))


def test_xsens_sensitivities_agree_with_the_data_sheet_and_the_fit_with_the_noise():
    r = _calibrate("xsens")
    g = r["gyro"]
    sens = 1.0 / np.diag(g.model.C)
    np.testing.assert_allclose(sens, [4778.0, 4758.0, 4766.0], rtol=2e-3)  # data sheet, 4 digits
    assert g.settings["g_sensitivity"]  # this unit's rest means follow gravity (F test)
    assert g.quality.chi2 / g.quality.dof < 2.0  # with it the motions fit the rest noise
    assert len(r["poses"]) == 38 and g.quality.n_motions == 37
    assert r["acc"].gyro is g  # one calibration holds both


def test_fork_data1_short_still_phases_need_no_hand_tuning():
    r = _calibrate("fork_data1")
    assert len(r["poses"]) >= 30
    assert r["static_note"].startswith("static detection chosen from")
    assert r["gyro"].quality.n_motions >= 29


def test_snu_host_timestamps_are_read_on_the_sensors_clock():
    """The reader times SNU's host stamps by the clock fitted to them (accelcal.formats.clock): the
    gyro gets even 100.0 Hz steps and keeps every motion.  Given the stamps as they are, the gyro's
    own safeguard still finds their jitter and integrates by the sample index."""
    from dataclasses import replace

    g = _calibrate("snu_good2")["gyro"]
    tb = g.settings["time_base"]
    assert abs(tb["rate"] / 100.0 - 1) < 5e-4 and tb["jitter"] < 0.01 and tb["gaps"] == 0
    assert not any("missing" in w for w in g.quality.warnings)
    spec = SESSIONS["snu_good2"]
    raw = calibrate_session(replace(spec, read={**spec.read, "clock": "stamps"}), local_paths(["snu_good2"]))["gyro"]
    tb = raw.settings["time_base"]
    assert tb["jitter"] > 0.05 and tb["used"] == "index"
    assert tb["chi2_per_dof"]["index"] < 0.5 * tb["chi2_per_dof"]["timestamps"]
    assert any("sample index" in w for w in raw.quality.warnings)
    assert raw.quality.n_motions < g.quality.n_motions  # a motion dropped as "missing samples"


def test_the_files_each_session_needs_are_in_the_data_table():
    from accelcal_repro.measured.data import DATASETS

    for dataset, files in files_needed(list(SESSIONS)).items():
        assert set(files) <= set(DATASETS[dataset]), dataset
