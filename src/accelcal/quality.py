"""Whether a calibration can be trusted: residuals against an independent noise prediction.

The residual of pose i, ``r_i = ||M⁻¹(z_i - b)|| - g``, is to first order the noise of
its mean projected on ``w_i = ∂r_i/∂z_i``.  That noise is measured *independently of the
fit*: each pose is a rest of hundreds of samples, whose own scatter (with its
autocorrelation) gives the standard error of its mean (:class:`accelcal.static.StaticPoses`
``mean_std``).  So the noise alone predicts ``σ_i² = Σ_k w_ik² se_ik²``
(:func:`accelcal.evaluation.residual_sigma`, as the discrepancy loop uses it), and

* ``χ² = Σ r_i²/σ_i²`` on ``dof = n - q`` degrees of freedom, with its upper-tail
  p-value, says whether the model and the noise explain the residuals;
* ``excess = sqrt(χ²/dof)`` says by what factor the residuals exceed the noise (1 when
  they are explained).  The residual-scaled "noise estimate" of earlier versions came
  from the same residuals and therefore always matched them.

Coverage.  The directions ``u_i = M⁻¹(z_i - b)/|·|`` of the poses in the sensor frame:
the number of *distinct orientations* (greedy clustering, 10° apart), the *coverage*
(fraction of the sphere within 30° of some pose: six faces give 0.40, a good hand-placed
session 0.8-1) and the *hemisphere bias* ``|mean u_i|`` (0 for a balanced set, 1 when
all poses point one way).

Warnings (:data:`RULES`; a clean fit has none), each a plain sentence for a
``warning:`` line, with a short code in ``flags`` (``few_dof``, ``excess``,
``few_orientations``, ``one_sided``) for tables:

* fewer degrees of freedom than parameters (``dof < q``): the residuals cannot check
  the fit (a 10-pose full fit has one);
* residuals far above the noise: ``excess > 1.5`` with ``p < 0.001``: the model misses an
  effect or the noise is not white: run ``accelcal discrepancy``;
* fewer distinct orientations than the estimator needs poses;
* poses bunched on one side (hemisphere bias > 0.6) or covering little of the sphere
  (coverage < 0.25): scale and non-orthogonality are extrapolated.

Standard errors.  :func:`assess` also gives the parameters' standard errors implied by
the independent noise, ``sqrt(diag((Jᵀ W J)⁻¹))`` with ``W = diag(1/σ_i²)``, scaled by
``max(1, excess)`` (the Particle Data Group's scale factor): they do not shrink when a
handful of residuals happens to be small, and they grow with a misfit.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .evaluation import chi2_test, noise_standard_errors, residual_sigma

#: Thresholds of the warnings (module docstring).
RULES = {"excess": 1.5, "p_value": 1e-3, "distinct_deg": 10.0, "coverage_deg": 30.0, "hemisphere": 0.6,
         "coverage": 0.25}
_FIBONACCI_POINTS = 4000


@dataclass(frozen=True)
class FitQuality:
    """Quality of one calibration fit (module docstring).

    Residual quantities are in the unit of g (m/s²).
    """

    noise_source: str
    n_poses: int
    n_parameters: int
    dof: int
    residual_rms: float
    predicted_rms: float
    excess: float
    chi2: float
    p_value: float
    distinct_orientations: int
    coverage: float
    hemisphere_bias: float
    warnings: tuple[str, ...]
    flags: tuple[str, ...] = ()

    @property
    def trustworthy(self) -> bool:
        """True when no warning was raised."""
        return not self.warnings

    def to_dict(self) -> dict:
        d = asdict(self)
        d["warnings"] = list(self.warnings)
        d["flags"] = list(self.flags)
        d["trustworthy"] = self.trustworthy
        d["rules"] = dict(RULES)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> FitQuality:
        keys = {f for f in cls.__dataclass_fields__}
        v = {k: d[k] for k in keys if k in d}
        v["warnings"] = tuple(v.get("warnings", ()))
        v["flags"] = tuple(v.get("flags", ()))
        for k in ("residual_rms", "predicted_rms", "excess", "chi2", "p_value", "coverage", "hemisphere_bias"):
            v[k] = float("nan") if v.get(k) is None else float(v[k])
        return cls(**v)


def directions(z, M, bias) -> np.ndarray:
    """Unit gravity directions of the poses in the sensor frame, ``M⁻¹(z_i - b)/|·|``."""
    x = np.linalg.solve(np.asarray(M, float), (np.asarray(z, float) - np.asarray(bias, float)).T).T
    return x / np.linalg.norm(x, axis=1, keepdims=True)


def distinct_orientations(u, min_angle_deg: float = RULES["distinct_deg"]) -> int:
    """Poses more than ``min_angle_deg`` apart from every earlier kept one (greedy, in order)."""
    kept = []
    c = np.cos(np.deg2rad(min_angle_deg))
    for v in np.asarray(u, float):
        if all(float(v @ w) < c for w in kept):
            kept.append(v)
    return len(kept)


def _fibonacci_sphere(n: int) -> np.ndarray:
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    r = np.sqrt(1 - z * z)
    phi = np.pi * (3 - np.sqrt(5)) * i
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def sphere_coverage(u, radius_deg: float = RULES["coverage_deg"]) -> float:
    """Fraction of the unit sphere within ``radius_deg`` of some pose direction."""
    grid = _fibonacci_sphere(_FIBONACCI_POINTS)
    near = (grid @ np.asarray(u, float).T).max(axis=1) >= np.cos(np.deg2rad(radius_deg))
    return float(near.mean())


def assess(z, mean_std, M, bias, residuals, n_parameters: int, model: str,
           min_poses: int | None = None) -> tuple[FitQuality, dict]:
    """Quality of a fit and the standard errors the independent pose noise implies.

    Parameters
    ----------
    z, mean_std : array_like, shape (n, 3)
        Pose means and the standard errors of their coordinates (the unit of the fit).
    M, bias : array_like
        The fitted model.
    residuals : array_like, shape (n,)
        ``||M⁻¹(z_i - b)|| - g`` (unit of g).
    n_parameters : int
        Unknowns of the model (9 full, 3 bias-only).
    model : {'full', 'bias'}
    min_poses : int, optional
        Poses the estimator needs (for the distinct-orientation warning); default q + 1.

    Returns
    -------
    quality : FitQuality
    standard_errors_noise : dict
        ``bias``, ``scale_factors``, ``nonorthogonality``, ``nonorthogonality_deg`` (full
        model) in the units of :meth:`accelcal.results.CalibrationResult.standard_errors`,
        scaled by ``max(1, excess)``.
    """

    z = np.asarray(z, float)
    r = np.asarray(residuals, float)
    sigma = residual_sigma(z, mean_std, M, bias)
    chi = chi2_test(r, sigma, n_parameters)
    excess = chi.excess if chi.dof > 0 else float("nan")
    u = directions(z, M, bias)
    distinct = distinct_orientations(u)
    cover = sphere_coverage(u)
    hemi = float(np.linalg.norm(u.mean(axis=0)))
    q = n_parameters
    need = q + 1 if min_poses is None else min_poses
    flags, warnings = _warnings(chi, excess, q, len(z), distinct, need, cover, hemi)
    nse = noise_standard_errors(z, mean_std, M, bias, model) * max(1.0, excess if np.isfinite(excess) else 1.0)
    se = {"bias": nse[:3]}
    if model == "full":
        se.update(scale_factors=nse[3:6], nonorthogonality=nse[6:9], nonorthogonality_deg=np.rad2deg(nse[6:9]))
    quality = FitQuality(noise_source="rests: standard error of each pose mean from its own samples "
                                      "(autocorrelation included)",
                         n_poses=len(z), n_parameters=q, dof=int(chi.dof), residual_rms=float(np.sqrt(np.mean(r * r))),
                         predicted_rms=float(np.sqrt(np.mean(sigma ** 2))), excess=float(excess),
                         chi2=float(chi.chi2), p_value=float(chi.p_value), distinct_orientations=int(distinct),
                         coverage=cover, hemisphere_bias=hemi, warnings=tuple(warnings), flags=tuple(flags))
    return quality, se


def _warnings(chi, excess: float, q: int, n_poses: int, distinct: int, need: int, cover: float,
              hemi: float) -> tuple[list, list]:
    """Flags and warnings of a fit: too few degrees of freedom, residuals beyond the noise, too
    few distinct orientations, poses on one side of the sphere."""
    warnings, flags = [], []
    if chi.dof < q:
        flags.append("few_dof")
        warnings.append(f"only {max(chi.dof, 0)} degree(s) of freedom ({n_poses} poses for {q} parameters): the "
                        "residuals cannot check the fit, and the ± rest on the pose noise alone; record at least "
                        f"{2 * q} poses in distinct orientations")
    if chi.dof > 0 and excess > RULES["excess"] and chi.p_value < RULES["p_value"]:
        flags.append("excess")
        warnings.append(f"pose residuals are {excess:.3g}x what the pose noise predicts (chi2/dof = "
                        f"{chi.reduced:.3g} on {chi.dof} dof, p = {chi.p_value:.2g}): the model misses an effect "
                        "(nonlinearity, drift, temperature, a disturbed pose) or the noise is not white; the ± "
                        "include this factor; run `accelcal discrepancy` on the recording")
    if distinct < need:
        flags.append("few_orientations")
        warnings.append(f"only {distinct} distinct orientations among {n_poses} poses (10 deg apart), fewer than the "
                        f"{need} this model needs: turn the sensor to new orientations between rests")
    if hemi > RULES["hemisphere"] or cover < RULES["coverage"]:
        flags.append("one_sided")
        warnings.append(f"the poses cover {100 * cover:.0f}% of the sphere (within 30 deg) and lean to one side "
                        f"(|mean direction| = {hemi:.2f}): scale and non-orthogonality are extrapolated; add poses "
                        "on the other side")
    return flags, warnings


__all__ = ["FitQuality", "RULES", "assess", "directions", "distinct_orientations", "sphere_coverage"]
