"""The magnetometer's discrepancy loop: which effect beyond ``|A (m - b)| = 1`` do the samples ask for?

The loop starts from the hard iron alone (a sphere: ``b`` and one scale, 4 unknowns) and
tests nested extensions of it (:data:`CANDIDATES`):

===============  ==  ==============================================================
``soft_iron``     5  the rest of a symmetric ``A`` (scale factors, non-orthogonality)
``disturbance``   3  an offset ``Δb`` during one stretch of the session (a field that
                     comes and goes: iron or a motor nearby), the stretch found from the data
``temperature``   4  ``b + k (T - T̄)`` and a scale ``1 + s (T - T̄)`` (needs a temperature column)
===============  ==  ==============================================================

Residuals are the fit's own (Sampson distances in units of the rests' noise,
:func:`accelcal.mag.fit.sampson_residuals`), linearised at the base fit; each candidate's
columns are the Jacobian of those residuals in its parameters.  Noise model: the residuals
of the whole session are not independent (a low-passed sensor, a field that differs from
place to place), so residuals and columns are whitened by an AR(1) model (:data:`AR_ORDER`) fitted
to the residuals of the largest fixed model (the ellipsoid, with temperature when a column exists;
:mod:`accelcal.mag.noise`), and the common scale of the innovations is estimated, not
assumed.  Tests, MDE and identifiability are the gyro loop's
(``accelcal.discrepancy.nested.nested_f_test``: ``F`` with a parametric-bootstrap
p-value, Holm over a round's candidates).  The disturbance's stretch is searched over the
windows between :data:`N_GRID` + 1 boundaries; its p-value is that of the largest ``F`` over
all windows (the bootstrap repeats the search), its MDE is at the Bonferroni level over them.
The most significant candidate is named and refitted (``soft_iron``: the ellipsoid's ML fit;
the others: one Gauss-Newton step), and the next round tests the rest on top of it.

An AR(1) does not describe residuals correlated over hundreds of samples (SNU's): each
candidate is also tested by a Wald test with the block jackknife's covariance
(:func:`block_p`, robust to any correlation shorter than a block, Holm-adjusted as well),
and a candidate is named only when both reject.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import distributions as dist
from ..errors import AccelcalError
from ..mag.fit import FieldSamples, fit_ellipsoid_ml, fit_hard_iron, sampson_residuals
from ..mag.noise import ARNoise, block_covariance, fit_ar
from ..mag.trust import prepare, quiet_intervals, rest_noise
from ..summary import Summary
from .nested import LoopOutcome, nested_f_test, orthonormal_basis, project_out
from .statistics import holm

#: What the magnetometer's residuals come in (one per sample), for the nested test's reasons.
SAMPLES = {"unit": "samples", "rows_per_unit": 1, "base": "the model fitted so far"}

#: The noise model's AR order.  Fitted to residuals from which the candidates' directions were
#: projected out, a finer spectrum under-states the noise exactly there: on 100 effect-free
#: sessions with AR(1) noise (lag-1 0.5) anything was named in 8 % with AIC up to order 8,
#: 7 % up to 3, 5 % at order 1, 2 % with the true model.
AR_ORDER = 1
#: Boundaries of the disturbance's windows (equal shares of the samples): N_GRID (N_GRID+1)/2 - 1 windows.
N_GRID = 12
#: The sphere's 4 parameters inside the ellipsoid's 9 (b, and A = a I).
_SPHERE = np.zeros((9, 4))
_SPHERE[:3, :3] = np.eye(3)
_SPHERE[[3, 6, 8], 3] = 1.0


@dataclass(frozen=True)
class MagCandidate:
    """One nested extension of the magnetometer's model (module docstring's table)."""

    name: str
    params: tuple[str, ...]
    unit: str
    needs: str


CANDIDATES = (
    MagCandidate("soft_iron", ("A_xy", "A_xz", "A_yz", "A_yy", "A_zz"), "1/raw",
                 "orientations that spread the field over the sphere (turns about all three axes)"),
    MagCandidate("disturbance", ("db_x", "db_y", "db_z"), "raw",
                 "several orientations inside and outside the disturbed stretch (turn the device while recording)"),
    MagCandidate("temperature", ("kb_x", "kb_y", "kb_z", "k_scale"), "raw/degC, 1/degC",
                 "a temperature column that varies during the session"),
)
CANDIDATE_NAMES = tuple(c.name for c in CANDIDATES)


@dataclass(frozen=True)
class MagLoopResult(LoopOutcome):
    """The magnetometer loop's decisions: the same keys as the gyroscope's (``to_dict``)."""

    named: tuple[str, ...]
    rounds: list
    excess_before: float
    excess_after: float
    estimates: dict
    n_samples: int
    alpha: float
    n_boot: int
    noise: dict = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    def to_dict(self) -> dict:
        return {"named": list(self.named) or ["none"], "outcome": self.outcome, "candidates": self.rounds,
                "excess_before": self.excess_before, "excess_after": self.excess_after,
                "estimates": {k: {p: {"value": v, "se": s} for p, (v, s) in e.items()}
                              for k, e in self.estimates.items()},
                "n_samples": self.n_samples, "alpha": self.alpha, "n_boot": self.n_boot,
                "noise_model": "the rests' noise (Sampson residuals in its units), whitened by an AR(1) model of the "
                               "residuals of the ellipsoid (their autocorrelation), times one common scale estimated "
                               "from the residuals; a candidate is named only when the Wald test with the block jackknife's "
                               "covariance (p_blocks) rejects too", "noise": self.noise, "notes": list(self.notes)}

    def summary(self, *, written_to=None) -> Summary:
        named = ", ".join(self.named) or "none"
        line = (f"magnetometer: {self.n_samples} samples; effect named: {named}; excess {self.excess_before:.3g} -> "
                f"{self.excess_after:.3g}")
        return Summary([line] + ([f"  written to {written_to}"] if written_to is not None else []))


def _base(samples: FieldSamples, soft_iron: bool):
    """The nonlinear base fit: ``(theta, residuals, Jacobian of the base's own parameters, full Jacobian)``."""
    fit = fit_ellipsoid_ml(samples) if soft_iron else fit_hard_iron(samples)
    r, J = sampson_residuals(fit.theta, samples)
    return fit.theta, r, (J if soft_iron else J @ _SPHERE), J


def _columns(name: str, J: np.ndarray, theta, temp) -> np.ndarray | None:
    """The candidate's columns (n, k) in its parameters at the base fit (None: cannot be formed)."""
    if name == "soft_iron":
        return J[:, [4, 5, 7, 6, 8]]
    if name == "temperature":
        if temp is None or not np.ptp(temp) > 0:
            return None
        dT = (temp - temp.mean())[:, None]
        # a uniform scale (1 + s dT) of A moves theta's soft-iron part along itself
        return np.column_stack([J[:, :3] * dT, (J[:, 3:] @ np.asarray(theta, float)[3:]) * dT[:, 0]])
    raise KeyError(name)


def _windows(n: int, n_grid: int = N_GRID) -> list[tuple[int, int]]:
    edges = np.linspace(0, n, n_grid + 1).astype(int)
    return [(int(edges[i]), int(edges[j])) for i in range(n_grid) for j in range(i + 1, n_grid + 1)
            if not (i == 0 and j == n_grid)]


def window_columns(J: np.ndarray, window) -> np.ndarray:
    """A disturbance's columns: the hard iron's, inside ``window`` only."""
    X = np.zeros((len(J), 3))
    X[window[0]:window[1]] = J[window[0]:window[1], :3]
    return X


def _scan(base_w, J, rw, E, ar: ARNoise, n_grid: int) -> dict:
    """The disturbance: the window of largest F, its p-value from the bootstrap of the largest F."""
    Qb = orthonormal_basis(base_w)
    r0, E0 = project_out(Qb, rw), project_out(Qb, E)
    wins = _windows(len(J), n_grid)
    best, F_max, Fb_max = None, -np.inf, np.full(E.shape[1], -np.inf)
    for w in wins:
        Z = orthonormal_basis(project_out(Qb, ar.whiten(window_columns(J, w))))
        dof = len(rw) - Qb.shape[1] - Z.shape[1]
        if Z.shape[1] < 3 or dof < 4:
            continue
        num = float(np.sum((Z.T @ r0) ** 2))
        F = (num / 3) / ((r0 @ r0 - num) / dof)
        nb = np.sum((Z.T @ E0) ** 2, axis=0)
        Fb_max = np.maximum(Fb_max, (nb / 3) / ((np.sum(E0 ** 2, axis=0) - nb) / dof))
        if F > F_max:
            best, F_max = w, F
    if best is None:
        return {}
    return {"window": best, "F_max": float(F_max), "n_windows": len(wins),
            "p_scan": float((1 + np.sum(Fb_max >= F_max)) / (1 + E.shape[1]))}


def _row(c: MagCandidate, **kw) -> dict:
    if kw.get("status") == "tested":  # the F distribution's tail: ranks candidates whose bootstrap p-values tie
        kw["p_f"] = min(1.0, float(dist.f_sf(kw["F"], kw["k"], kw["dof"])) * kw.get("n_windows", 1))
    return {**kw, "needs": c.needs, "params": list(c.params), "unit": c.unit}


def _named_columns(named: dict, J, theta, temp) -> list[np.ndarray]:
    """The columns of the named linear candidates (soft iron is in the base fit itself)."""
    return [window_columns(J, w) if c == "disturbance" else _columns(c, J, theta, temp)
            for c, w in named.items() if c != "soft_iron"]


def _disturbance_row(c, base_w, J, rw, E, ar, level, n_grid) -> dict:
    scan = _scan(base_w, J, rw, E, ar, n_grid)
    if not scan:
        return _row(c, status="not_identifiable")
    row = nested_f_test(base_w, ar.whiten(window_columns(J, scan["window"])), rw, E, level / scan["n_windows"],
                        **SAMPLES)
    if row["status"] == "tested":
        row.update(p_value=scan["p_scan"], F=scan["F_max"], window=list(scan["window"]), n_windows=scan["n_windows"])
    return _row(c, **row)


def block_p(r, A, k: int, n_tests: int = 1) -> float:
    """The last ``k`` columns of ``A`` by a Wald test with the block jackknife's covariance
    (:func:`accelcal.mag.noise.block_covariance`: whatever the residuals' correlation),
    Hotelling's F with the blocks as the degrees of freedom; times ``n_tests`` (a searched window)."""
    coef = np.linalg.lstsq(A, r, rcond=None)[0]
    cov, info = block_covariance(A, r - A @ coef)
    if cov is None or info["blocks"] <= k + 1:
        return float("nan")
    K, b = info["blocks"], coef[-k:]
    W = float(b @ np.linalg.pinv(cov[-k:, -k:]) @ b)
    return min(1.0, float(dist.f_sf(W * (K - k) / (k * (K - 1)), k, K - k)) * n_tests)


def _with_block_p(rows: dict, state: dict, named: dict, temp) -> None:
    """Each tested row's ``p_blocks``: its test again under the block jackknife's noise model."""
    J, theta = state["J"], state["theta"]
    base = np.column_stack([state["Jb"], *_named_columns(named, J, theta, temp)])
    for c, row in rows.items():
        if row["status"] != "tested":
            continue
        X = window_columns(J, row["window"]) if c == "disturbance" else _columns(c, J, theta, temp)
        row["p_blocks"] = block_p(state["r"], np.column_stack([base, X]), X.shape[1], row.get("n_windows", 1))


def _round(samples, temp, named: dict, ar, E, alpha, n_grid, candidates) -> tuple[dict, dict]:
    """One round: every candidate not yet named, tested on top of the base and the named."""
    theta, r, Jb, J = _base(samples, "soft_iron" in named)
    base_w = ar.whiten(np.column_stack([Jb, *_named_columns(named, J, theta, temp)]))
    rw = ar.whiten(r)
    todo = [c for c in CANDIDATES if c.name in candidates and c.name not in named]
    level = alpha / max(1, len(todo))
    rows = {}
    for c in todo:
        if c.name == "disturbance":
            rows[c.name] = _disturbance_row(c, base_w, J, rw, E, ar, level, n_grid)
            continue
        X = _columns(c.name, J, theta, temp)
        if X is None:
            rows[c.name] = _row(c, status="not_identifiable", reason="no temperature column (or a constant one)")
            continue
        rows[c.name] = _row(c, **nested_f_test(base_w, ar.whiten(X), rw, E, level, **SAMPLES))
    state = {"theta": theta, "r": r, "J": J, "Jb": Jb}
    _with_block_p(rows, state, named, temp)
    return rows, state


def noise_model(samples: FieldSamples, temp=None) -> ARNoise:
    """The AR model of the residuals of the largest fixed model: the ellipsoid, and the
    temperature's columns (one least-squares step) when a column exists."""
    theta, r, _, J = _base(samples, True)
    X = _columns("temperature", J, theta, temp) if temp is not None else None
    if X is not None:
        A = np.column_stack([J, X])
        r = r - A @ np.linalg.lstsq(A, r, rcond=None)[0]
    return fit_ar(r, max_order=AR_ORDER)


def mag_discrepancy(samples: FieldSamples, temp=None, *, alpha: float = 0.05, n_boot: int = 999,
                    seed: int = 20240708, candidates=CANDIDATE_NAMES, max_rounds: int = 3,
                    n_grid: int = N_GRID) -> MagLoopResult:
    """Run the magnetometer loop (module docstring) on one session's field samples (time
    order; ``temp`` the temperature of each sample, or None)."""
    temp = None if temp is None else np.asarray(temp, float)
    ar = noise_model(samples, temp)
    E = np.random.default_rng(seed).standard_normal((samples.n - ar.order, n_boot))
    named: dict = {}
    rounds = []
    for _ in range(max_rounds):
        rows, _state = _round(samples, temp, named, ar, E, alpha, n_grid, candidates)
        tested = [c for c, r in rows.items() if r["status"] == "tested"]
        for c, pa, pb in zip(tested, holm([rows[c]["p_value"] for c in tested]),
                             holm([rows[c]["p_blocks"] for c in tested])):
            rows[c].update(p_adjusted=float(pa), p_blocks_adjusted=float(pb))
        rounds.append(rows)
        # named when both noise models reject: the AR(1)'s F test and the block jackknife's Wald test
        sig = [c for c in tested if rows[c]["p_adjusted"] < alpha and rows[c]["p_blocks_adjusted"] < alpha]
        if not sig:
            break
        # the bootstrap's p-values tie at 1/(n_boot+1): then the F distribution's tail decides
        # (the disturbance's times its number of windows, for the search)
        best = min(sig, key=lambda c: (rows[c]["p_value"], rows[c]["p_f"]))
        named[best] = tuple(rows[best]["window"]) if best == "disturbance" else True
        if len(named) == len(candidates):
            break
    est, before, after = _refit(samples, temp, named, ar)
    notes = []
    if temp is None and "temperature" in candidates:
        notes.append("temperature not tested: the recording has no temperature column")
    return MagLoopResult(tuple(named), rounds, before, after, est, samples.n, alpha, n_boot,
                         {**ar.to_dict(), "n_grid": n_grid}, tuple(notes))


def _excess(r, q: int) -> float:
    return float(np.sqrt(r @ r / max(len(r) - q, 1)))


def _refit(samples, temp, named: dict, ar: ARNoise):
    """The named candidates refitted: estimates and s.e. (under the AR noise), excess before and after."""
    _, r0, _, _ = _base(samples, False)
    before = _excess(r0, 4)
    theta, r, Jb, J = _base(samples, "soft_iron" in named)
    Xs = _named_columns(named, J, theta, temp)
    A = np.column_stack([Jb, *Xs])
    step = np.linalg.lstsq(A, -r, rcond=None)[0]
    after = _excess(r + A @ step, A.shape[1]) if named else before
    Aw, rw = ar.whiten(A), ar.whiten(r + A @ step)
    cov = np.linalg.pinv(Aw.T @ Aw) * max(float(rw @ rw) / max(len(rw) - A.shape[1], 1), 1e-300)
    se = np.sqrt(np.diag(cov))
    out, j = {}, Jb.shape[1]
    for c in named:
        info = next(x for x in CANDIDATES if x.name == c)
        if c == "soft_iron":
            idx = [4, 5, 7, 6, 8]
            out[c] = {p: (float(theta[i] + step[i]), float(se[i])) for p, i in zip(info.params, idx)}
            continue
        out[c] = {p: (float(step[j + i]), float(se[j + i])) for i, p in enumerate(info.params)}
        j += len(info.params)
    return out, before, after


def field_samples(mag, intervals=None, source: str = "magnetometer") -> tuple[FieldSamples, np.ndarray]:
    """A session's usable field samples with the noise measured at ``intervals`` (sample ranges
    of the recording: the accelerometer's rests), else at the field's quietest stretches;
    and the recording's rows they come from."""
    prep = prepare(mag, source)
    rows = np.flatnonzero(prep.keep)
    iv = []
    for a, b in np.asarray(intervals if intervals is not None else np.zeros((0, 2)), int).reshape(-1, 2):
        lo, hi = np.searchsorted(rows, a), np.searchsorted(rows, b)
        if hi - lo >= 5:
            iv.append((int(lo), int(hi)))
    cov, _, how = rest_noise(prep.m, iv or quiet_intervals(prep.m))
    return FieldSamples(prep.m, noise_cov=cov, noise_source=how), rows


#: Bootstrap draws of ``accelcal discrepancy``'s magnetometer loop: p-values down to 0.005, enough for
#: Holm over three candidates at 0.05; SNU good2 (11 380 samples): 1.8 s CPU and 159 MB peak, 999 draws
#: 6.9 s and 357 MB.
N_BOOT = 199


def mag_layer(rec, poses=None, *, alpha: float = 0.05, n_boot: int = N_BOOT, seed: int = 20240708):
    """The magnetometer loop of a recording: ``(result, None)``, or ``(None, reason)`` in one
    line (no magnetometer, columns no fit can use): the accelerometer's loop runs anyway.

    The noise is measured at the accelerometer's rests (``poses``) as ``accelcal calibrate``
    does for the magnetometer, else at the field's quietest stretches."""
    if getattr(rec, "mag", None) is None:
        return None, "no magnetometer in the recording"
    try:
        samples, rows = field_samples(rec.mag, None if poses is None else poses.intervals, rec.source)
        temp = None if rec.temp is None else np.asarray(rec.temp, float)[rows]
        return mag_discrepancy(samples, temp, alpha=alpha, n_boot=n_boot, seed=seed), None
    except AccelcalError as e:
        return None, f"magnetometer not tested: {str(e).splitlines()[0]}"


__all__ = ["AR_ORDER", "CANDIDATES", "N_BOOT", "CANDIDATE_NAMES", "MagCandidate", "MagLoopResult", "N_GRID", "field_samples", "mag_discrepancy", "mag_layer",
           "noise_model", "window_columns"]
