"""Claims-ledger rows of the noise stage (paper key ``noise``): the ADIS16405 datasheet's noise
figures on the 2.78 h record, and the coverage the noise analysis states for its intervals.

Datasheet rules (one claim per figure): reproduced iff the reading of every axis
(:data:`accelcal_repro.noise.adis.PRIMARY`) lies within a factor ``factor`` of the
datasheet's typical value, ``1/factor <= fitted / datasheet <= factor``.  The factor is a
setting of the stage (``noise.claims.datasheet_factor``, 2 in both configs), chosen as
what "agrees with a typical value" can mean for one unit: the datasheet states a
population's typical values, one significant digit each, not limits; the ADEV minimum of
a 2.78 h record has a sampling error of ±10–50 % (its chi-square interval); and the
errors such a comparison exists to catch are factors of 9.8 (g against m/s²), 57
(degrees against radians) or 60 (per √h against per √s), all far outside 2.

Coverage rule: reproduced iff, for every simulated configuration and every term of the
fit (absent terms, true value 0, included), the exact 95 % interval of the rate at which
the term's interval holds the true value reaches ``coverage_floor`` (0.90): the stated
95 % is not shown to fall short by more than 5 points.  The rule can fail only from
:func:`coverage_rule_minimum` axes per term on (2 at a floor of 0.90: the power rule of
:func:`accelcal_repro.claims.power_rule_minimum` with the floor as the power): with fewer,
even no hit at all leaves the interval's upper end above the floor, and the claim is
``not_testable_at_this_scale``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..claims import COLUMNS, Claim, MinimumSample, power_rule_minimum, validate_rows

DATASHEET_SOURCE = "results/noise/adis16405/datasheet.csv"
COVERAGE_SOURCE = "results/noise/coverage.csv"

_DATASHEET_CLAIMS = (
    ("adis16405_accel_velocity_random_walk", "accelerometer", "velocity random walk", "0.2 m/s/sqrt(h)",
     "the white-noise density fitted to each accelerometer axis"),
    ("adis16405_accel_bias_stability", "accelerometer", "in-run bias stability", "0.2 mg",
     "the minimum of each accelerometer axis's Allan deviation"),
    ("adis16405_gyro_angle_random_walk", "gyroscope", "angle random walk", "2 deg/sqrt(h)",
     "the white-noise density fitted to each gyroscope axis"),
    ("adis16405_gyro_bias_stability", "gyroscope", "in-run bias stability", "0.007 deg/s",
     "the minimum of each gyroscope axis's Allan deviation"),
)


def coverage_rule_minimum(floor: float, level: float = 0.95) -> MinimumSample:
    """Fewest axes per configuration and term at which the coverage rule can fail: no hit in
    ``n`` puts the exact interval's upper end, ``1 − t^(1/n)`` (``t = (1 − level)/2``), below
    ``floor`` only for ``n > ln t / ln(1 − floor)``."""
    return power_rule_minimum(floor, "axes per configuration and term", level)


def datasheet_claims(table: pd.DataFrame, factor: float) -> list[dict]:
    """One row per datasheet figure from ``results/noise/adis16405/datasheet.csv``."""
    rows = []
    for claim_id, sensor, quantity, written, reading in _DATASHEET_CLAIMS:
        sel = table[(table.sensor == sensor) & (table.quantity == quantity) & table.primary.astype(bool)]
        claim = Claim("noise", claim_id,
                      f"ADIS16405 datasheet: {sensor} {quantity} {written} (typical); on the 2.78 h static record "
                      f"(SMAC imudata, 100 Hz), {reading} lies within a factor {factor:g} of it on every axis",
                      written)
        if len(sel) != 3:
            rows.append(claim.judge(float("nan"), False, f"{DATASHEET_SOURCE}: {len(sel)} axes instead of 3"))
            continue
        ratio = sel.ratio.to_numpy(dtype=float)
        passed = bool(np.all((ratio >= 1.0 / factor) & (ratio <= factor)))
        axes = ", ".join(f"{r.axis} {r.fitted:.3g} [{r.interval_low:.3g}, {r.interval_high:.3g}] (x{r.ratio:.2f})"
                         for r in sel.itertuples())
        evidence = (f"{DATASHEET_SOURCE}: {sel.reading.iloc[0]} [{sel.unit.iloc[0]}] with its "
                    f"{100 * sel.level.iloc[0]:g} % interval, {axes}; datasheet {sel.datasheet.iloc[0]:.4g}")
        rows.append(claim.judge(float(ratio.max()), passed, evidence,
                                fmt=f"x{ratio.min():.2f}-{{:.2f}} of the datasheet"))
    return rows


def coverage_claim(table: pd.DataFrame, floor: float, level: float) -> dict:
    """The coverage row from ``results/noise/coverage.csv``."""
    claim = Claim("noise", "term_interval_coverage",
                  f"accelcal noise: the {100 * level:g} % intervals of the fitted IEEE terms hold the true values of "
                  "simulated static records at the stated rate; reproduced iff for every configuration and term the "
                  f"exact 95 % interval of the coverage reaches {floor:g}",
                  f"{100 * level:g} %")
    if table.empty:
        return claim.judge(float("nan"), False, f"{COVERAGE_SOURCE}: no configuration")
    passed = bool(np.all(table.coverage_high >= floor))
    worst = table.loc[table.coverage.idxmin()]
    n = int(table["axes"].min())
    per = "; ".join(f"{c}: " + ", ".join(f"{r.term} {r.coverage:.2f}" for r in g.itertuples() if r.present)
                    for c, g in table.groupby("configuration", sort=False))
    evidence = (f"{COVERAGE_SOURCE}: {n} axes per configuration and term, {table.samples.iloc[0]} samples per "
                f"record; lowest coverage {worst.coverage:.2f} [{worst.coverage_low:.2f}, "
                f"{worst.coverage_high:.2f}] ({worst.configuration}, {worst.term}); terms present: {per}")
    return claim.judge(float(worst.coverage), passed, evidence, fmt="lowest {:.2f}",
                       scale=coverage_rule_minimum(floor).at(n))


def noise_claims(datasheet: pd.DataFrame, coverage: pd.DataFrame, *, factor: float, floor: float,
                 level: float) -> pd.DataFrame:
    """Ledger rows (:data:`accelcal_repro.claims.COLUMNS`) of the noise stage."""
    rows = datasheet_claims(datasheet, factor) + [coverage_claim(coverage, floor, level)]
    return validate_rows(pd.DataFrame(rows, columns=list(COLUMNS)), source="noise claims")


__all__ = ["coverage_claim", "coverage_rule_minimum", "datasheet_claims", "noise_claims"]
