"""Colored noise in the null: pose residuals whose errors share a slowly wandering bias.

Pose means taken minutes apart share the sensor's slowly wandering bias, so their errors
are correlated, and a trend in them is not by itself evidence of a deterministic drift.
This module is the statistical core of the ``wander`` null of
:func:`accelcal.discrepancy.detect.discrepancy`: the covariance of the pose residuals
implied by a noise model, generalised least squares (GLS) under it, restricted maximum
likelihood (REML) of the wander jointly with the calibration, and nested tests whose
null distribution is calibrated by a parametric bootstrap.

Noise model of the pose means.  Pose ``i`` averages the samples of ``[a_i, a_i + T_i]``;
its mean error on axis ``k`` is ``ē_ik = w̄_ik + β̄_ik`` with

* ``w̄_ik`` the short-term (white, quantization, …) part, independent between poses, of
  variance ``s · se_ik²``: ``se_ik`` the standard error the static detection computed
  from the pose's own samples (Geyer's autocorrelation time, :mod:`accelcal.static`),
  ``s`` a common white scale (between :data:`MIN_WHITE_SCALE` and :data:`MAX_WHITE_SCALE`), estimated;
* ``β̄_ik`` the interval mean of a slow bias process ``β_k(t)``, the same process
  (``bias_wander``) on every axis, of size ``σ_w`` (data unit) per axis, correlated
  between the axes by ``φ`` (below): a first-order Gauss–Markov process (variance
  ``σ_w²``, correlation time ``τ``, covariance ``σ_w² exp(-|t - t'|/τ)``) or, as ``τ → ∞``
  at fixed ``K² = 2 σ_w²/τ``, a random walk ``K² min(t, t')`` (the grid of ``τ`` ends
  with it).

The covariance of two interval means is exact (:func:`accelcal.discrepancy.stochastic.
pose_difference_variance` gives the variogram ``D_ij = Var(β̄_i − β̄_j)`` in closed form;
``−D/2`` is a generalised covariance, equal to the covariance up to terms ``f_i + f_j``
that the per-axis bias of the model absorbs, which is why the random walk and the flicker
floor need no stationary variance).  A pose residual ``r_i = ‖x_i‖ − g`` moves by
``∇_i · ē_i`` with ``∇_i = ∂r_i/∂z_i`` (≈ the unit gravity direction in the sensor frame,
through ``M⁻ᵀ``), so, with ``σ_i² = Σ_k ∇_ik² se_ik²`` and ``C`` the correlation of the
wander between the axes (``Cov(β_a(t), β_b(t')) = σ_w² C_ab k_τ(t, t')``)::

    Cov(r_i, r_j) = s σ_i² δ_ij + σ_w² (∇_iᵀ C ∇_j) k_τ(i, j),   k_τ = −D_τ/2 (unit size).

Axes that wander together.  A real sensor's axes often drift together (one supply,
reference or temperature drives all channels: on the ADIS16405 record, 5 s deviations of
the three axes from their local level correlate by 0.35-0.69).  Such a wander moves the
residual of a pose whose gravity points along the shared direction more than that of a
pose across it, which the independent-axes kernel ``∇_i · ∇_j`` cannot express.  Of a
general ``C`` (six parameters) the ~25 contrasts of a session support one: the wander is
modelled as an independent part plus a common-mode part shared by the three axes,
``C_φ = (1 − φ) I + φ 11ᵀ`` (correlation ``φ`` between any two axes, ``0 ≤ φ ≤ 1``, the
same sign on the three sensor axes), so the pair factor is ``(1 − φ) ∇_i · ∇_j + φ (Σ_a
∇_ia)(Σ_b ∇_jb)`` (:func:`axis_gram`).  ``φ = 0`` is the independent-axes model.
``φ`` is estimated by REML with ``(s, q, τ)`` on the grid :data:`COMMON_GRID` (each
``(φ, τ)`` kernel diagonalised once, as one stack: :func:`fit_common`), once per round under
the current model; the round's tests, MDEs and LOPO then stand at ``φ̂``.  Per-axis
sizes that differ, or correlations of other signs or strengths between different pairs
of axes, are approximated by the nearest member.

A per-placement offset.  A sensor placed by hand, or on a fixture that is not quite
repeatable, can carry an offset that is constant while it rests and independent from
one placement to the next (contact stress, a strain the mount relaxes, a board that
settles differently each time): the rests' own samples cannot see it (it is constant
within each), and a smooth effect of the orientation cannot express it.  It is the first
member of the grid of ``τ`` (``τ = 0``, :data:`PLACEMENT`): ``β̄_ik`` independent between
poses, of size ``σ_w`` per axis, ``D_ij = 2 σ_w²`` for ``i ≠ j``, so ``Cov = σ_w²
(∇_iᵀ C_φ ∇_i) δ_ij`` up to the terms the bias absorbs.  It differs from a white scale in
that it does not follow each pose's own noise (a pose with a long, quiet rest carries the
same offset as a short, noisy one), and from a deterministic effect of the orientation
only through repeated placements of one orientation (pure-error degrees of freedom:
:mod:`accelcal.discrepancy.wander_model`).

``s`` absorbs a white excess (pose-to-pose disturbances, noise faster than the poses that
the standard errors miss); small ``τ`` (below the pose durations) makes the wander extra
white noise too (``Var ≈ 2 σ_w² τ / T_i``); ``τ`` of the order of the spacing of the poses
is a per-pose (nugget-like) excess; long ``τ`` a slow wander shared by neighbouring
poses.  At ``σ_w = 0`` the model is the ``white`` null's (a common scale).

Linear model.  The test statistics use the model linearised at the current weighted
least-squares fit ``p₀`` (:func:`accelcal.discrepancy.fit.fit`): ``r(p) ≈ r₀ + J (p − p₀)``.
The neglected terms are of the order of (noise / g)² relative (≈ 1e-8 for a MEMS pose
mean), far below anything the tests resolve.  Whitened by ``σ`` and projected on the
``n − 3`` orthonormal contrasts ``L`` orthogonal to the three bias columns (which removes
the bias and, with it, the ambiguity of the generalised covariance), the data are
``y = Lᵀ r₀/σ ~ N(−X β, s (I + q K_τ))`` with ``X`` the other columns (six scale and
misalignment parameters, the named effects, the candidate) and ``q`` the wander
variance relative to the white one, the whole times the white scale ``s``.  ``K_τ`` is
diagonalised once per ``τ`` of a grid
(the per-placement offset, five per decade from a tenth of the shortest pose to ten
session lengths, then the random walk; each member of the grid, its code and its kernel,
is one entry of :data:`MEMBERS`, :mod:`.members`); each model's columns are projected out once per ``τ`` (:class:`Basis`: the
contrasts the model leaves free, in which its GLS residual projector is diagonal), so
every likelihood on the grid costs ``O(n)``.

Estimation (REML).  The noise ``(s, q, τ)`` is estimated jointly with the calibration by
restricted maximum likelihood: ``−2ℓ_R = log|Σ| + log|XᵀΣ⁻¹X| + yᵀ P y``, ``s``
profiled analytically (``ŝ = yᵀPy/(m − p)`` at ``Σ = s (I + q K_τ)``).  Confidence
intervals are profile-likelihood intervals: the range of a quantity over the set where
``−2ℓ_R`` is within ``χ²₁(0.95) = 3.84`` of its minimum; the estimate and the intervals
are taken on a fine grid (ten values per decade of ``τ`` and of ``q``: a resolution of
±12 %, well inside any interval the poses give).  Intervals that reach the ends of the
grid are reported open (the data cannot bound them); a wander the contrasts cannot see
is reported as not estimated with the reason, never replaced by white noise silently.

Tests (likelihood ratio, parametric bootstrap).  Current model vs current + effect: the
likelihood ratio ``LR = −2 (ℓ₀ − ℓ₁)`` of the maximum likelihoods over the parameters
*and* the noise, each model re-estimating ``(s, q, τ)`` (``s`` analytically, ``(q, τ)`` on
the same grid).  Its null distribution is not χ²₃: maximum likelihood underestimates a
variance by the share of the fixed effects, more so for the larger model, and the wander
trades off against slow effects, so ``LR`` is stretched (by 1.2–1.6 for most effects and
up to 3 for ``bias_drift`` under a random-walk-like wander: ``bartlett`` in the output).
The p-value comes from ``n_boot`` data sets simulated under the fitted null (the current
model with its REML noise) and refitted with both models exactly as the data:
``p = (1 + #{LR* ≥ LR})/(n_boot + 1)``, or, for a test that reaches ``h`` exceedances
first, Besag & Clifford's (1991) sequential ``p = h/ℓ`` after ``ℓ`` replicates (``h`` is
chosen so that such a test could not pass at level α with every replicate: it only saves
the replicates of clearly insignificant tests).  Because ``LR`` is invariant to the fixed effects
of the null and to the scale ``s``, the bootstrap needs only ``(q, τ)``; and since ``LR``
is asymptotically pivotal (χ²₃ whatever the noise parameters), the bootstrap p-value is
second-order accurate (a scale-only, Bartlett-type correction was tried and rejected: on
sessions with three Gauss–Markov components it gave 8 % false positives at α = 5 %).
The bootstrap draws under ``φ̂`` and refits ``(s, q, τ)`` in each
replicate, not ``φ``: the statistic is the likelihood ratio at the round's ``φ̂`` (a plug-in:
the estimation error of ``φ̂`` is not propagated; re-estimating it per replicate would need
every candidate's :class:`Basis` for every ``φ``, five times the cost; the benchmark
measures what holding it costs).  Its
guarantee: effect-free recordings whose noise is of this family get an effect named
with probability ≤ α (up to the Monte Carlo error of a finite ``n_boot`` and of ``φ̂``),
however large the wander.  A wander outside the family (several Gauss–Markov components,
flicker) is approximated by the nearest member; the tests check the false-positive rate
on such sessions.

Outliers (:mod:`.outliers`).  Pose ``i`` is an outlier when its residual is shifted: the
mean-shift model adds a free shift to that pose alone (equivalent to leaving it out).
The family of the ``n`` poses is tested with the largest internally studentised GLS
residual ``max_i |t_i|``, ``t_i = (P r)_i / sqrt(P_ii ŝ)`` at the round's fitted wander
(``P`` the GLS residual projector), against its exact null: a function of the projector
alone (the multiplicity and the correlation the wander implies between the poses), drawn
by Monte Carlo until the decision is resolved (up to 40 000 draws; a bootstrap of 199
replicates resolved nothing below 0.005).  The mean-shift likelihood ratio with the wander
re-estimated under both models (``(P r)_i² / P_ii`` minimised over the grid, a rank-one
update of the GLS fit) ranks the chosen pose against the candidate effects (ΔBIC).

Leave-one-pose-out.  ``(P r)_i / P_ii`` is the error of predicting pose ``i`` from the
others under the GLS model, including the wander's conditional mean given the
neighbouring poses (kriging); its RMS in units of ``σ`` is the wander LOPO gap.

Assumptions.  Gaussian errors; the per-pose standard errors of the rests are right for
the short-term noise up to the common factor ``0.5 ≤ s ≤ 4``; one wander process (or per-placement offset), of the
same size on the three axes (data unit), equicorrelated between the axes by ``φ ≥ 0`` (a
common-mode share), of the Gauss–Markov / random-walk family (a sum of components or a
flicker floor is approximated by its nearest member: the tests measure what that
costs); the poses' gradients at the linearisation point.  The per-pose standard errors
are computed from the pose's own samples, so noise with a correlation time near the pose
durations is partly counted in both (it then shows as a smaller ``σ_w`` or ``s``); the
interval-mean covariance is exact for the wander as modelled.

Modules: :mod:`.problem` (the noise model's kernels and the linearised problem),
:mod:`.gls` (likelihood over the grid, GLS projector, information; the grid minima of many
data sets compiled in :mod:`._grid_kernels`), :mod:`.reml` (the
fitted wander), :mod:`.bootstrap` (the round's tests), :mod:`.simulation` (exact draws
of interval means, the covariance a simulation implies).
"""

from .bootstrap import BATCHES, RoundTests, round_tests, stop_count
from .outliers import directions, max_null_pvalue, studentised_max
from .gls import (
    MAX_WHITE_SCALE,
    MIN_WHITE_SCALE,
    Q_REL_GRID,
    Basis,
    EffectInformation,
    Surface,
    basis,
    effect_information,
    excess_distribution,
    gls_projector,
    gls_step,
    profile,
    studentised,
)
from .members import FLICKER, MEMBERS, PLACEMENT, GridMember, member_of, members_in, register_member, unregister_member
from .problem import (
    MIN_WANDER_DOF,
    POINT_DURATION,
    TAU_PER_DECADE,
    TAU_PER_DECADE_FINE,
    Problem,
    WanderError,
    axis_gram,
    axis_weight,
    gm_variance,
    is_timed,
    problem,
    tau_grid,
    wander_kernel,
    wander_kernels,
)
from .reml import CHI2_95, COMMON_GRID, Q_REL_FINE, S_FACTORS, WanderFit, at, fit_common, fit_wander
from .rests import RestAllan, rest_allan
from .simulation import contrast_covariance, simulate_interval_means

__all__ = ["BATCHES", "Basis", "CHI2_95", "COMMON_GRID", "EffectInformation", "FLICKER", "MAX_WHITE_SCALE",
           "GridMember", "MEMBERS", "MIN_WANDER_DOF", "RestAllan", "is_timed", "member_of", "members_in", "register_member",
           "rest_allan", "unregister_member",
           "MIN_WHITE_SCALE", "PLACEMENT", "POINT_DURATION", "Problem", "Q_REL_FINE", "Q_REL_GRID", "RoundTests",
           "S_FACTORS", "Surface", "TAU_PER_DECADE", "TAU_PER_DECADE_FINE", "WanderError", "WanderFit", "at",
           "axis_gram", "axis_weight", "basis", "contrast_covariance", "directions", "effect_information",
           "excess_distribution", "fit_common", "fit_wander", "gls_projector", "gls_step", "gm_variance",
           "max_null_pvalue", "problem", "profile", "round_tests", "simulate_interval_means", "stop_count",
           "studentised", "studentised_max", "tau_grid", "wander_kernel", "wander_kernels"]
