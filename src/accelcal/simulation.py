"""Simulation of static accelerometer poses (Burkhard et al. 2024, Sec. 2).

Pose designs are unit gravity directions in the sensor frame; the true specific
force of a pose is ``x = g u``.  Designs:

* ``random_directions``: uniform on the sphere (the project's default for the
  Burkhard grids; the paper does not state its pose distribution).
* ``classic_directions(6)``: the six faces, each axis up and down.
* ``classic_directions(12)``: the 12 edge directions of a cube (cuboctahedron).
* ``classic_directions(24)``: the 24 vertices of a rhombicuboctahedron, i.e. all
  permutations and signs of ``(1, 1, 1 + sqrt 2)``: a symmetric 24-pose design that
  sees every axis at many angles.
"""

from __future__ import annotations

from itertools import permutations, product

import numpy as np

from .errors import InputShapeError
from .model import apply_model, m_from_params

#: Simulation settings of Burkhard et al. (2024), Sec. 2 (ADIS-16475 data sheet).
MG = 9.80665e-3  # 1 mg in m/s²


def random_directions(rng: np.random.Generator, n: int, trials: int | None = None) -> np.ndarray:
    """Directions uniform on the unit sphere, shape ``(n, 3)`` or ``(trials, n, 3)``."""
    shape = (n, 3) if trials is None else (trials, n, 3)
    v = rng.standard_normal(shape)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def classic_directions(n: int) -> np.ndarray:
    """The classic 6-, 12- or 24-position designs as unit vectors, shape ``(n, 3)``."""
    if n == 6:
        pts = [tuple(s * e) for e in np.eye(3) for s in (1.0, -1.0)]
    elif n == 12:
        pts = {p for base in permutations((1.0, 1.0, 0.0)) for p in _signed(base)}
    elif n == 24:
        c = 1.0 + np.sqrt(2.0)
        pts = {p for base in permutations((1.0, 1.0, c)) for p in _signed(base)}
    else:
        raise InputShapeError(f"classic designs have 6, 12 or 24 positions, not {n}")
    pts = np.array(sorted(pts, reverse=True), dtype=float)
    return pts / np.linalg.norm(pts, axis=1, keepdims=True)


def _signed(base):
    for signs in product((1.0, -1.0), repeat=3):
        yield tuple(float(s * b) if b != 0 else 0.0 for s, b in zip(signs, base))


def sample_truth(rng: np.random.Generator, trials: int, bias_range_mg=(0.9, 1.3),
                 scale_range_ppm=(300.0, 600.0), nonorth_range_deg=(0.02, 0.04),
                 identity_m: bool = False) -> dict[str, np.ndarray]:
    """Draw true errors uniformly as in Burkhard et al. (2024), Sec. 2.

    Magnitudes are drawn uniformly in the ranges; the sign of each bias component
    and scale factor is drawn at random (the paper gives magnitudes only).

    Returns
    -------
    dict with ``bias`` (trials, 3) [m/s²], ``scale_factors`` (trials, 3),
    ``nonorthogonality`` (trials, 3) [rad], ``M`` (trials, 3, 3).
    """
    def signed(lo, hi, size):
        return rng.uniform(lo, hi, size) * rng.choice((-1.0, 1.0), size)

    bias = signed(*bias_range_mg, (trials, 3)) * MG
    s = signed(*scale_range_ppm, (trials, 3)) * 1e-6
    th = np.deg2rad(signed(*nonorth_range_deg, (trials, 3)))
    if identity_m:
        s = np.zeros_like(s)
        th = np.zeros_like(th)
    return {"bias": bias, "scale_factors": s, "nonorthogonality": th, "M": m_from_params(s, th)}


def simulate_poses(directions, g: float, M, bias, noise_std, rng: np.random.Generator) -> np.ndarray:
    """Noisy static measurements ``z = M (g u) + b + e``, ``e ~ N(0, noise_std²)`` per axis.

    ``directions`` is ``(n, 3)`` or ``(trials, n, 3)``; ``M`` and ``bias`` broadcast over
    trials.  ``noise_std`` is a scalar or per-axis ``(3,)``.
    """
    u = np.asarray(directions, dtype=float)
    z = apply_model(g * u, M, bias)
    return z + rng.standard_normal(z.shape) * np.asarray(noise_std, dtype=float)


def simulate_recording(rng: np.random.Generator, directions, g: float, M, bias, noise_std: float,
                       rate: float = 100.0, rest_s: float = 4.0, move_s: float = 2.0,
                       init_rest_s: float = 30.0, temperature=None, draw_noise: bool = True) -> dict[str, np.ndarray]:
    """Raw time series of a multi-position session: rests at ``directions`` joined by motions.

    The sensor rests ``init_rest_s`` in the first pose, then ``rest_s`` in each following
    one; between rests the gravity direction rotates along the great circle in ``move_s``
    with a superimposed shake (so that a variance detector sees the motion), as a hand
    placing the sensor would.  Returns ``t``, ``acc`` (n, 3) and, if ``temperature`` is
    given as ``(start, end)`` °C, a linearly drifting ``temp`` column.

    ``draw_noise=False`` (only with ``noise_std == 0``): ``acc`` is the noise-free model and
    the last draw (``(n, 3)`` standard normals, all multiplied by zero) is left to the
    caller, who must make it before ``rng`` is used again to keep the stream; the
    benchmark owes it only when it draws again (a redrawn design, an outlier pose): the
    75,600 normals of its session are about 2 ms, ~3 % of a benchmark recording's CPU.
    """
    u = np.asarray(directions, dtype=float)
    n_move = int(round(move_s * rate))
    w = np.linspace(0, 1, n_move, endpoint=False)[:, None]
    # all motions at once: one draw of every shake (the same numbers, in the same order, as
    # one draw per motion) and the great circles of every pair of consecutive poses
    shake = 0.5 * g * np.sin(np.pi * w) * rng.standard_normal((max(len(u) - 1, 0), n_move, 3))
    moves = g * _slerp(u[:-1], u[1:], w) + shake
    chunks = []
    for i, ui in enumerate(u):
        n_rest = int(round((init_rest_s if i == 0 else rest_s) * rate))
        chunks.append(np.repeat(g * ui[None, :], n_rest, axis=0))
        if i + 1 < len(u):
            chunks.append(moves[i])
    x = np.concatenate(chunks)
    if draw_noise:
        acc = apply_model(x, M, bias) + noise_std * rng.standard_normal(x.shape)
    elif noise_std != 0:
        raise ValueError("draw_noise=False needs noise_std == 0")
    else:  # x + 0 * N(0, 1) is x (finite x; a -0.0 would come out +0.0): the draw is the caller's
        acc = apply_model(x, M, bias) + 0.0
    t = np.arange(len(x)) / rate
    out = {"t": t, "acc": acc}
    if temperature is not None:
        out["temp"] = np.linspace(temperature[0], temperature[1], len(t))
    return out


def _slerp(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Great-circle paths from unit vectors ``a`` to ``b`` (k, 3) at fractions ``w`` (m, 1):
    shape (k, m, 3).

    Antipodal ends have no unique great circle: the path then passes through a
    direction perpendicular to ``a``.
    """
    a = a / np.linalg.norm(a, axis=1, keepdims=True)
    b = b / np.linalg.norm(b, axis=1, keepdims=True)
    ab = np.sum(a * b, axis=1)
    angle = np.arccos(np.clip(ab, -1.0, 1.0))
    ref = np.where((np.abs(a[:, 0]) < 0.9)[:, None], [1.0, 0, 0], [0, 1.0, 0])
    perp = np.where((np.pi - angle < 1e-6)[:, None], np.cross(a, ref), b - ab[:, None] * a)
    with np.errstate(invalid="ignore", divide="ignore"):  # equal ends: perp = 0, path replaced below
        perp /= np.linalg.norm(perp, axis=1, keepdims=True)
    phi = angle[:, None, None] * w[None]
    path = np.cos(phi) * a[:, None, :] + np.sin(phi) * perp[:, None, :]
    same = angle < 1e-9
    path[same] = a[same][:, None, :]
    return path
