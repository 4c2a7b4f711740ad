"""Benchmark of the discrepancy loop: plan and streams, key/detection separation, and a scoring
that catches deliberately wrong detectors."""

import numpy as np
import pandas as pd
import pytest

from accelcal_repro.discrepancy import benchmark as B
from accelcal.discrepancy import detect as D
from accelcal.discrepancy.effects import EFFECT_IDS

SESSION = B.Session()
RULES = D.Rules()
SEED = 11


def test_plan_chunks_partition_the_plan():
    plan = B.plan(EFFECT_IDS, [1.0, 3.0], 3, 5, 2)
    assert len(plan) == 5 * 2 * 3 + 5 + 2 and plan.recording.is_unique
    parts = [B.chunk(plan, 4, k) for k in range(4)]
    assert sorted(pd.concat(parts).recording) == sorted(plan.recording)
    with pytest.raises(Exception):
        B.chunk(plan, 4, 4)


def test_each_recording_has_its_own_stream():
    """Same row and replicate -> identical recording, whatever else runs; different -> different."""
    a, ka = B.simulate_case("quadratic", 2.0, 3, seed=SEED, session=SESSION, rules=RULES)
    b, kb = B.simulate_case("quadratic", 2.0, 3, seed=SEED, session=SESSION, rules=RULES)
    c, _ = B.simulate_case("quadratic", 2.0, 4, seed=SEED, session=SESSION, rules=RULES)
    np.testing.assert_array_equal(a.acc, b.acc)
    assert ka == kb
    assert a.acc.shape != c.acc.shape or not np.array_equal(a.acc, c.acc)
    # raw counts, as a 16-bit sensor writes them
    np.testing.assert_array_equal(a.acc, np.round(a.acc))
    # the injected size is the requested multiple of the MDE along the injected direction
    d = np.array([ka[f"direction_{x}"] for x in "xyz"])
    phi = np.array([ka[f"param_{x}"] for x in "xyz"])
    np.testing.assert_allclose(phi, 2.0 * ka["mde_along"] * d)


def test_detection_reads_only_the_recording():
    # (a drift at 3 white MDE can pass for a random-walk wander under the colored null:
    # a pose-to-pose effect keeps this test about the key, not about that trade-off)
    rec, key = B.simulate_case("quadratic", 3.0, 0, seed=SEED, session=SESSION, rules=RULES)
    row = B.detect_case(rec, SESSION.g, RULES)
    assert not set(row) & {"truth", "expected", "size_mde", "param_x", "direction_x"}
    assert row["outcome"] == "quadratic"


def _benchmark(rows, rules, seed=SEED):
    keys, dets = [], []
    for truth, size, rep in rows:
        rec, key = B.simulate_case(truth, size, rep, seed=seed, session=SESSION, rules=RULES)
        name = f"{truth}_{size:g}_{rep:04d}"
        keys.append({"recording": name, **key})
        dets.append({"recording": name, **B.detect_case(rec, SESSION.g, rules)})
    scores = B.score_cases(pd.DataFrame(keys), pd.DataFrame(dets))
    rates = B.rates(scores)
    return scores, B.summary(scores, rates, alpha=RULES.alpha, power=RULES.power, confusion_size=3.0)


def _verdict(summary, effect, metric):
    r = summary[(summary.effect == effect) & (summary.metric == metric)]
    assert len(r) == 1
    return r.iloc[0]


NULL_ROWS = [(B.NONE, 0.0, r) for r in range(60)]


def test_scoring_catches_a_test_without_multiple_comparison_control():
    """Five candidates each at level α with no Holm, no ΔBIC and no LOPO rule: about
    1 - 0.95⁵ ≈ 23 % of effect-free recordings get an effect named; the scoring's
    false-positive verdict fails.  The real rules on the same recordings pass."""
    wrong = D.Rules(correction="none", bic_threshold=-np.inf, lopo_min_improvement=-np.inf)
    _, bad = _benchmark(NULL_ROWS, wrong)
    fp_bad = _verdict(bad, B.NONE, "false_positive_rate")
    assert fp_bad.verdict == "fail" and fp_bad.ci_low > RULES.alpha, fp_bad
    _, good = _benchmark(NULL_ROWS, RULES)
    fp = _verdict(good, B.NONE, "false_positive_rate")
    assert fp.verdict == "pass", fp
    assert fp.value < fp_bad.value


def test_scoring_catches_a_fitter_that_ignores_the_effect(monkeypatch):
    """A fitter that returns the current model for current + effect (effect fixed at 0) never
    sees anything: accuracy at >= 1 MDE collapses and the scoring's verdict fails."""
    rows = [(e, 3.0, r) for e in EFFECT_IDS for r in range(3)]
    # the blind fitter replaces the nonlinear fit the white null's F-test compares; the colored
    # null tests on the linearised columns (tests/test_discrepancy_colored.py checks it)
    rules = D.Rules(null="white")
    _, good = _benchmark(rows, rules)
    assert all(_verdict(good, e, "accuracy_ge_1mde").verdict == "pass" for e in EFFECT_IDS)

    real_fit = D.fit

    def blind_fit(data, effects=(), p0=None, max_iter=200):
        base = real_fit(data, effects[:-1], p0=None if p0 is None else p0[: 9 + 3 * (len(effects) - 1)])
        if not effects:
            return base
        from accelcal.discrepancy.fit import fit_at

        return fit_at(data, effects, np.concatenate([base.p, np.zeros(3)]))

    monkeypatch.setattr(D, "fit", blind_fit)
    _, bad = _benchmark(rows, rules)
    for e in EFFECT_IDS:
        v = _verdict(bad, e, "accuracy_ge_1mde")
        assert v.verdict == "fail" and v.value == 0.0, v


def test_crossing_and_intervals():
    assert B.crossing([0.5, 1, 2], [0.2, 0.5, 0.9], 0.5) == (pytest.approx(1.0), "")
    s, _ = B.crossing([1, 2], [0.4, 0.8], 0.6)
    assert s == pytest.approx(np.sqrt(2))  # midway in log(size)
    assert np.isnan(B.crossing([1, 2], [0.96, 1.0], 0.95)[0])
    assert np.isnan(B.crossing([1, 2], [0.1, 0.2], 0.5)[0])
    lo, hi = B.clopper_pearson(5, 100)
    assert lo == pytest.approx(0.01643, abs=1e-4) and hi == pytest.approx(0.11284, abs=1e-4)
    lo, hi = B.clopper_pearson(0, 10)
    assert lo == 0 and hi == pytest.approx(0.30850, abs=1e-4)


def test_counts_csv_round_trip(tmp_path):
    from accelcal.recording import read_recording

    rec, _ = B.simulate_case(B.NONE, 0.0, 0, seed=SEED, session=SESSION, rules=RULES)
    B.write_counts_csv(tmp_path / "r.csv", rec)
    back = read_recording(tmp_path / "r.csv")
    np.testing.assert_array_equal(back.acc, rec.acc)
    np.testing.assert_allclose(back.t, rec.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(back.temp, rec.temp, rtol=0, atol=1e-9)
    with pytest.raises(Exception):
        B.write_counts_csv(tmp_path / "f.csv", type(rec)(rec.t, rec.acc + 0.5, None, ""))
