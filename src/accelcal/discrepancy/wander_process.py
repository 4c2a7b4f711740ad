"""The wander processes: one table, each entry carrying all its behaviour.

The wander null (:mod:`.wander`) chooses by REML among the members of a grid: a
per-placement offset, a flicker (1/f) bias, Gauss–Markov wanders of many correlation
times and a random walk.  What the report, the command line and the reproductions do
with the member chosen (its name in the JSON, its covariance between pose means, its
Allan variance in the rests, the noise-library terms it is, its reading in words, its
cell in the sessions table) is a method or attribute of one :class:`WanderProcess`
subclass here, registered in :data:`PROCESSES`, never a branch on its name elsewhere
(``tests/test_wander_process_conformance.py`` checks every entry the same way;
``tests/test_wander_process_table.py`` keeps name comparisons out of other modules).

=================  ========================  ===========================  ====================
process (JSON)     term (JSON)               numbers (JSON keys)          noise-library term
=================  ========================  ===========================  ====================
``none``           ``none``                  —                            —
``per_placement``  ``per_placement_offset``  ``size``                     — (not a time series)
``flicker``        ``bias_wander``           ``size`` (its B)             ``bias_instability``
``random_walk``    ``bias_wander``           ``random_walk_K``            ``random_walk``
``gauss_markov``   ``bias_wander``           ``size``, ``tau_s``          ``gauss_markov``
=================  ========================  ===========================  ====================

What the grid's members are numerically (their codes, kernels, Allan variances in the
rests) is the member table's (:data:`accelcal.discrepancy.wander.MEMBERS`,
:mod:`.wander.members`); a process names its member (``member``).
:func:`process_of` names the process of a REML estimate (the last registered entry whose
:meth:`WanderProcess.matches` holds: an entry added later refines an earlier one);
:func:`process_in` reads it back from a report's ``noise_model``.

The *families* (:data:`FAMILIES`, the ``wander_family`` rule) say which members the grid
holds and what the problem is joined with; :func:`linearise_noise
<accelcal.discrepancy.wander_model.linearise_noise>` reads them off the entry.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import AccelcalError
from ..jsonsafe import is_finite
from ..noise.terms import TERMS
from .stochastic.implication import pose_difference_variance
from .wander import FLICKER, MEMBERS, PLACEMENT

NAN = float("nan")


def _g(v) -> str:
    """A number of the reading (None, NaN and ±inf: an open end)."""
    return "open" if v is None or not np.isfinite(v) else f"{v:.3g}"


def _interval(ci, what: str = "") -> str:
    lo, hi = (list(ci) + [NAN] * 2)[:2] if ci else (NAN,) * 2
    return f"[{_g(lo)}, {_g(hi)}{(' ' + what) if what else ''}]"


def _pair(ci) -> list:
    """The two ends of a JSON interval (None where absent)."""
    return (list(ci or []) + [None, None])[:2]


@dataclass(frozen=True)
class Words:
    """What every reading shares: the size formatter (unit, mg) and the white-scale and
    axis-correlation clauses of the report's ``noise_model`` (:func:`describe_noise_model
    <accelcal.discrepancy.wander_model.describe_noise_model>`)."""

    unit: str | None
    axes: str
    white: str

    def size(self, v) -> str:
        if v is None or not np.isfinite(v):
            return "open"
        u = self.unit or "data unit"
        return f"{v:.3g} {u}" + (f" ({1e3 * v / 9.80665:.3g} mg)" if self.unit == "m/s^2" else "")


class WanderProcess:
    """One wander process: its names, its numbers and all its behaviour.

    ``id`` is the report's ``noise_model.process``, ``term`` its ``noise_model.term``;
    ``parameters`` maps the JSON keys that carry the process's numbers to what they mean
    (a process with ``size`` has a stationary size); ``noise_term`` names the noise
    library's term (:data:`accelcal.noise.terms.TERMS`) the process is, None when it is not
    a time series (the per-placement offset) or nothing at all.
    """

    id: str
    term: str = "bias_wander"
    meaning: str
    label: str
    noise_term: str | None = None
    parameters: dict = {}
    #: A REML estimate of it for the conformance suite: :class:`~.wander.WanderFit` fields
    #: (``tau``, the grid member; ``q_abs``; optionally ``tau_ci``), None for ``none``.
    example: dict | None = None
    #: Whether it is a noise term beyond the rests' white noise (False only for ``none``).
    named: bool = True
    #: The member of the REML grid (:data:`accelcal.discrepancy.wander.MEMBERS`) whose
    #: estimate it is; its covariance is that member's kernel.
    member: str | None = None

    # ----- from the REML estimate (:class:`~.wander.WanderFit`)
    def matches(self, w, span: float) -> bool:
        """Whether the estimate ``w`` (session of ``span`` seconds) is this process: a
        wander at a code of its :attr:`member`."""
        return bool(w.present and w.member.id == self.member)

    def tau_s(self, w) -> float:
        """The JSON's ``tau_s`` (s; 0 for the offset, inf for a random walk, NaN without one)."""
        return w.tau if w.present else NAN

    def change_over_session(self, w, span: float) -> float:
        """The wander's change over the session (only a random walk has no stationary size)."""
        return NAN

    def white_like(self, w, shortest: float) -> bool:
        """Whether the estimate acts as white noise at the scale of the poses (τ below half the shortest)."""
        return bool(w.present and np.isfinite(w.tau) and w.tau < 0.5 * shortest)

    def white_excess(self, w, shortest: float) -> float:
        """The white noise it adds where it acts as white (:meth:`white_like`): ``N = sqrt(2 q τ)``."""
        return math.sqrt(2 * w.q_abs * w.tau) if self.white_like(w, shortest) else NAN

    def time_correlated(self, w, shortest: float) -> bool:
        """Whether its time correlation is established (the τ interval stays above the poses)."""
        lo = w.tau_ci[0] if w.tau_ci else NAN
        return bool(w.present and np.isfinite(lo) and lo >= 0.5 * shortest)

    def model_entry(self, w):
        """The noise library's model entry of the estimate (``noise_term``'s coefficient)."""
        return math.sqrt(w.q_abs)

    def own_variance(self, w) -> float:
        """Variance it adds to each pose mean independently of the others (data unit²; only
        an offset drawn once per placement has one: a wander's is in its covariance)."""
        return 0.0

    def difference_variance(self, w, starts, durations) -> np.ndarray:
        """``D_ij = Var(β̄_i − β̄_j)`` of the estimate between the poses' means (data unit²)."""
        return pose_difference_variance(self.noise_term, self.model_entry(w), starts, durations)

    # ----- from the report's JSON ``noise_model``
    def components(self, nm: dict) -> tuple:
        """The process as noise-library model entries ``((term, value), ...)`` of one axis
        (what the reproductions simulate); empty when it is not part of the time series."""
        return ()

    def placement_size(self, nm: dict) -> float:
        """Std of an offset drawn once per placement (data unit; 0 for every other process)."""
        return 0.0

    def size(self, nm: dict):
        """Its stationary size (``size`` among its parameters), else None."""
        return nm.get("size") if "size" in self.parameters else None

    def rest_allan(self, nm: dict):
        """What it adds to the rests' Allan variance: ``(k, k_ci, avar)`` with ``avar(taus,
        k, fs)`` at coefficient ``k`` (its band from ``k_ci``), or the allan check's verdict
        (a dict) when the rests cannot show it (:func:`~.report.allan_check`)."""
        return {"verdict": "no wander named"}

    def reading(self, nm: dict, words: Words) -> str:
        """The process in words, with what its numbers mean."""
        raise NotImplementedError

    def cell(self, nm: dict, g) -> tuple[str, str]:
        """Its value and interval in the sessions table, numbers written by ``g``."""
        ci = f"size [{', '.join(map(g, nm.get('size_ci') or [None, None]))}]"
        return f"size {g(nm.get('size'))}", ci


PROCESSES: dict[str, WanderProcess] = {}


class Meanings(Mapping):
    """``{process id: meaning}`` of :data:`PROCESSES` as it is now (the report schema's
    values of ``noise_model.process``: a process registered later is a known value too)."""

    def __getitem__(self, key: str) -> str:
        return PROCESSES[key].meaning

    def __iter__(self):
        return iter(PROCESSES)

    def __len__(self) -> int:
        return len(PROCESSES)


MEANINGS = Meanings()


def register_process(cls: type[WanderProcess]) -> type[WanderProcess]:
    """Class decorator: one instance of ``cls`` becomes the entry ``PROCESSES[cls.id]``."""
    if cls.id in PROCESSES:
        raise AccelcalError(f"wander process {cls.id!r} is already registered")
    PROCESSES[cls.id] = cls()
    return cls


def unregister_process(process_id: str) -> None:
    """Remove an entry (an example's or a test's)."""
    PROCESSES.pop(process_id, None)


def process_of(w, span: float) -> WanderProcess:
    """The process of the REML estimate ``w`` on a session of ``span`` seconds."""
    for p in reversed(PROCESSES.values()):
        if p.matches(w, span):
            return p
    raise AccelcalError(f"no wander process matches the estimate tau={w.tau!r}: register one")


def process_in(nm: dict | None) -> WanderProcess:
    """The process a report's ``noise_model`` names (``none`` when it names none)."""
    nm = nm or {}
    name = nm.get("process") or _process_of_term(nm)
    if name not in PROCESSES and not nm.get("estimated"):  # the white null's: a description, no process
        return PROCESSES["none"]
    if name not in PROCESSES:
        raise AccelcalError(f"the report names the wander process {name!r}, which is not registered "
                            f"(known: {', '.join(PROCESSES)}): import the module that registers it")
    return PROCESSES[name]


def _process_of_term(nm: dict) -> str:
    """The process of a ``noise_model`` without the ``process`` key (reports that named the
    term only): the one entry of its term, and for a bias wander a Gauss–Markov process
    when it gives a finite ``tau_s``, else a random walk (as the Allan check read them)."""
    term = nm.get("term") or "none"
    if term == "bias_wander":
        tau = nm.get("tau_s")
        return "gauss_markov" if tau is not None and np.isfinite(tau) else "random_walk"
    return next((p.id for p in PROCESSES.values() if p.term == term), "none")


def wander_named(nm: dict | None) -> bool:
    """Whether a report's ``noise_model`` names a noise term beyond the rests' white noise."""
    return bool((nm or {}).get("estimated")) and process_in(nm).named


@register_process
class NoWander(WanderProcess):
    id, term, label, named = "none", "none", "none", False
    meaning = "no second term"

    def matches(self, w, span):
        return not w.present

    def time_correlated(self, w, shortest):
        return False

    def difference_variance(self, w, starts, durations):
        return np.zeros((len(starts), len(starts)))

    def reading(self, nm, words):
        return f"no pose-to-pose noise beyond the rests' white noise (REML estimate 0){words.white}"


@register_process
class PerPlacement(WanderProcess):
    id, term, label = "per_placement", "per_placement_offset", "per-placement offset"
    meaning = "independent between poses: size (std per axis), no time scale"
    parameters = {"size": "std of the offset per axis (data unit)"}
    example = {"tau": PLACEMENT, "q_abs": 4e-6}
    member = "per_placement"

    def time_correlated(self, w, shortest):
        return False

    def own_variance(self, w):
        return w.q_abs

    def difference_variance(self, w, starts, durations):
        return 2.0 * w.q_abs * (1.0 - np.eye(len(starts)))

    def white_excess(self, w, shortest):  # white-like, but it adds to each pose, not to each sample
        return NAN

    def placement_size(self, nm):
        return float(nm["size"]) if nm.get("estimated") else 0.0

    def rest_allan(self, nm):
        return {"verdict": "not visible in the rests",
                "reason": "a per-placement offset is constant within each rest: the rests' Allan deviation "
                          "cannot see it"}

    def reading(self, nm, words):
        pl = nm.get("placement") or {}
        return (f"per-placement offset: {words.size(nm.get('size'))} per axis {_interval(nm.get('size_ci'))}, "
                f"independent from pose to pose, constant within each (no time correlation between the poses)"
                f"{words.axes}{words.white}" + (f"; {pl['reading']}" if pl.get("reading") else ""))

    def cell(self, nm, g):
        value, ci = super().cell(nm, g)
        return f"{value} per axis, no time correlation", ci


@register_process
class Flicker(WanderProcess):
    id, label, noise_term = "flicker", "flicker (1/f) bias", "bias_instability"
    meaning = ("flicker (1/f) bias: a flat Allan floor 0.664 B at every averaging time, no single correlation "
               "time; size is B")
    parameters = {"size": "the flicker coefficient B (data unit; Allan floor 0.664 B)"}
    example = {"tau": FLICKER, "q_abs": 4e-6}
    member = "flicker"

    def tau_s(self, w):
        return NAN

    def white_like(self, w, shortest):
        return False

    def time_correlated(self, w, shortest):
        return bool(w.present)

    def components(self, nm):  # size is the flicker coefficient B, the noise library's bias_instability
        return ((self.noise_term, float(nm["size"])),)

    def rest_allan(self, nm):  # a flat floor (2 ln 2/π) B², its band from B's interval
        B, basis = nm.get("size"), TERMS[self.noise_term]
        if B is None or not np.isfinite(B):
            return super().rest_allan(nm)
        return B, nm.get("size_ci") or [NAN, NAN], lambda taus, k, fs: k ** 2 * basis.basis(taus, fs, None)

    def reading(self, nm, words):
        return (f"bias wander: flicker (1/f, a flat Allan floor: no single correlation time), B "
                f"{words.size(nm.get('size'))} {_interval(nm.get('size_ci'))}, Allan floor 0.664 B"
                f"{words.axes}{words.white}")

    def cell(self, nm, g):
        _, ci = super().cell(nm, g)
        return f"flicker B {g(nm.get('size'))} (Allan floor 0.664 B), no single tau", ci


def _k_band(nm: dict):
    return nm.get("random_walk_K"), nm.get("random_walk_K_ci") or [NAN, NAN]


@register_process
class RandomWalk(WanderProcess):
    id, label, noise_term = "random_walk", "random walk", "random_walk"
    meaning = ("random walk: no stationary size and no correlation time; random_walk_K, its change over "
               "t seconds having std K sqrt(t)")
    parameters = {"random_walk_K": "data unit / sqrt(s): the change over t seconds has std K sqrt(t)"}
    example = {"tau": math.inf, "q_abs": 1e-7}
    member = "random_walk"

    def change_over_session(self, w, span):
        return w.K * math.sqrt(span)

    def components(self, nm):
        return ((self.noise_term, float(nm["random_walk_K"])),)

    def rest_allan(self, nm):
        K, K_ci = _k_band(nm)
        if K is None or not np.isfinite(K):
            return super().rest_allan(nm)
        return K, K_ci, lambda taus, k, fs: k ** 2 * taus / 3.0

    def reading(self, nm, words):
        K, (klo, khi) = nm.get("random_walk_K"), _pair(nm.get("random_walk_K_ci"))
        u = words.unit or "data unit"
        return (f"bias wander: a random walk (no stationary size, no correlation time: it drifts without bound), "
                f"K {_g(K)} {u}/sqrt(s) {_interval([klo, khi])}: its change over t seconds has standard deviation "
                f"K sqrt(t), {words.size(nm.get('change_over_session'))} over the {_g(nm.get('session_s'))} s "
                f"session{words.axes}{words.white}")

    def cell(self, nm, g):
        return (f"K {g(nm.get('random_walk_K'))}/sqrt(s)",
                f"K [{', '.join(map(g, nm.get('random_walk_K_ci') or [None, None]))}]")


@register_process
class GaussMarkov(WanderProcess):
    id, label, noise_term = "gauss_markov", "Gauss-Markov wander", "gauss_markov"
    meaning = "first-order Gauss-Markov: size (std) and correlation time tau_s"
    parameters = {"size": "std of the wander per axis (data unit)", "tau_s": "correlation time (s)"}
    example = {"tau": 30.0, "q_abs": 4e-6}
    member = "gauss_markov"

    def model_entry(self, w):
        return math.sqrt(w.q_abs), w.tau

    def components(self, nm):
        return ((self.noise_term, (float(nm["size"]), float(nm["tau_s"]))),)

    def rest_allan(self, nm):
        # at τ_A ≪ τ its short-lag random-walk part K² τ_A / 3 (K² = 2 s²/τ); the exact
        # Gauss–Markov Allan variance where τ is known, the random walk's where it is not
        K, K_ci = _k_band(nm)
        if K is None or not np.isfinite(K):
            return super().rest_allan(nm)
        tau_c, basis = nm.get("tau_s"), TERMS[self.noise_term]
        if tau_c is None or not np.isfinite(tau_c):
            return K, K_ci, lambda taus, k, fs: k ** 2 * taus / 3.0
        return K, K_ci, lambda taus, k, fs: k ** 2 * tau_c / 2.0 * basis.basis(taus, fs, tau_c)

    def reading(self, nm, words):
        tlo, thi = _pair(nm.get("tau_ci"))
        low = "0: a per-placement offset is not ruled out" if tlo == 0 else _g(tlo)
        high = "no upper bound: a random walk is not ruled out" if thi is None or not np.isfinite(thi) else _g(thi)
        tau = f"correlation time {_g(nm.get('tau_s'))} s [{low}, {high}]"
        slow = ("" if nm.get("time_correlation_established") else
                "; its time correlation is not established (it may be extra noise of each pose rather than a wander)")
        return (f"bias wander: Gauss-Markov, size {words.size(nm.get('size'))} per axis "
                f"{_interval(nm.get('size_ci'))}, {tau}{words.axes}{words.white}{slow}")

    def cell(self, nm, g):
        value, ci = super().cell(nm, g)
        return (f"{value}, tau {g(nm.get('tau_s'))} s",
                f"{ci}, tau [{', '.join(map(g, nm.get('tau_ci') or [None, None]))}] s")


def words_of(nm: dict, unit: str | None = None) -> Words:
    """The clauses every reading of ``nm`` shares (module :class:`Words`)."""
    ws = nm.get("white_scale")
    white = (f"; white scale {_g(ws)} {_interval(nm.get('white_scale_ci'))} (the rests' pose noise variance times "
             f"this)" if ws is not None else "")
    axes = (f"; correlation between the axes {_g(nm.get('axis_correlation'))} "
            f"{_interval(nm.get('axis_correlation_ci'))}" if is_finite(nm.get("axis_correlation")) else "")
    return Words(unit, axes, white)


# --------------------------------------------------------------------------- families


@dataclass(frozen=True)
class WanderFamily:
    """The members the wander is chosen from and what its problem is joined with (the
    ``wander_family`` rule): ``members`` the ids of the grid's members
    (:data:`~.wander.MEMBERS`; None: every registered member, in table order), ``rests``
    whether the likelihood is joined by the rests' own samples (:mod:`.wander.rests`),
    ``short`` whether a short component the rests pin is taken out first (:mod:`.wander.sums`)."""

    id: str
    meaning: str
    members: tuple[str, ...] | None = None
    rests: bool = False
    short: bool = False

    def grid_members(self) -> tuple[str, ...]:
        """The ids of the members its grid holds, in table order."""
        return tuple(m for m in MEMBERS if self.members is None or m in self.members)


#: The families, in the order :data:`~.rules.WANDER_FAMILIES` lists them.
FAMILIES: dict[str, WanderFamily] = {f.id: f for f in (
    WanderFamily("one_process", "a per-placement offset, one Gauss-Markov process or a random walk (the earlier "
                                "model)", members=("per_placement", "gauss_markov", "random_walk")),
    WanderFamily("flicker", "one_process's members and a flicker (1/f) bias, which stands for a sum of processes "
                            "spread over the decades (wander.FLICKER)"),
    WanderFamily("flicker_rests", "flicker's members chosen by the joint likelihood of the pose residuals and the "
                                  "rests' own samples (as flicker when the pose data do not carry the rests)",
                 rests=True),
    WanderFamily("sum", "a sum of processes: flicker's members for the long part, plus a short Gauss-Markov "
                        "component pinned by the rests' Allan variances when they show one", short=True),
)}


__all__ = ["FAMILIES", "MEANINGS", "PROCESSES", "WanderFamily", "WanderProcess", "Words", "process_in", "process_of",
           "register_process", "unregister_process", "wander_named", "words_of"]
