"""The claims ledger: one row per claim of a paper, with a verdict computed from results.

Columns (:data:`COLUMNS`)::

    paper, claim_id, claim, paper_value, reproduced_value, verdict, evidence

``paper`` is one of :data:`PAPERS`; ``verdict`` one of :data:`VERDICTS`:
``reproduced`` / ``not_reproduced`` (decided by a rule stated in the claim text and
applied to a result table) or ``not_reproducible`` (nothing to compute it from, e.g. no
public data; ``evidence`` says why).  Reproduced values are never typed in: a
:class:`Claim` turns a value computed from a table into a row with :meth:`Claim.judge`.

Each workflow stage writes ``results/claims/<stage>.csv`` (the stage's own module builds
the rows, e.g. :mod:`accelcal_repro.burkhard2024.claims`); :func:`assemble_ledger`
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
#: Sources of claims: the three papers, ``discrepancy``, the goals the project's
#: discrepancy loop states for itself, and ``noise``, the ADIS16405 datasheet's noise
#: figures and the coverage the noise analysis states for its intervals, judged the same way.
PAPERS = ("burkhard2024", "batista2011", "tereshkov", "discrepancy", "noise")
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
    "EXPECTED_COLUMNS",
    "LedgerError",
    "PAPERS",
    "VERDICTS",
    "assemble_ledger",
    "at_least",
    "expected_verdicts",
    "read_claims",
    "validate_rows",
    "verdict_changes",
    "verdict_counts",
]
