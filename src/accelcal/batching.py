"""Batched estimates from a single-problem estimator, trial by trial (the registry's
:meth:`~accelcal.registry.Estimator.fit_batch` for estimators without a batched form)."""

from __future__ import annotations

import numpy as np

from .errors import AccelcalError
from .registry import Estimator
from .results import BatchResult


def batch_of_single(est: Estimator, z, g: float, noise_std: float | None) -> BatchResult:
    """The batched form of an estimator that has none: the single-problem estimator on each
    trial, a trial it refuses NaN with ``valid=False`` and the name of its error in ``status``."""
    z = np.asarray(z, dtype=float)
    T = len(z)
    bias, M = np.full((T, 3), np.nan), np.full((T, 3, 3), np.nan)
    status = np.full(T, "ok", dtype=object)
    for t in range(T):
        try:
            r = est.fit(z[t], g, noise_std=noise_std)
        except AccelcalError as e:
            status[t] = type(e).__name__
            continue
        bias[t], M[t] = r.bias, r.M
    return BatchResult(method=est.name, bias=bias, M=M, valid=status == "ok", status=status.astype(str))
