"""Monte Carlo runners and the timing benchmark: determinism, grid independence, efficiency."""

import numpy as np
import pandas as pd
import pytest

from accelcal.montecarlo import crlb_mc, crlb_mc_point, grid_seed, rms_ratio, summarize_crlb
from accelcal.timing import summarize_timing, time_batched, time_interleaved

FAST = ["full_lls", "bias_lls"]


def test_same_seed_gives_identical_tables():
    a = crlb_mc(7, [1e-4, 1e-3], 20, methods=["full_lls", "full_als", "full_nlls", "bias_lls", "bias_nlls"])
    b = crlb_mc(7, [1e-4, 1e-3], 20, methods=["full_lls", "full_als", "full_nlls", "bias_lls", "bias_nlls"])
    pd.testing.assert_frame_equal(a, b)
    c = crlb_mc(8, [1e-4, 1e-3], 20, methods=FAST)
    assert not np.allclose(a.loc[a.method == "full_lls", "bias_err_x"], c.loc[c.method == "full_lls", "bias_err_x"])


def test_grid_point_data_do_not_depend_on_other_grid_points():
    """Chunking the noise grid (one job per level) must not change any level's data."""
    alone = crlb_mc(3, [1e-4], 30, methods=FAST)
    together = crlb_mc(3, [1e-2, 1e-5, 1e-4], 30, methods=FAST)
    pd.testing.assert_frame_equal(alone, together[together.noise_std == 1e-4].reset_index(drop=True))
    # the stream is keyed by the value, not by its position in the list
    assert grid_seed(1, "s", 1e-4).generate_state(4).tolist() == grid_seed(1, "s", 1e-4).generate_state(4).tolist()
    assert grid_seed(1, "s", 1e-4).generate_state(4).tolist() != grid_seed(1, "s", 1e-3).generate_state(4).tolist()
    assert grid_seed(1, "a", 1e-4).generate_state(4).tolist() != grid_seed(1, "b", 1e-4).generate_state(4).tolist()


def test_table_layout_and_identical_data_per_family():
    df = crlb_mc_point(5, 1e-3, 10, methods=["full_lls", "full_nlls", "bias_lls", "bias_nlls"])
    assert len(df) == 40
    for col in ("noise_std", "trial", "method", "bias_err_x", "bias_err_y", "bias_err_z", "bias_err_norm",
                "scale_err", "nonorth_err", "valid", "status", "bias_crlb_rms", "scale_crlb_rms", "nonorth_crlb_rms"):
        assert col in df
    assert df["valid"].all()
    full = df[df.method.str.startswith("full")]
    bias = df[df.method.str.startswith("bias")]
    assert full["scale_err"].notna().all() and bias["scale_err"].isna().all()
    # methods of one family see the same data, hence the same bound per trial
    f = full.pivot(index="trial", columns="method", values="bias_crlb_rms")
    np.testing.assert_array_equal(f["full_lls"], f["full_nlls"])
    # the bias-only bound (M = I) is below the full-model bound on the same poses
    assert (bias.groupby("trial")["bias_crlb_rms"].first() < full.groupby("trial")["bias_crlb_rms"].first()).all()
    # full LLS and NLLS find (nearly) the same bias on identical data
    e = full.pivot(index="trial", columns="method", values="bias_err_norm")
    np.testing.assert_allclose(e["full_lls"], e["full_nlls"], rtol=0.05, atol=1e-6)


def test_invalid_trials_are_recorded_not_raised():
    def broken(z, g, noise_std):
        T = len(z)
        return {"bias": np.full((T, 3), np.nan), "M": np.full((T, 3, 3), np.nan),
                "valid": np.zeros(T, bool), "status": np.full(T, "NotPositiveDefiniteError")}

    df = crlb_mc_point(1, 1e-3, 5, methods=["full_lls"], estimators={"full_lls": broken})
    assert not df["valid"].any() and df["bias_err_norm"].isna().all()
    s = summarize_crlb(df)
    assert s.loc[0, "n_valid"] == 0 and np.isnan(s.loc[0, "bias_ratio"])
    with pytest.raises(KeyError, match="unknown method"):
        crlb_mc_point(1, 1e-3, 5, methods=["nope"])


@pytest.mark.parametrize("noise", [1e-6, 1e-4])
def test_low_noise_rms_attains_the_crlb(noise):
    """At low noise the ML-like estimators are efficient: RMS / CRLB ≈ 1.

    600 trials: the ratio's standard error is ~3 % (reported as bias_ratio_se); the band
    is 4 standard errors and never less than 10 %.
    """
    s = summarize_crlb(crlb_mc(2024, [noise], 600, methods=FAST)).set_index("method")
    for m in FAST:
        r, se = s.loc[m, "bias_ratio"], s.loc[m, "bias_ratio_se"]
        assert 0.01 < se < 0.06
        assert abs(r - 1) < max(0.10, 4 * se), (m, r, se)
    assert s.loc["full_lls", "scale_ratio"] == pytest.approx(1, abs=0.15)
    assert s.loc["full_lls", "nonorth_ratio"] == pytest.approx(1, abs=0.15)


def test_rms_ratio_standard_error_matches_the_spread():
    rng = np.random.default_rng(0)
    ratios = [rms_ratio(rng.standard_normal(400), np.ones(400))[0] for _ in range(300)]
    _, se = rms_ratio(rng.standard_normal(400), np.ones(400))
    assert np.std(ratios) == pytest.approx(se, rel=0.2)


class FakeClock:
    """Each call advances by the cost of the last method called: timings without a clock."""

    def __init__(self):
        self.t, self.cost = 0.0, 0.0

    def __call__(self):
        self.t += self.cost
        return self.t


@pytest.mark.parametrize("interleave", ["block", "problem"])
def test_interleaved_timing_and_summary(interleave):
    clock = FakeClock()

    def method(cost):
        def f(z, g):
            clock.cost = cost
        return f

    z = np.zeros((4, 24, 3))
    methods = {"full_lls": method(1e-4), "full_nlls": method(3.5e-3), "bias_lls": method(1e-4),
               "bias_nlls": method(2e-3)}
    single = time_interleaved({m: z for m in methods}, 9.8, methods, repeats=3, interleave=interleave, clock=clock)
    assert len(single) == 4 * 3 * 4 and set(single["interleave"]) == {interleave}
    # every method ran on every (repeat, problem), and not always in the same position
    assert single.groupby("method")["order"].nunique().min() > 1
    batch = time_batched({"full_lls_batch": z, "bias_lls_batch": z}, 9.8,
                         {"full_lls_batch": method(4e-4), "bias_lls_batch": method(4e-5)}, repeats=2, clock=clock)
    s = summarize_timing(single, batch).set_index("method")
    assert s.loc["full_lls", "speedup_median"] == pytest.approx(35)
    assert s.loc["bias_lls", "speedup_median"] == pytest.approx(20)
    assert s.loc["full_lls", "baseline"] == "full_nlls"
    assert s.loc["full_lls_batch", "problems_per_s"] == pytest.approx(1e4)
    assert s.loc["full_lls_batch", "speedup_median"] == pytest.approx(35)
    assert s.loc["full_nlls", "median_s"] == pytest.approx(3.5e-3)
