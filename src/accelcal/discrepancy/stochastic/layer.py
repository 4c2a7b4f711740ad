"""Stochastic layer of the discrepancy workflow: which noise term does the simulator miss?

The simulator's noise model starts as white noise.  This module compares the Allan
deviation of the measured rest intervals with that model, names the missing noise term
(if any) by a calibrated test, adds it, re-simulates the rests and reports how much the
Allan-deviation gap shrinks, and what the named term means for the static-pose means
the deterministic calibration works with.

Identifiability (measured: 4 simulated sessions × 3 axes per row, one 52 s rest and
twenty 8 s rests at 100 Hz, N = 0.1, each term crossing the white line 1–3 octaves
below τ_max).  With the default candidates the layer named nothing on 12/12 white-only
axes and named the injected term first on 12/12 quantization, 12/12 flicker, 9/12 random
walk (one ramp, one flicker, one sinusoid instead), 11/12 ramp (one random walk) and
12/12 sinusoid axes.  Adding ``gauss_markov`` turned 6/12 flicker axes and 4/12 random
walk axes into Gauss–Markov ones; an injected Gauss–Markov bias (T_c = 1 s) is named
``gauss_markov`` on 8/12 axes when it is a candidate and ``bias_instability`` or
``sinusoid`` when not.  The flicker floor is the one-parameter reading of "bias
instability" that records this short can identify.

Test (exactly).  Start from ``white``.  At each step, for every remaining candidate
``k`` fit current + ``k``; ``LR_k = D_current − D_{current+k}`` and
``ΔBIC_k = −LR_k + p_k ln(n_τ)`` (``p_k`` = 1, 2 for the two-parameter terms).  The AVAR
points at neighbouring τ are correlated, the edf are approximations, ``c_k = 0`` lies on
the boundary and ``T_c``/``f₀`` are not identified under the null, so ``LR`` is not χ²: its null
distribution comes from a parametric bootstrap — ``n_boot`` synthetic data sets of the
fitted current model with the measured segment lengths, each refitted with current and
every current + k.  Per-candidate p-value ``(1 + #{LR*_k ≥ LR_k}) / (n_boot + 1)``;
the multiple-comparison correction over candidates is the max-statistic one
(Westfall–Young): candidate ``k``'s adjusted p-value is
``(1 + #{max_k' LR*_k' ≥ LR_k}) / (n_boot + 1)``, which holds the family-wise error of the
step at ``alpha`` whatever the dependence between candidates.  The candidate with the
smallest ``ΔBIC`` is named when its adjusted p-value is below ``alpha`` *and*
``ΔBIC < 0``; the search stops at the first step that names nothing or after
``max_terms`` terms.  Step 1 is a level-``alpha`` test of "white is enough", so
white-only data get a term named with probability ≤ ``alpha`` per axis.  Standard
errors: standard deviation of the refitted coefficients over the ``n_boot`` bootstrap
sets of the final model.  Step 1's null (white only) is the same on every axis up to its scale ``N``, and the
statistics (deviances, LR, ΔBIC) are scale-free, so one bootstrap at ``N = 1`` serves all
axes (its coefficients times each axis's ``N`` give the standard errors): exact, and a
third of the cost of a bootstrap per axis.

Fit.  Every model is fitted by :func:`accelcal.noise.allan_fit.fit_avar` (the Gamma
likelihood of the Allan variance points, coefficients ≥ 0), weighted by the pooled
white-FM edf of the rests, without the model-error variance that the noise analysis of a
long static record adds (:func:`accelcal.noise.allan_fit.fit_avar_model_error`): the
rests are short, white noise dominates their Allan variance, and the tests below are
calibrated by a bootstrap of the time series with these weights.  The error bars of the
Allan deviation use the edf of the fitted model (:func:`~accelcal.noise.allan_fit.model_edf`,
its Satterthwaite mix).

Gap (one definition, before and after).  The rests are re-simulated ``n_resim`` times
with the fitted model (same segment lengths; white-only fit "before", final model
"after", common random numbers) and the simulated Allan variance is the mean over the
replicates.  With ``r_j = log10(ADEV_measured(τ_j) / ADEV_simulated(τ_j))`` and
``s_j = 1/(ln 10 √(2 ν_j))`` the standard error of the measured ``log10 ADEV`` (white-FM
edf ``ν_j``: the same yardstick before and after)::

    gap     = sqrt(mean_j (r_j / s_j)²)   ≈ 1 when the model explains the data to
                                          within its sampling noise
    log_gap = sqrt(mean_j r_j²)           decades; dominated by the noisy long τ

Homogeneity.  Pooling assumes every rest is the same process.  The layer also reports,
per τ, the ratio of the Allan deviation of the other rests (pooled) to that of the
longest rest, with a two-sided F-test p-value (white-FM edf): hand-placed poses that are
noisier than the initial rest show up there, and then a term named on the pooled curve
describes the poses' disturbance as much as the sensor.

"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ... import distributions as dist
from ...noise.allan import AllanVariance, allan_variance, check_segments
from ...noise.allan_fit import NoiseFit, fit_avar, fit_avar_batch, model_edf
from ...noise.simulation import simulate_segments
from ...noise.terms import TERMS, noise_term
from .implication import pose_residual_implication
from .results import AxisStochastic, StochasticError, StochasticResult

#: Default candidates: the one-parameter terms and the sinusoid.  ``gauss_markov`` is
#: opt-in: it imitates a random walk or a flicker floor over 3 decades of τ (module
#: docstring, "Identifiability").
DEFAULT_CANDIDATES = ("quantization", "bias_instability", "random_walk", "drift_ramp", "sinusoid")
DEFAULT_N_BOOT = 199
DEFAULT_N_RESIM = 16


# --------------------------------------------------------------------------- homogeneity


def segment_homogeneity(allan_longest: AllanVariance, allan_others: AllanVariance | None) -> dict:
    """Allan deviation of the other rests relative to the longest, with two-sided F-test p-values.

    Returns lists over the τ where both have terms (empty without other rests):
    ``taus``, ``adev_ratio`` (shape (k, d) as nested lists) and ``p_value``.
    """
    if allan_others is None:
        return {"taus": [], "adev_ratio": [], "p_value": []}
    k = min(allan_longest.taus.size, allan_others.taus.size)
    ratio = allan_others.avar[:k] / allan_longest.avar[:k]
    nu_o, nu_l = allan_others.edf[:k, None], allan_longest.edf[:k, None]
    cdf = dist.f_cdf(ratio, nu_o, nu_l)
    p = np.minimum(1.0, 2 * np.minimum(cdf, 1 - cdf))
    return {"taus": allan_longest.taus[:k], "adev_ratio": np.sqrt(ratio), "p_value": p}


def rest_segments(acc, intervals) -> list[np.ndarray]:
    """Cut the rests ``[start, stop)`` (e.g. :attr:`accelcal.static.StaticPoses.intervals`) out of ``acc``."""
    acc = np.asarray(acc, dtype=float)
    iv = np.asarray(intervals, dtype=int)
    if iv.ndim != 2 or iv.shape[1] != 2 or np.any(iv[:, 0] < 0) or np.any(iv[:, 1] > len(acc)) \
            or np.any(iv[:, 1] <= iv[:, 0]):
        raise StochasticError(f"intervals must be [start, stop) rows within the {len(acc)} samples")
    return [acc[a:b] for a, b in iv]


def stochastic_layer(segments, fs: float, *, seed: int, alpha: float = 0.05, max_terms: int = 3,
                     candidates: Sequence[str] = DEFAULT_CANDIDATES, intervals=None,
                     n_boot: int = DEFAULT_N_BOOT, n_resim: int = DEFAULT_N_RESIM,
                     axis_names: Sequence[str] | None = None, unit: str = "u") -> StochasticResult:
    """Name the noise terms a white-noise simulator misses, per axis, and show the gap shrink.

    Parameters
    ----------
    segments : sequence of array_like, each shape (n_i, d)
        Rest intervals of the recording (rate samples in the data's unit).
    fs : float
        Sampling rate [Hz].
    seed : int
        Seeds the bootstrap and the re-simulation (results are deterministic).
    alpha, max_terms : float, int
        Family-wise level of each step's test; most terms named beyond white.
    candidates : sequence of str
        Candidate terms (ids of :data:`~accelcal.noise.TERMS`, not ``white``).
    intervals : array_like of int, shape (n_segments, 2), optional
        Sample ranges ``[start, stop)`` of the segments in the recording, for the pose
        times of the pose-residual implication; default: the segments back to back,
        which understates the drift of time-correlated terms between poses.
    n_boot : int
        Parametric-bootstrap data sets per test step (and for the standard errors).
    n_resim : int
        Re-simulations averaged into the simulated Allan deviation of the gap.
    axis_names : sequence of str, optional
        Default ``x, y, z`` for three columns, else ``0, 1, …``.
    unit : str
        Name of the data unit, for the output.

    Returns
    -------
    StochasticResult

    Raises
    ------
    StochasticError, NoiseModelError, AllanError (all :class:`~accelcal.errors.AccelcalError`)
        Non-finite or too short segments, too little data for four octaves of τ,
        constant data, bad settings (an unknown candidate: NoiseModelError).
    """
    segs = check_segments(segments, fs)
    settings = _Settings.checked(candidates, alpha, max_terms, n_boot, n_resim)
    allan, names, rests = _checked_rests(segs, fs, intervals, axis_names)
    adev_long, homog = _longest_rest(segs, fs, allan, rests.lengths)
    # Step 1's null (white only) is the same for every axis up to the scale N, and its
    # statistics are scale-free: one bootstrap at N = 1 serves all axes (exact).
    unit_white = NoiseFit(("white",), np.array([1.0]), float("nan"), 0.0)
    shared = _bootstrap(np.random.default_rng(np.random.SeedSequence([int(seed), 1 << 20])), unit_white, rests,
                        list(settings.candidates) if max_terms > 0 else [], n_boot)
    axes = []
    for j, name in enumerate(names):
        boot_seq, resim_seq = np.random.SeedSequence([int(seed), j]).spawn(2)
        axes.append(_one_axis(name, j, rests, settings, np.random.default_rng(boot_seq), resim_seq, adev_long[:, j],
                              homog[j], shared))
    notes = ("intervals not given: pose times assume the rests back to back",) if intervals is None else ()
    return StochasticResult(fs=float(fs), seed=int(seed), alpha=float(alpha), candidates=settings.candidates,
                            n_boot=int(n_boot), n_resim=int(n_resim), segment_lengths=rests.lengths,
                            axes=tuple(axes),
                            unit=unit, notes=notes)


def _checked_rests(segs, fs, intervals, axis_names) -> tuple[AllanVariance, tuple, "_Rests"]:
    """The rests' pooled Allan variance, the axis names and the rests (refuses too few octaves of τ,
    a constant axis, names that do not match the columns)."""
    lengths = tuple(int(s.shape[0]) for s in segs)
    d = segs[0].shape[1]
    allan = allan_variance(segs, fs)
    if allan.taus.size < 4:
        raise StochasticError(f"the rests reach only {allan.taus.size} octaves of tau (longest rest "
                              f"{max(lengths) / fs:.2f} s); need at least 4 to tell noise terms apart")
    if np.any(allan.avar <= 0):
        raise StochasticError("a rest axis is constant: zero Allan variance (stuck sensor?)")
    names = tuple(axis_names) if axis_names is not None else (("x", "y", "z") if d == 3 else
                                                             tuple(str(i) for i in range(d)))
    if len(names) != d:
        raise StochasticError(f"{len(names)} axis names for {d} columns")
    starts, durations = _pose_times(intervals, lengths, fs)
    return allan, names, _Rests(allan, lengths, float(fs), starts, durations)


def _longest_rest(segs, fs, allan: AllanVariance, lengths) -> tuple[np.ndarray, list[dict]]:
    """The longest rest's Allan deviation on the pooled τ grid (NaN beyond its reach), per axis,
    and its homogeneity with the other rests (:func:`segment_homogeneity`), one dict per axis."""
    longest = int(np.argmax(lengths))
    m_long = allan.m[allan.m <= lengths[longest] // 2]
    allan_long = allan_variance([segs[longest]], fs, m=m_long)
    others = [s for i, s in enumerate(segs) if i != longest and s.shape[0] >= 2]
    m_oth = allan.m[allan.m <= max((s.shape[0] for s in others), default=0) // 2]
    allan_oth = allan_variance(others, fs, m=m_oth) if others and m_oth.size else None
    adev_long = np.full((allan.taus.size, segs[0].shape[1]), np.nan)
    adev_long[: m_long.size] = allan_long.adev
    h = segment_homogeneity(allan_long, allan_oth)
    per_axis = [{"taus": h["taus"], **{k: np.asarray(h[k])[:, j] if len(h["taus"]) else []
                                       for k in ("adev_ratio", "p_value")}} for j in range(adev_long.shape[1])]
    return adev_long, per_axis

@dataclass(frozen=True)
class _Settings:
    """The layer's settings (:func:`stochastic_layer`), checked."""

    candidates: tuple[str, ...]
    alpha: float
    max_terms: int
    n_boot: int
    n_resim: int

    @classmethod
    def checked(cls, candidates, alpha, max_terms, n_boot, n_resim) -> _Settings:
        cand = tuple(dict.fromkeys(candidates))
        for k in cand:
            noise_term(k)
        if "white" in cand:
            raise StochasticError("'white' is the base model, not a candidate")
        if not 0 < alpha < 1:
            raise StochasticError(f"alpha must be in (0, 1), got {alpha}")
        if max_terms < 0 or n_boot < 19 or n_resim < 1:
            raise StochasticError("need max_terms >= 0, n_boot >= 19 (p-values down to 0.05) and n_resim >= 1")
        return cls(cand, alpha, max_terms, n_boot, n_resim)


@dataclass(frozen=True)
class _Rests:
    """The rests as the layer sees them: their pooled Allan variance (every axis), the
    segments' lengths [samples], the rate [Hz], and the poses' start times and durations [s]."""

    allan: AllanVariance
    lengths: tuple[int, ...]
    fs: float
    starts: np.ndarray
    durations: np.ndarray


def _pose_times(intervals, lengths, fs) -> tuple[np.ndarray, np.ndarray]:
    """Start and duration [s] of each rest: from ``intervals``, else the rests back to back."""
    if intervals is None:
        ends = np.cumsum(lengths)
        iv = np.column_stack([ends - np.array(lengths), ends])
    else:
        iv = np.asarray(intervals, dtype=int)
        if iv.shape != (len(lengths), 2) or np.any(iv[:, 1] - iv[:, 0] != np.array(lengths)):
            raise StochasticError("intervals must be (n_segments, 2) [start, stop) rows matching the segment lengths")
    return iv[:, 0] / float(fs), (iv[:, 1] - iv[:, 0]) / float(fs)


@dataclass(frozen=True)
class _Refits:
    """A model's bootstrap data sets refitted: its coefficients (n_boot, p) and nonlinear
    parameter (n_boot,) under its own terms, and the LR of each added term (n_boot, k)."""

    coefs: np.ndarray
    shapes: np.ndarray
    lr: np.ndarray

    def at_white(self, n_white: float) -> _Refits:
        """The refits of the unit white model (the shared step-1 bootstrap) for white noise ``N``:
        the coefficients scale with ``N``, the statistics are scale-free."""
        return _Refits(self.coefs * n_white, self.shapes, self.lr)


def _bootstrap(rng, fit: NoiseFit, rests: _Rests, extra: Sequence[str], n_boot: int) -> _Refits:
    """Refit ``n_boot`` synthetic data sets of ``fit``'s model with its own terms and with each term + extra[k]."""
    fs, taus, edf = rests.fs, rests.allan.taus, rests.allan.edf
    sims = simulate_segments(rng, rests.lengths, fs, fit.model, size=n_boot)
    av = allan_variance(sims, fs, m=rests.allan.m).avar.T  # (n_boot, k)
    null = fit_avar_batch(taus, av, edf, fit.term_ids, fs)
    coefs = np.array([[math.sqrt(max(v, 0.0)) for v in f.c] for f in null])
    shapes = np.array([f.shape for f in null])
    dev0 = np.array([f.deviance for f in null])
    lr = np.empty((n_boot, len(extra)))
    for i, k in enumerate(extra):
        alt = fit_avar_batch(taus, av, edf, fit.term_ids + (k,), fs)
        lr[:, i] = np.maximum(dev0 - np.array([f.deviance for f in alt]), 0.0)
    return _Refits(coefs, shapes, lr)


def _fit_table(fit: NoiseFit, refits: _Refits, fs: float, tau_max: float) -> dict:
    """Coefficients with bootstrap standard errors; the nonlinear parameter's error also counts
    its grid step (uniform rounding, step²/12), else a grid-limited estimate would show 0."""
    se = refits.coefs.std(axis=0, ddof=1)
    out = {}
    for i, (k, v) in enumerate(fit.coefficients.items()):
        out[k] = {"value": v, "se": float(se[i])}
        key = TERMS[k].shape_key
        if key:
            grid = TERMS[k].shape_grid(fs, tau_max)
            step = fit.shape * (grid[1] / grid[0] - 1.0)
            out[k][key] = fit.shape
            out[k][key.rsplit("_", 1)[0] + "_se"] = float(np.sqrt(np.var(refits.shapes, ddof=1) + step**2 / 12))
    return out


@dataclass(frozen=True)
class _TermSearch:
    """The outcome of the stepwise test on one axis: the final fit, the terms it named, one
    record per step, and the bootstrap refits of the white-only fit and of the final fit."""

    after: NoiseFit
    named: tuple[str, ...]
    tests: tuple[dict, ...]
    refits_before: _Refits
    refits_after: _Refits


def _name_terms(before: NoiseFit, avar: np.ndarray, rests: _Rests, settings: _Settings, rng,
                shared: _Refits) -> _TermSearch:
    """The stepwise test of the module docstring ("Test") on one axis, from the white-only fit ``before``."""
    taus, edf, fs = rests.allan.taus, rests.allan.edf, rests.fs
    log_n = math.log(taus.size)
    current, refits_before, refits, tests, named = before, None, None, [], []
    while len(named) < settings.max_terms:
        # at most one two-parameter term per model: once one is named the others drop out
        has_shaped = any(TERMS[k].shape_key for k in current.term_ids)
        remaining = [k for k in settings.candidates
                     if k not in current.term_ids and not (has_shaped and TERMS[k].shape_key)]
        if not remaining:
            break
        alts = {k: fit_avar(taus, avar, edf, current.term_ids + (k,), fs) for k in remaining}
        lr_obs = np.array([max(current.deviance - alts[k].deviance, 0.0) for k in remaining])
        if current.term_ids == ("white",) and list(remaining) == list(settings.candidates):
            refits = shared.at_white(current.coefficients["white"])
        else:
            refits = _bootstrap(rng, current, rests, remaining, settings.n_boot)
        refits_before = refits if refits_before is None else refits_before
        step = _test_step(current, alts, remaining, lr_obs, refits.lr, settings, log_n, len(tests) + 1)
        tests.append(step)
        if step["named"] is None:
            break
        named.append(step["named"])
        current = alts[step["named"]]
        refits = None
    if refits is None and current.term_ids == ("white",):
        refits = shared.at_white(current.coefficients["white"])
    if refits is None:  # the final model was never the null of a test: bootstrap its standard errors
        refits = _bootstrap(rng, current, rests, [], settings.n_boot)
    return _TermSearch(current, tuple(named), tuple(tests), refits if refits_before is None else refits_before, refits)


def _test_step(current: NoiseFit, alts: dict, remaining: list, lr_obs: np.ndarray, lr_boot: np.ndarray,
               settings: _Settings, log_n: float, step: int) -> dict:
    """One step's record: every remaining candidate's LR, p-values (raw and max-statistic
    adjusted), ΔBIC and estimate; the best one, and whether it is named."""
    n_boot = settings.n_boot
    # a bootstrap LR equal to the observed one up to round-off counts as ≥
    tol = 1e-9 * max(1.0, float(lr_obs.max()))
    p_raw = (1 + (lr_boot >= lr_obs[None, :] - tol).sum(axis=0)) / (n_boot + 1)
    p_adj = (1 + (lr_boot.max(axis=1)[:, None] >= lr_obs[None, :] - tol).sum(axis=0)) / (n_boot + 1)
    dbic = -lr_obs + np.array([TERMS[k].n_parameters for k in remaining]) * log_n
    best = int(np.argmin(dbic))
    accept = bool(p_adj[best] < settings.alpha and dbic[best] < 0)
    return {
        "step": step,
        "current_model": list(current.term_ids),
        "candidates": {k: {"statistic": float(lr_obs[i]), "p_value": float(p_raw[i]),
                           "p_value_adjusted": float(p_adj[i]), "delta_bic": float(dbic[i]),
                           "value": alts[k].coefficients[k],
                           **({TERMS[k].shape_key: alts[k].shape} if TERMS[k].shape_key else {})}
                       for i, k in enumerate(remaining)},
        "best": remaining[best],
        "named": remaining[best] if accept else None,
    }


def _adev_interval(allan: AllanVariance, fit: NoiseFit, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """68.3 % interval of the measured Allan deviation (every axis) with the edf of the model
    ``fit`` (:func:`~accelcal.noise.allan_fit.model_edf`, the Satterthwaite mix of its terms'
    edf: narrower than the coherent mix where terms overlap, kept so that the layer's
    outputs do not change)."""
    nu_mix = model_edf(allan, fit, mix="satterthwaite")
    return allan.adev_interval(0.683, np.column_stack([nu_mix] * allan.avar.shape[1]))


def _resimulated_adev(fit: NoiseFit, rests: _Rests, n_resim: int, seq) -> np.ndarray:
    """Allan deviation of the rests re-simulated ``n_resim`` times with ``fit``'s model (mean
    Allan variance over the replicates); the same ``seq`` gives every model the same random
    numbers (common random numbers)."""
    sims = simulate_segments(np.random.default_rng(seq), rests.lengths, rests.fs, fit.model, size=n_resim)
    return np.sqrt(allan_variance(sims, rests.fs, m=rests.allan.m).avar.mean(axis=1))


def _one_axis(name: str, j: int, rests: _Rests, settings: _Settings, rng, resim_seq, adev_long: np.ndarray,
              homog: dict, shared: _Refits) -> AxisStochastic:
    allan, fs = rests.allan, rests.fs
    taus, edf = allan.taus, allan.edf
    avar = allan.avar[:, j]
    before = fit_avar(taus, avar, edf, ("white",), fs)
    search = _name_terms(before, avar, rests, settings, rng, shared)
    after = search.after
    lo, hi = _adev_interval(allan, after, fs)
    resim_before = _resimulated_adev(before, rests, settings.n_resim, resim_seq)
    # nothing named: the same simulation (common random numbers)
    resim_after = resim_before if after is before else _resimulated_adev(after, rests, settings.n_resim, resim_seq)
    adev = np.sqrt(avar)
    se_log10 = 1.0 / (math.log(10.0) * np.sqrt(2.0 * edf))

    def gaps(sim):
        r = np.log10(adev / sim)
        return float(np.sqrt(np.mean(r**2))), float(np.sqrt(np.mean((r / se_log10) ** 2)))

    log_gb, gb = gaps(resim_before)
    log_ga, ga = gaps(resim_after)
    return AxisStochastic(
        axis=name, taus=taus, n_terms=allan.n_terms, edf=edf, adev_measured=adev,
        adev_ci=np.column_stack([lo[:, j], hi[:, j]]), adev_longest_rest=adev_long,
        adev_model_before=np.sqrt(before.avar(taus, fs)), adev_model_after=np.sqrt(after.avar(taus, fs)),
        adev_resim_before=resim_before, adev_resim_after=resim_after,
        fit_before=_fit_table(before, search.refits_before, fs, taus.max()),
        fit_after=_fit_table(after, search.refits_after, fs, taus.max()), tests=search.tests,
        named=search.named, gap_before=gb, gap_after=ga, log_gap_before=log_gb, log_gap_after=log_ga,
        homogeneity=homog,
        pose_residual_implication=pose_residual_implication(after.model, rests.starts, rests.durations, fs,
                                                            float(taus.max())))


__all__ = ["DEFAULT_CANDIDATES", "DEFAULT_N_BOOT", "DEFAULT_N_RESIM", "rest_segments", "segment_homogeneity",
           "stochastic_layer"]
