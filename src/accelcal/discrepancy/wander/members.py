"""The members of the wander's REML grid: one table, each entry carrying its kernel.

The wander null chooses by REML among the members of a grid of "correlation times"
(package docstring): a flicker (1/f) bias, a per-placement offset, Gauss–Markov wanders
of many correlation times and a random walk.  A grid is a float array of *codes*: a
member with correlation times owns the codes that are those times (Gauss–Markov: the
finite positive ones; the random walk: ``inf``), a member without one owns one code that
is not a time (the offset ``0``, flicker ``−1``).  Everything the numerics do with a
member is a method or attribute of one :class:`GridMember` subclass here, registered in
:data:`MEMBERS` (table order is grid order), never a branch on its code elsewhere:

* its codes on the grid (:meth:`GridMember.codes`) and which codes are its (:meth:`~GridMember.owns`);
* its kernel: the variogram ``D_ij = Var(β̄_i − β̄_j)`` of the interval means of a unit
  member (:meth:`~GridMember.variogram`), which :func:`.problem.wander_kernels` turns into
  the pose residuals' generalised covariance ``−(∇_iᵀ C_φ ∇_j) D_ij / 2`` and
  :func:`.problem.kernel_eigensystems` diagonalises once per round;
* its size and random-walk coefficient from the wander variance ``q_abs``
  (:attr:`~GridMember.stationary`, :meth:`~GridMember.K`), what its size is
  (:attr:`~GridMember.size_kind`), whether its code is a correlation time the report's τ
  interval spans (:attr:`~GridMember.has_tau`), the notes the report's 95 % region takes
  from it (:attr:`~GridMember.tau_note`, :attr:`~GridMember.region_note`);
* its Allan variance within the rests (:meth:`~GridMember.rest_avar`, the joint likelihood of
  :mod:`.rests`).

What the report calls the member chosen and what it means is the wander-process table's
(:mod:`accelcal.discrepancy.wander_process`: each process names its ``member``);
``tests/test_wander_member_conformance.py`` checks every member's kernel against its
process's stated covariance, against the noise library's and as a variogram.
Adding a member: one subclass, :func:`register_member`, then its process
(``examples/custom_grid_member.py``).

Why the table costs nothing: the members act only where the kernels are built (once per
round and per one-τ refit, a loop over four entries around the same numpy arrays); the
likelihood grid, compiled or not (:mod:`._grid_kernels`), sees the kernels' eigenvalues
only.  Measured side by side (79 benchmark recordings of the default config, four runs
each, interleaved): 67.4 ms per recording before the table, 67.6 ms with it, the
detections identical.
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import AccelcalError
from ...noise.terms import IntervalPairs, model_avar, noise_term

#: The per-placement offset's code on the grid (``τ = 0``: no correlation between the poses).
PLACEMENT = 0.0
#: The flicker member's code (``τ = −1``: no correlation time).
FLICKER = -1.0


class GridMember:
    """One member of the wander's grid: its codes and its kernel (module docstring).

    ``code`` is the one code a member without a correlation time owns (None for a member
    whose codes are its correlation times: it overrides :meth:`codes` and :meth:`owns`).
    """

    id: str
    code: float | None = None
    #: Its codes are correlation times and it has a random-walk coefficient ``K``.
    timed: bool = False
    #: It has a stationary size (``sqrt(q_abs)``; a random walk has none).
    stationary: bool = True
    #: Its code is a correlation time the report's τ interval spans (the offset's 0 is).
    has_tau: bool = True
    #: What its size is: members whose size is the same quantity share the size interval.
    size_kind: str = "std"
    #: The report's note when the 95 % region holds it with a wander, about τ or about the region.
    tau_note: str = ""
    region_note: str = ""
    #: Whether it changes within a rest (a member constant within each adds nothing to the rests' Allan variance).
    within_rest: bool = True

    def codes(self, lo: float, hi: float, per_decade: int) -> np.ndarray:
        """Its codes on a grid whose correlation times run from ``lo`` to ``hi`` [s]."""
        return np.array([self.code])

    def owns(self, taus: np.ndarray) -> np.ndarray:
        """Which codes of ``taus`` are this member's (bool, same shape)."""
        return taus == self.code

    def variogram(self, taus: np.ndarray, starts: np.ndarray, durations: np.ndarray, gap: np.ndarray):
        """``D_ij`` (len(taus), n, n), or broadcastable to it, of a unit member at each of its
        codes ``taus`` over the pose intervals (``gap``: the time between two intervals; the
        diagonal is set to 0 by the caller)."""
        raise NotImplementedError

    def K(self, q_abs, taus):
        """Its random-walk coefficient at wander variance ``q_abs`` (NaN without a time scale)."""
        return np.full(np.shape(q_abs), np.nan)

    def size_K(self, q_abs: float, tau: float) -> tuple[float, float]:
        """``(size, K)`` of an estimate at code ``tau`` (``size``: inf for a member without a
        stationary size, 0 when there is no wander)."""
        q = max(q_abs, 0.0)
        size = math.sqrt(q) if self.stationary else (math.inf if q_abs > 0 else 0.0)
        return size, (float(self.K(q, tau)) if self.timed else math.nan)

    def rest_avar(self, tau: float, taus: np.ndarray, fs: float) -> np.ndarray:
        """Its Allan variance (K,) at averaging times ``taus`` [s], unit size, code ``tau``."""
        raise NotImplementedError


#: The members, in grid order (the first of tied members wins REML's argmin).
MEMBERS: dict[str, GridMember] = {}


def register_member(cls: type[GridMember]) -> type[GridMember]:
    """Class decorator: one instance of ``cls`` becomes the entry ``MEMBERS[cls.id]``, last in grid order."""
    if cls.id in MEMBERS:
        raise AccelcalError(f"grid member {cls.id!r} is already registered")
    member = cls()
    taken = [m.id for m in MEMBERS.values() if member.code is not None and m.owns(np.array([member.code]))[0]]
    if taken:
        raise AccelcalError(f"grid member {cls.id!r}: its code {member.code!r} is already {taken[0]!r}'s")
    MEMBERS[cls.id] = member
    return cls


def unregister_member(member_id: str) -> None:
    """Remove an entry (an example's or a test's)."""
    MEMBERS.pop(member_id, None)


def member_of(tau: float) -> GridMember:
    """The member whose code ``tau`` is."""
    code = np.array([float(tau)])
    for m in MEMBERS.values():
        if m.owns(code)[0]:
            return m
    raise AccelcalError(f"no grid member has the code {tau!r}: register one")


def members_in(taus) -> tuple[str, ...]:
    """The ids of the members that own a code of the grid ``taus``, in table order."""
    taus = np.asarray(taus, float)
    return tuple(m.id for m in MEMBERS.values() if m.owns(taus).any())


def column_members(taus) -> list[tuple[GridMember, np.ndarray]]:
    """Each member that owns codes of ``taus`` with the mask of its codes; every code must be owned."""
    taus = np.asarray(taus, float)
    out, seen = [], np.zeros(taus.shape, bool)
    for m in MEMBERS.values():
        own = m.owns(taus)
        if own.any():
            out.append((m, own))
            seen |= own
    if not seen.all():
        raise AccelcalError(f"no grid member has the code(s) {np.unique(taus[~seen]).tolist()}: register one")
    return out


@register_member
class Flicker(GridMember):
    """Flicker (1/f: a flat Allan floor ``0.664 B`` at every averaging time; the limit of
    Gauss–Markov components of equal Allan share spread evenly over the decades).  Its
    generalised covariance is ``−(B²/π) ln|t − t'|`` (:class:`accelcal.noise.terms.BiasInstability`),
    a unit member has ``B = 1``, so its ``q_abs`` is ``B²``.  A sum of processes from seconds
    to minutes (the "flicker-like floor" of many MEMS records) is nearer to it than to any
    one Gauss–Markov process or random walk: with it in the grid, REML chooses between them
    by their likelihood (the same number of parameters)."""

    id, code, has_tau, size_kind = "flicker", FLICKER, False, "B"
    region_note = "the 95 % region holds the flicker member (a 1/f floor: no single correlation time)"

    def variogram(self, taus, starts, durations, gap):
        return flicker_variogram(starts, durations)

    def rest_avar(self, tau, taus, fs):
        return model_avar({"bias_instability": 1.0}, taus, fs)


@register_member
class PerPlacement(GridMember):
    """An offset independent from pose to pose and constant within each: ``D = 2`` off the diagonal."""

    id, code, within_rest = "per_placement", PLACEMENT, False
    tau_note = "tau: the interval holds the per-placement offset (no time correlation between the poses)"

    def variogram(self, taus, starts, durations, gap):
        return 2.0

    def rest_avar(self, tau, taus, fs):
        return np.zeros(np.asarray(taus).size)


@register_member
class GaussMarkov(GridMember):
    """First-order Gauss–Markov wanders of unit variance, one per correlation time: ``per_decade``
    per decade from ``lo`` to ``hi``."""

    id, timed = "gauss_markov", True

    def codes(self, lo, hi, per_decade):
        k = int(math.ceil(math.log10(hi / lo) * per_decade))
        return np.geomspace(lo, hi, k + 1)

    def owns(self, taus):
        return np.isfinite(taus) & (taus > 0)

    def variogram(self, taus, starts, durations, gap):
        T = durations
        tc = taus[:, None]                                                           # (T', 1)
        W = self.interval_variance(tc, T)                                            # (T', n)
        E = -np.expm1(-T / tc) / T                                                   # (T', n)
        cov = tc[:, :, None] ** 2 * E[:, :, None] * E[:, None, :] * np.exp(-gap / tc[:, :, None])
        return W[:, :, None] + W[:, None, :] - 2 * cov

    @staticmethod
    def interval_variance(tau, durations):
        """Variance of the mean of a unit process over intervals of ``durations`` (correlation time ``tau``)."""
        T = durations
        return 2 * (tau * T + tau**2 * np.expm1(-T / tau)) / T**2

    def K(self, q_abs, taus):  # the short-lag random-walk coefficient K = sqrt(2 s²/τ)
        return np.sqrt(2 * q_abs / taus)

    def rest_avar(self, tau, taus, fs):
        return model_avar({"gauss_markov": (1.0, float(tau))}, taus, fs)


@register_member
class RandomWalk(GridMember):
    """The random walk (``τ → ∞`` at fixed ``K² = 2 σ²/τ``), ``K = 1``: ``q_abs`` is ``K²``."""

    id, code, timed, stationary = "random_walk", math.inf, True, False

    def owns(self, taus):
        return np.isinf(taus)

    def variogram(self, taus, starts, durations, gap):
        T = durations
        return gap + (T[:, None] + T[None, :]) / 3

    def K(self, q_abs, taus):
        return np.sqrt(q_abs)

    def rest_avar(self, tau, taus, fs):
        return model_avar({"random_walk": 1.0}, taus, fs)


def flicker_variogram(starts, durations) -> np.ndarray:
    """``D_ij`` of the interval means of a unit flicker (``B = 1``, :data:`FLICKER`)."""
    a, T = np.asarray(starts, float), np.asarray(durations, float)
    D = np.asarray(noise_term("bias_instability").interval_difference_variance(1.0, None, IntervalPairs(a, T)),
                   float).copy()
    np.fill_diagonal(D, 0.0)
    return D


__all__ = ["FLICKER", "MEMBERS", "PLACEMENT", "GridMember", "column_members", "flicker_variogram", "member_of",
           "members_in", "register_member", "unregister_member"]
