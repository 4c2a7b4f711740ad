"""The data every model of one recording is fitted to: the static pose means and their noise.

A :class:`PoseData` holds the pose means ``z_i`` (data unit), the pose times and
temperatures (centred: ``Δt_i``, ``ΔT_i``) and the noise-predicted standard deviation
``σ_i`` of each pose residual, ``σ_i² = Σ_k (∂r_i/∂z_ik)² se_ik²`` from the per-pose
standard errors ``se_ik`` of the static detection (which account for correlated
samples; :func:`accelcal.evaluation.residual_sigma`).  ``σ_i`` is computed once,
at the closed-form (full LLS) fit, and then held fixed, so that every model of a
recording is fitted to, and compared on, the same weighted data.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..effects import COVARIATES, TEMPERATURE, TIME
from ..errors import AccelcalError
from ..evaluation import residual_sigma
from ..extended_model import EffectTerms, effect_terms
from ..lls import full_lls
from .wander.rests import RestAllan, rest_allan


@dataclass(frozen=True)
class PoseData:
    """What every model of one recording is fitted to (rows in time order).

    Attributes
    ----------
    z : ndarray, shape (n, 3)
        Pose means, data unit.
    g : float
        Gravity magnitude (the unit the residuals are in).
    sigma : ndarray, shape (n,)
        Noise-predicted standard deviation of each pose residual (unit of g), fixed.
    t : ndarray, shape (n,)
        Mid time of each pose [s].
    temp : ndarray, shape (n,), or None
        Mean temperature of each pose [°C], if the recording has one.
    mean_std : ndarray, shape (n, 3)
        Per-pose standard errors of the means (data unit), from the static detection.
    t_ref, temp_ref : float
        Centres of the covariates (the means over the full pose set; a subset keeps them).
    t_start, t_end : ndarray, shape (n,), or None
        First and last sample time of each pose [s] (the interval its mean averages over:
        the wander null needs them for the covariance of interval means).  None: unknown.
    index : ndarray of int, shape (n,), or None
        Index of each pose in the recording's full pose set (a subset keeps it); None = ``0..n-1``.
    rests : RestAllan or None
        The rests' pooled Allan variances (:mod:`.wander.rests`: what the wander null borrows
        from the rests' own samples); None when the samples were not given.  A subset keeps
        it (the noise is the recording's).
    """

    z: np.ndarray
    g: float
    sigma: np.ndarray
    t: np.ndarray
    temp: np.ndarray | None
    mean_std: np.ndarray
    t_ref: float
    temp_ref: float
    t_start: np.ndarray | None = None
    t_end: np.ndarray | None = None
    index: np.ndarray | None = None
    rests: RestAllan | None = None
    _terms: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __len__(self) -> int:
        return len(self.z)

    def effect_terms(self, effects) -> EffectTerms:
        """The effects on these poses (:func:`accelcal.extended_model.effect_terms`), kept:
        a recording's loop evaluates the same models hundreds of times.

        Raises
        ------
        AccelcalError
            An effect needs a covariate the recording lacks.
        """
        key = tuple(effects)
        terms = self._terms.get(key)
        if terms is None:
            terms = self._terms[key] = effect_terms(key, {name: self.covariate(name) for name in COVARIATES}, len(self))
        return terms

    def covariate(self, name: str | None) -> np.ndarray | None:
        """The centred covariate ``Δt`` or ``ΔT`` (None if the recording has no such column)."""
        if name == TIME:
            return self.t - self.t_ref
        if name == TEMPERATURE:
            return None if self.temp is None else self.temp - self.temp_ref
        return None

    @property
    def pose_index(self) -> np.ndarray:
        """Index of each pose in the full pose set."""
        return np.arange(len(self.z)) if self.index is None else self.index

    @property
    def has_intervals(self) -> bool:
        return self.t_start is not None and self.t_end is not None

    def subset(self, keep) -> PoseData:
        """The poses ``keep`` (boolean mask or indices), covariates centred as in the full set."""
        def sel(a):
            return None if a is None else a[keep]

        return PoseData(self.z[keep], self.g, self.sigma[keep], self.t[keep], sel(self.temp), self.mean_std[keep],
                        self.t_ref, self.temp_ref, sel(self.t_start), sel(self.t_end), self.pose_index[keep],
                        self.rests)


def pose_data(z, g: float, mean_std, t, temp=None, sigma=None, t_start=None, t_end=None) -> PoseData:
    """Build :class:`PoseData`; ``sigma`` defaults to the noise prediction at the full LLS fit.

    ``t_start``, ``t_end`` (optional, both or neither): the interval each pose mean
    averages over [s], ``t_start <= t <= t_end``, intervals in time order and disjoint.

    Raises
    ------
    AccelcalError
        Shapes that do not match, or the full LLS failing on the poses (too few or
        degenerate poses: the same one-line errors as ``accelcal calibrate``).
    """
    z = np.asarray(z, float)
    mean_std = np.asarray(mean_std, float)
    t = np.asarray(t, float)
    if z.ndim != 2 or z.shape[1] != 3 or mean_std.shape != z.shape or t.shape != (len(z),):
        raise AccelcalError(f"pose data of inconsistent shapes: z {z.shape}, mean_std {mean_std.shape}, t {t.shape}")
    if temp is not None:
        temp = np.asarray(temp, float)
        if temp.shape != t.shape:
            raise AccelcalError(f"pose temperatures of shape {temp.shape}, expected {t.shape}")
    if sigma is None:
        base = full_lls(z, g)
        sigma = residual_sigma(z, mean_std, base.M, base.bias)
    sigma = np.asarray(sigma, float)
    if not np.all(np.isfinite(sigma)) or np.any(sigma <= 0):
        raise AccelcalError("a pose has zero or non-finite noise: its standard error cannot weight it")
    if (t_start is None) != (t_end is None):
        raise AccelcalError("give both t_start and t_end of the poses, or neither")
    if t_start is not None:
        t_start, t_end = np.asarray(t_start, float), np.asarray(t_end, float)
        if t_start.shape != t.shape or t_end.shape != t.shape:
            raise AccelcalError(f"pose intervals of shapes {t_start.shape}, {t_end.shape}, expected {t.shape}")
        if not (np.all(np.isfinite(t_start)) and np.all(np.isfinite(t_end))) or np.any(t_end < t_start) \
                or np.any(t_start[1:] < t_end[:-1]):
            raise AccelcalError("pose intervals must be finite, in time order and disjoint (t_start <= t_end)")
    return PoseData(z, float(g), sigma, t, temp, mean_std, float(t.mean()),
                    float(temp.mean()) if temp is not None else float("nan"), t_start, t_end, None)


def pose_data_from_static(poses, g: float, samples=None, fs: float | None = None) -> PoseData:
    """:class:`PoseData` of the poses found by :func:`accelcal.static.detect_static`; with
    the recording's ``samples`` (n, 3) [data unit] at ``fs`` [Hz], also the rests' Allan
    variances (:func:`~.wander.rests.rest_allan` over the poses' sample intervals)."""
    data = pose_data(poses.means, g, poses.mean_std, poses.t_mid, poses.temp, t_start=poses.t_start,
                     t_end=poses.t_end)
    if samples is None or fs is None:
        return data
    return replace(data, rests=rest_allan(samples, poses.intervals, fs))


__all__ = ["PoseData", "pose_data", "pose_data_from_static"]
