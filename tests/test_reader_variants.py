"""A user's own CSV in 33 natural variants through `accelcal calibrate`: read and right, or
refused in one line that names the cause and the option (accelcal_repro.reader_variants)."""

from __future__ import annotations

import pytest

from accelcal_repro.reader_variants import VARIANTS, run_variant, session


@pytest.fixture(scope="module")
def sim():
    return session()


@pytest.mark.parametrize("variant", VARIANTS, ids=[v.name for v in VARIANTS])
def test_variant(variant, sim, tmp_path):
    r = run_variant(variant, sim, tmp_path)
    assert r["outcome"] == variant.expect, r
    if variant.expect == "read":
        assert r["exit"] == 0 and r["n_poses"] == 30, r
        assert r["unit"] == variant.unit
        # the noise (0.01 m/s², 400 samples a pose) allows ~0.5 mm/s²: a wrong unit, time
        # unit or column would be off by orders of magnitude
        assert r["bias_error_mm_s2"] < 1.0, r
    else:
        assert r["exit"] == 2 and r["one_line"] and not r["traceback"], r
        assert r["message"].startswith("accelcal: error: ") and variant.words in r["message"], r
        assert not r["written"]


def test_inferred_guesses_are_stated(sim, tmp_path):
    by = {v.name: v for v in VARIANTS}
    r = run_variant(by["ms_timestamps"], sim, tmp_path)
    assert "time unit: ms (inferred" in r["notes"] and "--time-unit" in r["notes"]
    r = run_variant(by["g_no_unit"], sim, tmp_path)
    assert "unit: g (inferred from the median |a|" in r["notes"] and "standard gravity" in r["notes"]
    r = run_variant(by["iso_datetime"], sim, tmp_path)
    assert "ISO 8601" in r["notes"]
