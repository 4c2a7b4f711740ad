"""The claims ledger: one row per claim of a paper, with a verdict computed from results.

Columns (:data:`COLUMNS`)::

    paper, claim_id, claim, paper_value, reproduced_value, verdict, evidence

``paper`` is one of :data:`PAPERS`; ``verdict`` one of :data:`VERDICTS`:
``reproduced`` / ``not_reproduced`` (decided by a rule stated in the claim text and
applied to a result table), ``not_testable_at_this_scale`` (:data:`NOT_TESTABLE`: the
result table holds too small a sample for the rule to give both verdicts; ``evidence``
gives the ``n`` it has and the ``n`` it needs) or ``not_reproducible`` (nothing to
compute it from, e.g. no public data; ``evidence`` says why).  Reproduced values are
never typed in: a :class:`Claim` turns a value computed from a table into a row with
:meth:`Claim.judge`.

Every rule states the least sample it needs (:class:`MinimumSample`): below it the
verdict would be the scale's, not the data's.  A rule on counts has no outcome of ``n``
that gives one of its verdicts (with one session per row, the exact 95 % interval's upper
end reaches a power of 0.8 even with no success: :func:`power_rule_minimum`); a rule on a
resampled statistic cannot resolve its threshold (:func:`rank_rule_minimum`,
:func:`bootstrap_rule_minimum`); a rule comparing a Monte Carlo mean with an absolute
threshold cannot resolve it while the mean's standard error exceeds it
(:func:`resolution_minimum`).  :meth:`Claim.judge` with ``scale`` gives
``not_testable_at_this_scale`` below the minimum.

Each workflow stage writes ``results/claims/<stage>.csv`` (the stage's own module builds
the rows, e.g. :mod:`accelcal_repro.burkhard2024.claims`); :func:`assemble_ledger`
concatenates them into ``results/claims.csv`` and validates them.

Adding a claim is a few lines::

    SPEED = Claim("burkhard2024", "speed_full", "Full LLS is about 35x faster ...", "≈35×")
    row = SPEED.judge(value, passed=value >= 10, evidence="results/...: how", fmt="{:.1f}×")

A stage's builder is a table of :class:`ClaimRule` entries (one claim, one entry: its id,
its rule's text, the inputs it reads, its verdict function) judged on one context by
:func:`judge_rules`; a claim is added as one entry.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any
from pathlib import Path

import numpy as np
import pandas as pd

COLUMNS = ("paper", "claim_id", "claim", "paper_value", "reproduced_value", "verdict", "evidence")
#: Sources of claims: the three papers, and the goals the project states for itself, judged
#: the same way: ``discrepancy`` (its discrepancy loop), ``gyro`` (the gyroscope's
#: calibration, :mod:`accelcal_repro.gyro.stage`) and ``noise`` (the ADIS16405 datasheet's
#: noise figures and the coverage the noise analysis states for its intervals).
PAPERS = ("burkhard2024", "batista2011", "tereshkov", "discrepancy", "gyro", "noise")
#: The verdict of a rule whose sample is too small for the data to decide it.
NOT_TESTABLE = "not_testable_at_this_scale"
VERDICTS = ("reproduced", "not_reproduced", NOT_TESTABLE, "not_reproducible")
#: What a ``not_testable_at_this_scale`` row's evidence must say: the n it has and the n it needs.
_SCALE_EVIDENCE = re.compile(r"\bn \S+ .*\bneeds n >= \S+")


class LedgerError(ValueError):
    """A claims file or row that does not follow the ledger's rules."""


# --------------------------------------------------------------------------- sample sizes
@dataclass(frozen=True)
class MinimumSample:
    """The least sample a rule needs before its verdict can depend on the data.

    ``needed`` counts ``unit`` (e.g. "recordings per row"); ``why`` says what the rule
    cannot do below it (one clause, shown in the evidence).
    """

    needed: float
    unit: str
    why: str

    def at(self, n: float, testable: bool | None = None) -> Scale:
        """This requirement at a sample of ``n``; ``testable`` overrides ``n >= needed``
        where an exact criterion exists for fractional ``n`` (effective sample sizes)."""
        return Scale(float(n), self, testable)


@dataclass(frozen=True)
class Scale:
    """A rule's sample (``n``) against its :class:`MinimumSample`.

    An unknown ``n`` (NaN: the table does not count it) is testable: the rule's own
    handling of missing data applies.
    """

    n: float
    minimum: MinimumSample
    exact: bool | None = None

    @property
    def testable(self) -> bool:
        if self.exact is not None:
            return bool(self.exact)
        return not self.n < self.minimum.needed

    def reason(self) -> str:
        """``not testable at this scale: n <has> (<unit>), needs n >= <needed>: <why>``."""
        m = self.minimum
        return f"not testable at this scale: n {self.n:g} ({m.unit}), needs n >= {m.needed:.3g}: {m.why}"


def _tail(level: float) -> float:
    return (1.0 - level) / 2.0


def upper_end_with_no_success(n, level: float = 0.95) -> np.ndarray:
    """Upper end of the exact (Clopper–Pearson) interval of 0 successes in ``n`` (real ``n > 0``)."""
    with np.errstate(divide="ignore"):
        return 1.0 - _tail(level) ** (1.0 / np.asarray(n, float))


def lower_end_with_all_successes(n, level: float = 0.95) -> np.ndarray:
    """Lower end of the exact interval of ``n`` successes in ``n`` (real ``n > 0``)."""
    with np.errstate(divide="ignore"):
        return _tail(level) ** (1.0 / np.asarray(n, float))


def _smallest_integer_above(x: float, strict: bool) -> int:
    x = round(float(x), 9)  # 2 / (1 - 0.95) is 39.99999999999996 in floating point
    return int(math.floor(x) + 1 if strict else math.ceil(x))


def power_rule_minimum(power: float, unit: str, level: float = 0.95) -> MinimumSample:
    """Rule "reproduced iff the exact interval's upper end >= ``power``": it can fail only
    if no success puts the upper end below the power, ``1 - t^(1/n) < power`` (``t`` the
    tail, 0.025): ``n > ln t / ln(1 - power)``; 3 at a power of 0.8."""
    n = _smallest_integer_above(math.log(_tail(level)) / math.log(1.0 - power), strict=True)
    return MinimumSample(n, unit, f"with fewer, the exact {100 * level:g} % interval's upper end reaches the "
                                  f"power {power:g} even with no success, so the rule cannot fail")


def rate_upper_rule_minimum(limit: float, unit: str, level: float = 0.95) -> MinimumSample:
    """Rule "reproduced needs the upper end <= ``limit``" (a false-positive rate's 2α): it
    can pass only if no event keeps the upper end at or below the limit,
    ``n >= ln t / ln(1 - limit)``; 36 for a limit of 0.1."""
    n = _smallest_integer_above(math.log(_tail(level)) / math.log(1.0 - limit), strict=False)
    return MinimumSample(n, unit, f"with fewer, the exact {100 * level:g} % interval's upper end exceeds "
                                  f"{limit:g} even with no event, so the rule cannot pass")


def rate_lower_rule_minimum(limit: float, unit: str, level: float = 0.95) -> MinimumSample:
    """Rule "reproduced iff the lower end > ``limit``": it can pass only if ``n`` events of
    ``n`` lift the lower end above the limit, ``t^(1/n) > limit``: ``n > ln t / ln limit``;
    2 for a limit of 0.05."""
    n = _smallest_integer_above(math.log(_tail(level)) / math.log(limit), strict=True)
    return MinimumSample(n, unit, f"with fewer, the exact {100 * level:g} % interval's lower end stays at or "
                                  f"below {limit:g} even if every one is an event, so the rule cannot pass")


def rank_rule_minimum(unit: str, level: float = 0.95) -> MinimumSample:
    """Rule "the measured value lies inside (or outside) the central ``level`` of ``R``
    re-simulated values": with ``R`` draws the measured value's quantile takes the values
    ``k / R``, and lying beyond every draw has probability ``2 / (R + 1)`` when the model is
    right; the central interval is resolved only when that is at most ``1 - level``:
    ``R >= 2 / (1 - level) - 1``, 39 for 95 %."""
    n = _smallest_integer_above(2.0 / (1.0 - level) - 1.0, strict=False)
    return MinimumSample(n, unit, f"with fewer, the central {100 * level:g} % of the re-simulations is their whole "
                                  f"range: a value beyond all of them has probability 2/(n+1) > {1 - level:.2g} "
                                  "when the model is right, so the rule tests a wider interval than it states")


def bootstrap_rule_minimum(alpha: float, unit: str) -> MinimumSample:
    """A bootstrap test that rejects when ``p = (1 + #{T* >= T}) / (B + 1) < alpha``: it can
    reject only if ``1 / (B + 1) < alpha``, ``B > 1/alpha - 1``; 20 at alpha 0.05."""
    n = _smallest_integer_above(1.0 / alpha - 1.0, strict=True)
    return MinimumSample(n, unit, f"with fewer, the smallest bootstrap p-value 1/(n+1) is not below alpha "
                                  f"{alpha:g}, so the test can name nothing")


def resolution_minimum(n: float, se: float, threshold: float, z: float, unit: str) -> MinimumSample:
    """Rule "an estimated mean is below an absolute ``threshold``" on ``n`` draws whose mean
    has standard error ``se``: the estimate resolves the threshold only when ``z`` standard
    errors fit below it, which takes ``n (z se / threshold)^2`` draws (two without a standard
    error)."""
    if not math.isfinite(se):
        return MinimumSample(2, unit, "a mean's standard error needs two")
    needed = math.ceil(round(n * (z * se / threshold) ** 2, 6)) if se > 0 and threshold > 0 else 1
    return MinimumSample(max(needed, 1), unit, f"with fewer, {z:g} standard errors of the Monte Carlo mean exceed "
                                               f"the threshold {threshold:g} (its standard error is {se:.2g} at "
                                               f"n {n:g}), so the rule cannot pass whatever the estimator does")


@dataclass(frozen=True)
class Claim:
    """One claim of a paper; its rule for a verdict is part of ``claim`` (the text)."""

    paper: str
    claim_id: str
    claim: str
    paper_value: str

    def __post_init__(self):
        if self.paper not in PAPERS:
            raise LedgerError(f"claim {self.claim_id!r}: unknown paper {self.paper!r} (known: {', '.join(PAPERS)})")
        if not self.claim_id or not self.claim_id.replace("_", "").isalnum():
            raise LedgerError(f"claim id {self.claim_id!r} must be a non-empty identifier (letters, digits, _)")
        if not self.claim.strip():
            raise LedgerError(f"claim {self.claim_id!r} has no text")

    def row(self, verdict: str, reproduced_value: str, evidence: str) -> dict:
        out = {"paper": self.paper, "claim_id": self.claim_id, "claim": self.claim,
               "paper_value": self.paper_value, "reproduced_value": reproduced_value,
               "verdict": verdict, "evidence": evidence}
        validate_rows([out])
        return out

    def judge(self, value: float, passed: bool, evidence: str, fmt: str = "{:.3g}", scale: Scale | None = None,
              shown: str | None = None) -> dict:
        """Row for a value computed from results; ``passed`` applies the claim's rule.

        A non-finite value (nothing valid to measure) is ``not_reproduced``.  Given a
        ``scale`` that is not :attr:`Scale.testable`, the row is ``not_testable_at_this_scale``
        whatever ``passed`` says: its evidence starts with the table (``evidence`` up to the
        first ``": "``), then the ``n`` it has and needs, then the rest of ``evidence``.
        ``shown`` replaces the formatted value.
        """
        value = float(value)
        if shown is None:
            shown = fmt.format(value) if math.isfinite(value) else "nan"
        if scale is not None and not scale.testable:
            return self.not_testable(scale, evidence, shown)
        ok = bool(passed) and math.isfinite(value)
        return self.row("reproduced" if ok else "not_reproduced", shown, evidence)

    def not_testable(self, scale: Scale, evidence: str, shown: str = "") -> dict:
        """Row for a rule whose sample is below its minimum: ``evidence`` is
        ``"<table>: <what was measured>"`` (or the table alone); the reason goes after the
        table, the measurement after the reason."""
        source, _, rest = evidence.partition(": ")
        return self.row(NOT_TESTABLE, shown, f"{source}: {scale.reason()}" + (f"; measured: {rest}" if rest else ""))

    def not_reproducible(self, reason: str) -> dict:
        """Row for a claim that cannot be checked (``reason`` goes to ``evidence``)."""
        return self.row("not_reproducible", "", reason)


@dataclass(frozen=True)
class ClaimRule:
    """One claim of a stage as an entry of its builder's table.

    ``rule(ctx)`` is the claim's text with its rule (thresholds and grid from ``ctx``);
    ``paper_value`` the paper's value (text, or a function of ``ctx``); ``inputs`` the names
    of ``ctx`` the entry reads (a builder that does not provide one is refused, not judged
    on a default); ``verdict(ctx, claim)`` the ledger row, or None when the configuration
    runs nothing for this claim (e.g. an installation sweep left out).
    """

    claim_id: str
    paper_value: str | Callable[[Any], str]
    rule: Callable[[Any], str]
    inputs: tuple[str, ...]
    verdict: Callable[[Any, Claim], dict | None]

    def judge(self, paper: str, ctx: Any) -> dict | None:
        missing = [k for k in self.inputs if not hasattr(ctx, k)]
        if missing:
            raise LedgerError(f"claim {self.claim_id!r} reads {', '.join(missing)}, which its builder does not give")
        value = self.paper_value(ctx) if callable(self.paper_value) else self.paper_value
        return self.verdict(ctx, Claim(paper, self.claim_id, self.rule(ctx), value))


def judge_rules(paper: str, rules: Sequence[ClaimRule], ctx: Any) -> list[dict]:
    """The ledger rows of ``rules`` (in their order) judged on ``ctx``."""
    return [row for rule in rules if (row := rule.judge(paper, ctx)) is not None]


# --------------------------------------------------------------------------- checks
def at_least(claim: Claim, value: float, threshold: float, evidence: str, fmt: str = "{:.3g}") -> dict:
    """``reproduced`` iff ``value >= threshold``."""
    return claim.judge(value, value >= threshold, evidence, fmt)


# --------------------------------------------------------------------------- ledger
def validate_rows(rows: Iterable[Mapping] | pd.DataFrame, source: str = "claims") -> pd.DataFrame:
    """Check ledger rows; return them as a DataFrame with exactly :data:`COLUMNS`.

    Raises :class:`LedgerError` (one line naming ``source`` and the offending row) for
    missing or extra columns, an unknown paper or verdict, an empty claim text, a
    reproduced/not_reproduced row without a reproduced value or evidence, a
    not_reproducible row without a reason, a not_testable_at_this_scale row whose
    evidence lacks the ``n`` it has and needs, and duplicate (paper, claim_id).
    """
    df = rows if isinstance(rows, pd.DataFrame) else pd.DataFrame(list(rows))
    missing = [c for c in COLUMNS if c not in df.columns]
    extra = [c for c in df.columns if c not in COLUMNS]
    if missing or extra:
        raise LedgerError(f"{source}: columns must be {', '.join(COLUMNS)}"
                          + (f"; missing {missing}" if missing else "") + (f"; unexpected {extra}" if extra else ""))
    df = df.loc[:, list(COLUMNS)].copy()
    df = df.astype(object).where(df.notna(), "").astype(str)
    for i, r in df.iterrows():
        where = f"{source}: row {i} ({r['paper']}/{r['claim_id']})"
        if r["paper"] not in PAPERS:
            raise LedgerError(f"{where}: unknown paper {r['paper']!r} (known: {', '.join(PAPERS)})")
        if r["verdict"] not in VERDICTS:
            raise LedgerError(f"{where}: unknown verdict {r['verdict']!r} (known: {', '.join(VERDICTS)})")
        if not r["claim_id"].strip() or not r["claim"].strip():
            raise LedgerError(f"{where}: empty claim_id or claim text")
        if r["verdict"] == "not_reproducible":
            if not r["evidence"].strip():
                raise LedgerError(f"{where}: a not_reproducible claim needs the reason in 'evidence'")
        elif r["verdict"] == NOT_TESTABLE:
            if not _SCALE_EVIDENCE.search(r["evidence"]):
                raise LedgerError(f"{where}: a {NOT_TESTABLE} claim needs the n it has and the n it needs in "
                                  "'evidence' ('n <has> ..., needs n >= <needed>')")
        elif not r["reproduced_value"].strip() or not r["evidence"].strip():
            raise LedgerError(f"{where}: verdict {r['verdict']} needs a reproduced_value and evidence")
    dup = df.duplicated(["paper", "claim_id"], keep=False)
    if dup.any():
        ids = sorted(set(df.loc[dup, "paper"] + "/" + df.loc[dup, "claim_id"]))
        raise LedgerError(f"{source}: duplicate claim id(s) {', '.join(ids)}")
    return df.reset_index(drop=True)


def read_claims(path: str | Path) -> pd.DataFrame:
    """Read one stage's claims file (every column as text) and validate it."""
    path = Path(path)
    try:
        df = pd.read_csv(path, dtype=str, keep_default_na=False)
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError) as e:
        raise LedgerError(f"{path}: cannot read claims file ({e})") from None
    return validate_rows(df, source=str(path))


def assemble_ledger(paths: Sequence[str | Path]) -> pd.DataFrame:
    """Concatenate per-stage claims files into the ledger, validating each and the whole
    (claim ids must be unique per paper across stages).  Rows keep file order."""
    frames = [read_claims(p) for p in paths]
    if not frames:
        return pd.DataFrame(columns=list(COLUMNS))
    return validate_rows(pd.concat(frames, ignore_index=True), source="ledger (" + ", ".join(map(str, paths)) + ")")


#: Columns of an expected-verdicts file (the CI reproduction check).
EXPECTED_COLUMNS = ("paper", "claim_id", "verdict")


def expected_verdicts(ledger: pd.DataFrame) -> pd.DataFrame:
    """The ``(paper, claim_id, verdict)`` table of a ledger, sorted: what an
    expected-verdicts file holds."""
    return ledger.loc[:, list(EXPECTED_COLUMNS)].sort_values(["paper", "claim_id"]).reset_index(drop=True)


def verdict_changes(ledger: pd.DataFrame, expected: pd.DataFrame) -> list[str]:
    """One line per difference between a ledger and its expected verdicts: a claim whose
    verdict changed, a claim without an expected verdict, and an expected claim that the
    ledger no longer has.  Empty when they agree."""
    have = {(r.paper, r.claim_id): r.verdict for r in ledger.itertuples()}
    want = {(r.paper, r.claim_id): r.verdict for r in expected.itertuples()}
    lines = []
    for key in sorted(have.keys() | want.keys()):
        name = "/".join(key)
        if key not in want:
            lines.append(f"{name}: new claim (verdict {have[key]}) has no expected verdict")
        elif key not in have:
            lines.append(f"{name}: expected verdict {want[key]} but the ledger has no such claim")
        elif have[key] != want[key]:
            lines.append(f"{name}: verdict changed from {want[key]} to {have[key]}")
    return lines


def verdict_counts(ledger: pd.DataFrame) -> dict[str, int]:
    """Number of claims per verdict (for logs)."""
    return {v: int(np.sum(ledger["verdict"] == v)) for v in VERDICTS}


__all__ = [
    "COLUMNS",
    "Claim",
    "ClaimRule",
    "EXPECTED_COLUMNS",
    "LedgerError",
    "MinimumSample",
    "NOT_TESTABLE",
    "PAPERS",
    "Scale",
    "VERDICTS",
    "assemble_ledger",
    "at_least",
    "bootstrap_rule_minimum",
    "expected_verdicts",
    "judge_rules",
    "lower_end_with_all_successes",
    "power_rule_minimum",
    "rank_rule_minimum",
    "rate_lower_rule_minimum",
    "rate_upper_rule_minimum",
    "read_claims",
    "resolution_minimum",
    "upper_end_with_no_success",
    "validate_rows",
    "verdict_changes",
    "verdict_counts",
]
