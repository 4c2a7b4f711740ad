"""The fitted wander: REML of the noise ``(s, q, τ)`` and of the axis correlation ``φ``.

Package docstring, "Estimation (REML)" and "Axes that wander together".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ... import distributions as dist
from .gls import MAX_WHITE_SCALE, MIN_WHITE_SCALE, Q_REL_GRID, Basis, basis, profile
from .members import GridMember, column_members, member_of, members_in
from .problem import TAU_PER_DECADE_FINE, Problem, gm_variance, kernel_eigensystems, tau_grid

#: ``χ²₁`` quantile of the 95 % profile-likelihood intervals.
CHI2_95 = float(dist.chi2_isf(0.05, 1))


# --------------------------------------------------------------------------- fitted wander


@dataclass(frozen=True)
class WanderFit:
    """REML estimate of the noise model ``s (I + q K_τ)`` under one model, with its
    profile-likelihood intervals.

    ``white_scale`` = ``ŝ`` (variance of the white part over the rests' prediction);
    ``q_rel`` the wander's variance relative to the white one in the contrasts (the tests'
    scale), ``q_abs`` in the data unit squared (``s_w²``, the wander's variance; ``K²`` for
    the random walk), ``size`` its std, ``K`` its short-lag random-walk coefficient (per
    axis).  ``common`` is the wander's correlation ``φ`` between the axes the fit stands at,
    ``common_ci`` its 95 % profile interval on :data:`COMMON_GRID` and ``common_profile``
    the profiled ``−2ℓ_R`` at each grid value (:func:`fit_common`; empty when ``φ`` was not
    estimated).
    """

    t: int
    q_rel: float
    tau: float
    q_abs: float
    size: float
    K: float
    white_scale: float
    reml: float
    size_ci: tuple
    tau_ci: tuple
    K_ci: tuple
    white_scale_ci: tuple
    excess_ci: tuple
    at_bound: tuple
    common: float = 0.0
    common_ci: tuple = ()
    common_profile: tuple = ()

    @property
    def present(self) -> bool:
        return self.q_rel > 0

    @property
    def member(self) -> GridMember:
        """The member of the grid the estimate stands at (:data:`.members.MEMBERS`)."""
        return member_of(self.tau)


#: Relative variances of the report's grid: 0, then ten per decade.
Q_REL_FINE = np.concatenate([[0.0], np.logspace(-3.0, 4.0, 71)])
#: White-scale factors (over the conditional estimate) the report's intervals scan.
S_FACTORS = np.logspace(-1.0, 1.0, 81)


def fit_wander(prob: Problem, X: np.ndarray, fine: bool = True, bas: Basis | None = None) -> WanderFit:
    """REML estimate of ``(s, q, τ)`` for fixed-effect columns ``X``, with 95 % profile intervals.

    ``fine``: estimate and intervals on a grid of ten ``τ`` and ten ``q`` per decade (what
    the report uses); otherwise the test grid, without intervals (``bas``: the
    :class:`Basis` of ``X`` on it, if known).
    """
    if not fine:
        sf = profile(prob, X, prob.y[None], Q_REL_GRID, bas=bas)
        reml = sf.reml[0]
        t, k = np.unravel_index(int(np.argmin(reml)), reml.shape)
        return _wander_at(prob, int(t), float(Q_REL_GRID[k]), float(sf.white_scale()[0, t, k]), float(reml[t, k]))
    fp = prob.with_taus(tau_grid(prob.durations, prob.span, TAU_PER_DECADE_FINE, members=members_in(prob.taus)))
    sf = profile(fp, X, fp.y[None], Q_REL_FINE)
    nu = max(sf.m - sf.p, 1)
    quad = sf.quad[0]                                           # (T, Q)
    dev = sf.reml[0]
    tf, kf = np.unravel_index(int(np.argmin(dev)), dev.shape)
    best = float(dev[tf, kf])
    s_hat = sf.white_scale()[0]
    # the full deviance over (τ, q, s), s = f ŝ(τ, q) on a scan around the optimum (above the
    # floor), at the grid points whose profiled deviance is inside the region (the others have
    # no s inside it: the deviance at ŝ is its minimum over the allowed s)
    ct, cq = np.nonzero(dev <= best + CHI2_95 + 1e-9)
    s_full = s_hat[ct, cq][:, None] * S_FACTORS[None, :]                     # (N, S)
    dev_full = nu * np.log(s_full) + quad[ct, cq][:, None] / s_full + (sf.logdet + sf.logdet_a)[ct, cq][:, None]
    inside = ((dev_full <= best + CHI2_95) & (s_full >= MIN_WHITE_SCALE * (1 - 1e-12))
              & (s_full <= MAX_WHITE_SCALE * (1 + 1e-12)))
    taus, T = fp.taus, fp.taus.size
    tv, qv = taus[ct][:, None], Q_REL_FINE[cq][:, None]
    q_abs = s_full * qv / fp.scale[ct][:, None]
    col = _columns(taus)
    stationary, has_tau, kind = (a[ct][:, None] for a in (col.stationary, col.has_tau, col.size_kind))
    with np.errstate(divide="ignore", invalid="ignore"):
        size = np.where(stationary, np.sqrt(q_abs), np.inf)
        K = np.where(qv > 0, col.K(ct, q_abs, tv), 0.0)  # no wander: K = 0 whatever the member
    # the residual excess the model predicts on average: sqrt(s (1 + q)) (mean eigenvalue 1)
    excess = np.sqrt(s_full * (1.0 + qv))
    wander = inside & (qv > 0)
    # members without a time scale (the per-placement offset, flicker): the intervals of τ
    # and K are the timed wanders' (and τ's the offset's 0; the flicker member's size is
    # its B, not a std: the size interval is of the members whose size is the chosen one's)
    timed = wander & col.timed[ct][:, None]
    bound = _bounds(inside, wander, timed, ct, cq, col, float(s_hat[tf, kf]))

    def rng(a, mask):
        v = a[mask]
        return (float(np.min(v)), float(np.max(v))) if v.size else (float("nan"), float("nan"))

    tau_ci = rng(np.broadcast_to(tv, inside.shape), wander & has_tau)
    same = inside & ((kind == col.size_kind[tf]) | (qv == 0))
    size_ci, K_ci = rng(size, same), rng(K, inside & (col.timed[ct][:, None] | (qv == 0)))
    if inside[cq == 0].any():  # q = 0 inside the region: the lower ends are 0
        size_ci, K_ci = (0.0, size_ci[1]), (0.0, K_ci[1])
    out = _wander_at(fp, int(tf), float(Q_REL_FINE[kf]), float(s_hat[tf, kf]), best)
    return WanderFit(**{**out.__dict__, "size_ci": size_ci, "tau_ci": tau_ci, "K_ci": K_ci,
                        "white_scale_ci": rng(s_full, inside), "excess_ci": rng(excess, inside),
                        "at_bound": bound})


@dataclass(frozen=True)
class _Columns:
    """What each column of a grid's member is (:mod:`.members`): the arrays (T,) of
    :attr:`~.members.GridMember.stationary`, ``timed``, ``has_tau``, ``size_kind``."""

    taus: np.ndarray
    owners: list
    stationary: np.ndarray
    timed: np.ndarray
    has_tau: np.ndarray
    size_kind: np.ndarray

    def K(self, ct, q_abs, tv) -> np.ndarray:
        """Each member's random-walk coefficient at the grid points of columns ``ct`` (N,)."""
        out = np.full(q_abs.shape, np.nan)
        for m, own in self.owners:
            rows = own[ct]
            out[rows] = m.K(q_abs[rows], tv[rows])
        return out

    def notes(self, wander, ct) -> list[tuple[str, str]]:
        """``(tau_note, region_note)`` of each member, in table order, that the region holds with a wander."""
        return [(m.tau_note, m.region_note) for m, own in self.owners if wander[own[ct]].any()]


def _columns(taus) -> _Columns:
    owners = column_members(taus)
    member = [next(m for m, own in owners if own[t]) for t in range(taus.size)]

    def attr(name, dtype):
        return np.array([getattr(m, name) for m in member], dtype)

    return _Columns(taus, owners, attr("stationary", bool), attr("timed", bool), attr("has_tau", bool),
                    attr("size_kind", object))


def _bounds(inside, wander, timed, ct, cq, col: _Columns, s_opt: float) -> tuple[str, ...]:
    """Where the 95 % region of :func:`fit_wander` meets an end of its grid (``inside``: the
    region's points; ``wander``/``timed``: those with a wander / a timed one; ``ct``/``cq``:
    their τ and q indices; ``col``: the grid's members; ``s_opt``: the white scale at the
    optimum), and the notes of the members it holds with a wander (:mod:`.members`)."""
    bound = []
    taus = col.taus
    finite = taus[np.isfinite(taus) & col.timed]
    if inside[cq == Q_REL_FINE.size - 1].any():
        bound.append("size: upper end of the grid (q_rel 1e4)")
    if timed[(taus[ct] >= finite.max())[:, None] & timed].any():
        bound.append("tau: the interval reaches the random walk (no upper bound)")
    if timed[(taus[ct] == finite.min())[:, None] & timed].any():
        bound.append("tau: lower end of the grid")
    notes = col.notes(wander, ct)
    bound += [t for t, _ in notes if t] + [r for _, r in notes if r]
    if inside[:, 0].any() or inside[:, -1].any():
        bound.append("white scale: end of the scanned range (x0.1 - x10 of its estimate)")
    if np.isclose(s_opt, MIN_WHITE_SCALE):
        bound.append(f"white scale: at its floor {MIN_WHITE_SCALE:g}")
    if np.isclose(s_opt, MAX_WHITE_SCALE):
        bound.append(f"white scale: at its ceiling {MAX_WHITE_SCALE:g}")
    return tuple(bound)


def _wander_at(prob: Problem, t: int, q_rel: float, s_hat: float, reml: float) -> WanderFit:
    tau = float(prob.taus[t])
    q_abs = s_hat * q_rel / float(prob.scale[t])
    size, K = gm_variance(q_abs, tau)
    nan2 = (float("nan"), float("nan"))
    return WanderFit(t=t, q_rel=q_rel, tau=tau, q_abs=q_abs, size=size, K=K, white_scale=s_hat, reml=reml,
                     size_ci=nan2, tau_ci=nan2, K_ci=nan2, white_scale_ci=nan2, excess_ci=nan2, at_bound=(),
                     common=float(prob.common))


#: Correlations ``φ`` of the wander between the sensor axes that :func:`fit_common` chooses
#: from: independent axes, then a common-mode share of a third to all of the wander (four
#: values: each costs one diagonalisation of the kernels per round; with five the loop was
#: 1.3x slower than with independent axes on sessions with effects).
COMMON_GRID = np.array([0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0])


def fit_common(prob: Problem, X: np.ndarray, grid=None) -> tuple[Problem, Basis, WanderFit]:
    """REML of the wander's axis correlation ``φ`` jointly with ``(s, q, τ)`` on the test grid.

    The kernels of every ``(φ, τ)`` are diagonalised as one stack and profiled in one pass
    (the grid of ``τ`` repeated per ``φ``), so the cost is that of one profile on a grid
    ``len(grid)`` times longer.

    Parameters
    ----------
    prob : Problem
        The linearised problem (any ``common``).
    X : ndarray (m, p)
        Fixed-effect columns of the model whose noise is estimated.
    grid : array_like, optional
        Values of ``φ`` (default :data:`COMMON_GRID`; ``0`` first: a tie, e.g. no wander at
        all, keeps independent axes).

    Returns
    -------
    Problem, Basis, WanderFit
        The problem rebuilt at the estimate ``φ̂``, the :class:`Basis` of ``X`` on it, and
        the REML noise there (``fit_wander(..., fine=False)``) with ``common_ci`` (the grid
        values within ``χ²₁(0.95)`` of the minimum) and ``common_profile``.
    """
    grid = np.asarray(COMMON_GRID if grid is None else grid, float)
    T = prob.taus.size
    lam, V, scale = kernel_eigensystems(prob, prob.taus, grid)
    stack = Problem(prob.y, prob.X0, prob.L, prob.sigma, prob.grad, prob.starts, prob.durations,
                    np.tile(prob.taus, grid.size), lam, V, scale, prob.notes, float("nan"), prob.rests)
    bas = basis(stack, X)
    dev = profile(stack, X, prob.y[None], Q_REL_GRID, bas=bas).reml[0].reshape(grid.size, -1).min(axis=1)
    k = int(np.argmin(dev))
    sl = slice(k * T, (k + 1) * T)
    p = Problem(prob.y, prob.X0, prob.L, prob.sigma, prob.grad, prob.starts, prob.durations, prob.taus,
                lam[sl], V[sl], scale[sl], prob.notes, float(grid[k]), prob.rests)
    b = Basis(bas.K, bas.U[sl], bas.mu[sl], bas.logdet_xx)
    w = fit_wander(p, X, fine=False, bas=b)
    inside = grid[dev <= dev[k] + CHI2_95]
    w = WanderFit(**{**w.__dict__, "common_ci": (float(inside.min()), float(inside.max())),
                     "common_profile": tuple(float(v) for v in dev)})
    return p, b, w



def at(prob: Problem, w: WanderFit) -> tuple[Problem, float]:
    """The one-τ problem of a fitted noise ``w`` and its relative wander variance there
    (``q_abs = s q / scale_τ``: the same wander whatever the grid it was found on)."""
    p1 = prob.with_taus([w.tau])
    return p1, float(w.q_abs * p1.scale[0] / w.white_scale) if w.white_scale > 0 else 0.0



__all__ = ["CHI2_95", "COMMON_GRID", "Q_REL_FINE", "S_FACTORS", "WanderFit", "at", "fit_common", "fit_wander"]
