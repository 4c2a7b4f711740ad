"""How long to record: the record length at which each noise term's interval reaches a given width.

From the fitted model of each axis (:mod:`accelcal.noise.report`), for a record of length T
at the same rate:

* the term's *information* is the sum, over the octaves of τ at which the term carries at
  least half of the model's Allan variance and which a record of length T reaches
  (τ ≤ T/4, the report's grid), of the NIST SP 1065 edf of the overlapping Allan variance
  for the term's noise type (:func:`accelcal.noise.allan.edf_overlapping`): I(T);
* an Allan variance estimate with ν degrees of freedom has ``var(ln AVAR) ≈ 2/ν``, so a
  coefficient on the deviation scale (√AVAR) has ``sd(ln c) ≈ (2 I)^-½`` and its
  interval at level p the relative half-width ``h(T) = z_p (2 I(T))^-½``;
* the octaves are correlated (0.5 to 0.9 one octave apart), so the sum overstates the
  information: where this record resolves the term, h is scaled by the ratio of the
  report's own bootstrap half-width to h(T_now), which carries the correlation and the
  trade between terms; where it does not, h(T) is used as it is, and the planner says it
  is optimistic.

The answer is the shortest T (to 1 %) with h(T) ≤ the requested width; "never" when even
10⁸ s would not (a term the model holds at zero, or one always masked by another).  An
unresolved term is planned at the upper end of its interval, as the exports use it: a
smaller true value needs a longer record.
"""

from __future__ import annotations

import math

import numpy as np

from .. import distributions as dist
from .allan import edf_overlapping
from .terms import TERMS, model_avar

DEFAULT_WIDTH = 0.25
#: Longest record considered [s].
MAX_RECORD_S = 1e8
_SHARE = 0.5


def information(coef: dict, term: str, fs: float, record_s: float) -> float:
    """I(T): summed edf of the octaves of τ ≤ T/4 where ``term`` carries half the model AVAR (module docstring)."""
    n = int(record_s * fs)
    m = 2.0 ** np.arange(int(math.log2(max(n // 4, 1))) + 1)
    taus = m / fs
    total = model_avar({k: math.sqrt(v) for k, v in coef.items()}, taus, fs)
    part = coef.get(term, 0.0) * TERMS[term].basis(taus, fs)
    mine = part >= _SHARE * np.maximum(total, 1e-300)
    if not mine.any():
        return 0.0
    return float(np.sum(edf_overlapping(n, m[mine], TERMS[term].alpha)))


def half_width(coef: dict, term: str, fs: float, record_s: float, level: float) -> float:
    """h(T) = z (2 I)^-½ before the correlation scaling (inf when the term never carries the curve)."""
    info = information(coef, term, fs, record_s)
    z = float(dist.norm_ppf(0.5 + level / 2))
    return z / math.sqrt(2 * info) if info > 0 else math.inf


def plan(s, duration_s: float, width: float = DEFAULT_WIDTH, level: float = 0.95) -> dict:
    """``{term: (record length [s] per axis, optimistic per axis)}`` of one sensor (:class:`SensorNoise`)."""
    fs = s.allan.fs
    out = {}
    for term in planned(s):
        lengths, optimistic = [], []
        for fit, terms in zip(s.fits, s.terms):
            est = terms[term]
            coef = dict(zip(fit.term_ids, fit.c))
            if not est.resolved:
                coef[term] = est.hi ** 2  # planned at its upper bound, as the exports use it
            now = half_width(coef, term, fs, duration_s, level)
            scale = 1.0
            if est.resolved and math.isfinite(now) and est.value > 0:
                scale = max((est.hi - est.lo) / (2 * est.value) / now, 1.0)
            lengths.append(_shortest(coef, term, fs, level, width / scale))
            optimistic.append(scale == 1.0)
        out[term] = (lengths, optimistic)
    return out


def planned(s) -> list[str]:
    """The terms of ``s``'s fit that the planner plans (:attr:`~accelcal.noise.terms.NoiseTerm.planned_as`)."""
    return [k for k in s.terms[0] if TERMS[k].planned_as]


def _shortest(coef, term, fs, level, width) -> float:
    """The shortest record (1 s to 10^8 s, to 1 %) whose h(T) is within ``width``: a coarse log grid, then bisection
    (the information only grows with the record)."""
    grid = np.logspace(0, math.log10(MAX_RECORD_S), 33)  # four per decade
    ok = [half_width(coef, term, fs, t, level) <= width for t in grid]
    if not any(ok):
        return math.inf
    i = ok.index(True)
    if i == 0:
        return float(grid[0])
    lo, hi = float(grid[i - 1]), float(grid[i])
    while hi / lo > 1.01:
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if half_width(coef, term, fs, mid, level) <= width else (mid, hi)
    return hi


def duration_text(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "never (the model never lets it carry the curve)"
    for unit, size in (("d", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if seconds >= size:
            return f"{seconds / size:.2g} {unit}"
    return f"{seconds:.2g} s"


def plan_lines(s, duration_s: float, width: float, level: float) -> list[str]:
    """The summary lines of the planner for one sensor (worst axis)."""
    p = plan(s, duration_s, width, level)
    parts = []
    for term, (lengths, optimistic) in p.items():
        name = TERMS[term].planned_as
        j = int(np.argmax(lengths))
        if all(t[term].resolved for t in s.terms) or not math.isfinite(lengths[j]):
            parts.append(f"{name} {duration_text(lengths[j])}"
                         + (" (optimistic)" if optimistic[j] and math.isfinite(lengths[j]) else ""))
        else:  # planned at its upper bound: a smaller true value needs longer, and this record did not suffice
            parts.append(f"{name} more than {duration_text(max(lengths[j], duration_s))} (not resolved here)")
    return [f"  record for +-{100 * width:.0f} % ({100 * level:.0f} % intervals, worst axis): " + "; ".join(parts)]


__all__ = ["DEFAULT_WIDTH", "duration_text", "half_width", "information", "plan", "plan_lines"]
