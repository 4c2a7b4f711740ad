"""Simulation under a noise model of the pose means: exact draws and the implied contrast covariance."""

from __future__ import annotations

import numpy as np

from ..stochastic.implication import pose_difference_variance
from .problem import Problem


def contrast_covariance(prob: Problem, terms: dict) -> np.ndarray:
    """Contrast covariance ``I + K`` of the white per-pose noise plus a noise model ``terms``
    (as :func:`simulate_interval_means` takes it, several components allowed) projected
    like the wander: the truth of a simulation, for its MDE."""
    S = np.eye(prob.m)
    for k, v in terms.items():
        for vi in (v if isinstance(v, list) else [v]):
            D = pose_difference_variance(k, vi, prob.starts, prob.durations)
            K = -0.5 * (prob.grad @ prob.grad.T) * D / prob.sigma[:, None] / prob.sigma[None, :]
            S = S + prob.L.T @ K @ prob.L
    return S



def simulate_interval_means(rng: np.random.Generator, terms: dict, starts, durations, size: int = 3,
                            axis_corr=None) -> np.ndarray:
    """Exact Gaussian draws of the interval means of a noise model on ``size`` axes.

    Parameters
    ----------
    terms : dict
        Noise model ``{term: coefficient}`` as :func:`accelcal.noise.model_avar`
        takes it (two-parameter terms: ``(coefficient, shape)``); for several components of
        one term pass a list of values, e.g. ``{"gauss_markov": [(s1, 3.0), (s2, 30.0)]}``.
    starts, durations : array_like (n,)
    size : int
        Axes.
    axis_corr : array_like (size, size), optional
        Correlation of the process between the axes (default: independent axes); each
        axis keeps the variance of ``terms``.

    Returns
    -------
    ndarray (n, size)
        Interval means up to a common constant per axis (what a model with a bias sees):
        drawn from ``−D/2 + c 11ᵀ`` with ``D`` the exact variogram of the interval means
        and ``c`` large enough to make it positive definite.
    """
    starts, durations = np.asarray(starts, float), np.asarray(durations, float)
    D = np.zeros((starts.size, starts.size))
    for k, v in terms.items():
        for vi in (v if isinstance(v, list) else [v]):
            D = D + pose_difference_variance(k, vi, starts, durations)
    n = starts.size
    c = float(np.max(D)) * n + 1e-300
    Cv = -0.5 * D + c
    ev, vec = np.linalg.eigh(0.5 * (Cv + Cv.T))
    root = vec * np.sqrt(np.clip(ev, 0.0, None))
    z = rng.standard_normal((n, size))
    if axis_corr is not None:
        z = z @ np.linalg.cholesky(np.asarray(axis_corr, float)).T
    return root @ z


__all__ = ["contrast_covariance", "simulate_interval_means"]
