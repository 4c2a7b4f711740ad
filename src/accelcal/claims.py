"""The claims ledger: one row per claim of a paper, with a verdict computed from results.

Columns (:data:`COLUMNS`)::

    paper, claim_id, claim, paper_value, reproduced_value, verdict, evidence

``paper`` is one of :data:`PAPERS`; ``verdict`` one of :data:`VERDICTS`:
``reproduced`` / ``not_reproduced`` (decided by a rule stated in the claim text and
applied to a result table) or ``not_reproducible`` (nothing to compute it from, e.g. no
public data; ``evidence`` says why).  Reproduced values are never typed in: a
:class:`Claim` turns a value computed from a table into a row with :meth:`Claim.judge`.

Each workflow stage writes ``results/claims/<stage>.csv``; :func:`assemble_ledger`
concatenates them into ``results/claims.csv`` and validates them.

Adding a claim is a few lines::

    SPEED = Claim("burkhard2024", "speed_full", "Full LLS is about 35x faster ...", "≈35×")
    row = SPEED.judge(value, passed=value >= 10, evidence="results/...: how", fmt="{:.1f}×")
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

COLUMNS = ("paper", "claim_id", "claim", "paper_value", "reproduced_value", "verdict", "evidence")
PAPERS = ("burkhard2024", "batista2011", "tereshkov")
VERDICTS = ("reproduced", "not_reproduced", "not_reproducible")


class LedgerError(ValueError):
    """A claims file or row that does not follow the ledger's rules."""


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

    def judge(self, value: float, passed: bool, evidence: str, fmt: str = "{:.3g}") -> dict:
        """Row for a value computed from results; ``passed`` applies the claim's rule.

        A non-finite value (nothing valid to measure) is ``not_reproduced``.
        """
        value = float(value)
        ok = bool(passed) and math.isfinite(value)
        shown = fmt.format(value) if math.isfinite(value) else "nan"
        return self.row("reproduced" if ok else "not_reproduced", shown, evidence)

    def not_reproducible(self, reason: str) -> dict:
        """Row for a claim that cannot be checked (``reason`` goes to ``evidence``)."""
        return self.row("not_reproducible", "", reason)


# --------------------------------------------------------------------------- checks
def at_least(claim: Claim, value: float, threshold: float, evidence: str, fmt: str = "{:.3g}") -> dict:
    """``reproduced`` iff ``value >= threshold``."""
    return claim.judge(value, value >= threshold, evidence, fmt)


def max_relative_difference(summary: pd.DataFrame, column: str, method: str, reference: str,
                            by: str = "noise_std") -> tuple[float, pd.Series]:
    """``max over by`` of ``|x_method / x_reference - 1|`` for ``column`` of a summary
    table with one row per (``by``, method).  Returns the maximum and the per-level values."""
    wide = summary.pivot_table(index=by, columns="method", values=column)
    for m in (method, reference):
        if m not in wide:
            raise LedgerError(f"summary has no rows for method {m!r} (has {sorted(wide.columns)})")
    rel = (wide[method] / wide[reference] - 1.0).abs()
    # a level where either is missing (no valid trial) counts as a failure
    return (float(rel.max()) if rel.notna().all() and len(rel) else float("nan")), rel


def equal_within(claim: Claim, summary: pd.DataFrame, column: str, method: str, reference: str,
                 rel_tol: float, source: str, by: str = "noise_std") -> dict:
    """``reproduced`` iff ``column`` of ``method`` is within ``rel_tol`` (relative) of
    ``reference`` at every level ``by`` of ``summary``; the evidence lists every level."""
    worst, rel = max_relative_difference(summary, column, method, reference, by)
    levels = ", ".join(f"{k:g}: {100 * v:.2g}%" for k, v in rel.items())
    evidence = f"{source}: |{column}({method})/{column}({reference}) - 1| per {by}: {levels}"
    return claim.judge(100 * worst, worst <= rel_tol, evidence, fmt="{:.2g}% max rel. diff.")


# --------------------------------------------------------------------------- Burkhard 2024, foundation stage
def burkhard_foundation_claims(crlb_summary: pd.DataFrame, timing_summary: pd.DataFrame, *,
                               speed_min_ratio: float = 10.0, equal_rel_tol: float = 0.05,
                               interleave: str = "block",
                               crlb_path: str = "results/foundation/crlb_summary.csv",
                               timing_path: str = "results/foundation/timing_summary.csv") -> pd.DataFrame:
    """The Burkhard (2024) rows of the foundation stage, computed from its two summaries.

    Rules (stated in the claim texts):

    * ``speed_full`` / ``speed_bias``: reproduced iff the median of the paired per-problem
      ratios t_NLLS / t_LLS (``interleave`` timings) is at least ``speed_min_ratio``.
    * ``fig1a_full_lls_equals_nlls``: reproduced iff the RMS bias error of full LLS is
      within ``equal_rel_tol`` (relative) of full NLLS at every noise level.
    * ``table1_field_tests``: not reproducible (no public data).
    """
    rows = []
    for cid, method, paper in (("speed_full", "full_lls", "≈35×"), ("speed_bias", "bias_lls", "≈20×")):
        base = "full NLLS" if method == "full_lls" else "bias-only NLLS"
        name = "Full LLS" if method == "full_lls" else "Bias-only LLS"
        claim = Claim(
            "burkhard2024", cid,
            f"{name} is about {paper[1:]} faster than {base} (24 poses). Rule: reproduced if the "
            f"median per-problem time ratio {base} / {name.split()[0].lower()} LLS, measured in one run on "
            f"identical problems ({interleave}-interleaved, repeated), is >= {speed_min_ratio:g}x "
            f"(the paper's order of magnitude; absolute ratios depend on implementation and machine)",
            paper)
        sel = timing_summary[(timing_summary["mode"] == "single") & (timing_summary["method"] == method)
                             & (timing_summary["interleave"] == interleave)]
        if len(sel) != 1:
            raise LedgerError(f"timing summary has {len(sel)} rows for {method} ({interleave}); expected 1")
        r = sel.iloc[0]
        other = timing_summary[(timing_summary["mode"] == "single") & (timing_summary["method"] == method)
                               & (timing_summary["interleave"] != interleave)]
        extra = "".join(f"; {o['interleave']}-interleaved: {o['speedup_median']:.1f}x" for _, o in other.iterrows())
        evidence = (f"{timing_path}: median paired ratio {r['baseline']}/{method} = {r['speedup_median']:.1f}x "
                    f"(IQR {r['speedup_q25']:.1f}-{r['speedup_q75']:.1f}x, n={int(r['n_timings'])}; "
                    f"median {1e6 * r['median_s']:.0f} us vs "
                    f"{1e6 * r['median_s'] * r['speedup_of_medians']:.0f} us){extra}")
        rows.append(at_least(claim, r["speedup_median"], speed_min_ratio, evidence, fmt="{:.1f}×"))

    claim = Claim(
        "burkhard2024", "fig1a_full_lls_equals_nlls",
        "Fig. 1(a): full LLS and full NLLS have the same bias error at every noise level (24 poses, M != I). "
        f"Rule: reproduced if the Monte Carlo RMS bias error of full LLS is within {100 * equal_rel_tol:g}% "
        "(relative) of full NLLS at every noise level of the grid",
        "LLS ≈ NLLS")
    rows.append(equal_within(claim, crlb_summary, "bias_rms", "full_lls", "full_nlls", equal_rel_tol, crlb_path))

    rows.append(Claim("burkhard2024", "table1_field_tests",
                      "Table 1: field-test calibration of an ADIS-16475 and a STIM318 with LLS and NLLS",
                      "Table 1").not_reproducible("no public data: the field-test recordings are not published"))
    return pd.DataFrame(rows, columns=list(COLUMNS))


# --------------------------------------------------------------------------- ledger
def validate_rows(rows: Iterable[Mapping] | pd.DataFrame, source: str = "claims") -> pd.DataFrame:
    """Check ledger rows; return them as a DataFrame with exactly :data:`COLUMNS`.

    Raises :class:`LedgerError` (one line naming ``source`` and the offending row) for
    missing or extra columns, an unknown paper or verdict, an empty claim text, a
    reproduced/not_reproduced row without a reproduced value or evidence, a
    not_reproducible row without a reason, and duplicate (paper, claim_id).
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


def verdict_counts(ledger: pd.DataFrame) -> dict[str, int]:
    """Number of claims per verdict (for logs)."""
    return {v: int(np.sum(ledger["verdict"] == v)) for v in VERDICTS}


__all__ = [
    "COLUMNS",
    "Claim",
    "LedgerError",
    "PAPERS",
    "VERDICTS",
    "assemble_ledger",
    "at_least",
    "burkhard_foundation_claims",
    "equal_within",
    "max_relative_difference",
    "read_claims",
    "validate_rows",
    "verdict_counts",
]
