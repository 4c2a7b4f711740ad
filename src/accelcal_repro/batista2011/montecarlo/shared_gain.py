"""The Kalman filter of Sec. IV on many runs at once with one precomputed gain sequence
(:func:`shared_gain_filter`), fed block by block; compiled when the filter kernels are."""

from __future__ import annotations

import numpy as np

from accelcal.kernels import compiled
from accelcal.batista.filter import rotation_coefficients


def _mv(M: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Batched 3x3 matrix-vector product, layout ``M`` (3, 3, T), ``v`` (3, T)."""
    return (M * v[None]).sum(axis=1)


def shared_gain_filter(dt: float, a_m, omega_m, y, x0, gains, record, sub_block: int = 25) -> np.ndarray:
    """The Kalman filter of Sec. IV on many runs with a precomputed gain sequence.

    Each run propagates its state with its own gyro readings (exact ``Φ`` in closed
    form, first-order hold of ``a_m``, as :func:`accelcal.batista.filter.kalman_filter`)
    and updates with ``gains[k]`` (from :func:`~accelcal.batista.filter.covariance_sequence`).

    Parameters
    ----------
    dt : float
    a_m, omega_m, y : array_like, shape (T, n, 3)
    x0 : array_like, shape (T, 9)
    gains : array_like, shape (n, 9, 3)
    record : array_like of int
        Sample indices to return (sorted).
    sub_block : int
        Samples processed per vectorised chunk (small chunks stay in cache).

    Returns
    -------
    numpy.ndarray, shape (T, len(record), 9)
    """
    a_m, omega_m, y = (np.asarray(v, float) for v in (a_m, omega_m, y))
    st = _FilterState(np.asarray(x0, float), a_m[:, 0], omega_m[:, 0], np.asarray(record), dt)
    gains = np.asarray(gains, float)
    for k0 in range(1, a_m.shape[1], sub_block):
        sl = slice(k0, k0 + sub_block)
        st.run_block(a_m[:, sl], omega_m[:, sl], y[:, sl], gains, k0)
    return st.out


def _blocks_bkt(w: np.ndarray, dt: float):
    """:func:`~accelcal.batista.filter.rotation_blocks` (``J1`` divided by ``dt``) for
    ``w`` of layout (B, 3, T), returned in layout (B, 3, 3, T), by elementwise arithmetic
    (``S(w)² = w wᵀ - |w|² I``), which is much faster than batched 3x3 products."""
    w = w * dt
    th2 = np.einsum("bit,bit->bt", w, w)
    a, b, c, d, e = rotation_coefficients(np.sqrt(th2))
    K = np.zeros(w.shape[:1] + (3, 3) + w.shape[2:])
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -w[:, 2], w[:, 1], -w[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = w[:, 2], -w[:, 1], w[:, 0]
    WW = w[:, :, None] * w[:, None, :]
    out = []
    for c0, c1, c2, scale in ((1.0, a, b, 1.0), (1.0, b, c, dt), (0.5, d, e, dt)):
        M = c2[:, None, None] * WW - c1[:, None, None] * K
        diag = c0 - c2 * th2
        for i in range(3):
            M[:, i, i] += diag
        out.append(M * scale if scale != 1.0 else M)
    return tuple(out)


def _compiled_block():
    """The compiled block loop when the filter kernels run compiled (:mod:`accelcal.kernels`), else None."""
    if compiled("batista._filter_kernels") is None:
        return None
    from .. import _shared_gain_kernels

    return _shared_gain_kernels


class _FilterState:
    """Running state of :func:`shared_gain_filter` fed block by block (memory stays bounded).

    With numba the block runs as the compiled kernel
    :func:`accelcal_repro.batista2011._shared_gain_kernels.shared_gain_block` (state ``x`` kept as (T, 9));
    the numpy loop below is the reference (state as (9, T))."""

    def __init__(self, x0, a0, w0, record, dt):
        self.kernels = _compiled_block()
        x0 = np.asarray(x0, float)
        self.x = np.array(x0) if self.kernels is not None else np.ascontiguousarray(x0.T)
        self.a_prev = np.array(a0, float)
        self.w_prev = np.array(w0, float)
        self.record = np.asarray(record, int)
        self.recorded = np.zeros(int(self.record.max(initial=-1)) + 1, bool)  # sample index -> recorded?
        self.recorded[self.record] = True
        self.dt = dt
        self.out = np.empty((len(x0), len(self.record), 9))
        self.j = 0
        self._store(0)

    def _store(self, k):
        while self.j < len(self.record) and self.record[self.j] == k:
            self.out[:, self.j] = self.x if self.kernels is not None else self.x.T
            self.j += 1

    def run_block(self, a, w, y, gains, k0):
        """Samples ``k0 .. k0 + B - 1``: ``a``, ``w``, ``y`` of shape (T, B, 3)."""
        if self.kernels is not None:
            B = a.shape[1]
            store = np.zeros(B, bool)
            part = self.recorded[k0:k0 + B]
            store[:len(part)] = part
            c = np.ascontiguousarray
            self.kernels.shared_gain_block(self.dt, self.x, self.a_prev, self.w_prev, c(a, dtype=float),
                                           c(w, dtype=float), c(y, dtype=float), c(gains[k0:k0 + B]), store,
                                           self.out, self.j)
            self.j += int(store.sum())
            return
        dt = self.dt
        wT = np.moveaxis(w, 0, -1)  # (B, 3, T)
        wbar = 0.5 * (np.concatenate([self.w_prev.T[None], wT[:-1]], axis=0) + wT)
        E, J0, J1 = _blocks_bkt(wbar, dt)  # (B, 3, 3, T)
        aT = np.ascontiguousarray(np.moveaxis(a, 0, -1))  # (B, 3, T)
        yT = np.ascontiguousarray(np.moveaxis(y, 0, -1))
        a0 = self.a_prev.T
        x = self.x
        for i in range(a.shape[1]):
            v, g, b = x[:3], x[3:6], x[6:]
            a1 = aT[i]
            # x⁻ = Φ x + G0 a_k + G1 a_{k+1}, with -J0 b + (J1/dt) a_k + (J0 - J1/dt) a_{k+1}
            v_new = _mv(E[i], v + dt * g) + _mv(J0[i], a1 - b) + _mv(J1[i], a0 - a1)
            g_new = _mv(E[i], g)
            innov = yT[i] - v_new
            x = np.concatenate([v_new, g_new, b]) + gains[k0 + i] @ innov
            a0 = a1
            self.x = x
            self._store(k0 + i)
        self.a_prev = a[:, -1]
        self.w_prev = w[:, -1]


__all__ = ["shared_gain_filter"]
