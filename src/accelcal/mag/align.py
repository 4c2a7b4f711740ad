"""The magnetometer's axes aligned to the accelerometer's, and the dip angle (Kok & Schön
2016; Papafotis & Sotiriadis, MAG.I.C.AL., 2019).

At rest the accelerometer measures the specific force ``f`` (up) and the calibrated
magnetometer the unit field ``h``, both in their own axes.  One field seen in every
orientation has one angle to the vertical: ``f̂ᵀ R ĥ = -sin(dip)`` for every rest, with
``R`` the rotation from the magnetometer's axes to the accelerometer's.  The linear
solution of ``f̂ᵢᵀ X ĥᵢ = 1`` gives ``X = R / c`` (Papafotis' first step) when the rests
visit enough orientations; a Gauss–Newton on ``(R, dip)`` refines it (and is the only
solution when fewer than nine distinct orientations leave ``X`` underdetermined: then it
starts from the nearest rotation to the minimum-norm ``X`` and from the identity, the
lower cost winning).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import MagDegenerateError
from .model import rotvec_to_matrix

#: Fewest rests (or accelerometer samples near g): rotation (3) and dip (1), and one more.
MIN_DIRECTIONS = 5
#: Singular values of the alignment below this share of the largest leave a parameter undetermined.
DEGENERATE_RATIO = 1e-3


@dataclass(frozen=True)
class Alignment:
    """Rotation ``R`` (magnetometer -> accelerometer axes) and dip, with their standard errors.

    ``se_rotation`` are the standard errors [rad] of a small rotation about the accelerometer's
    x, y, z applied after ``R``; ``dips`` the dip [deg] of each rest after alignment;
    ``undetermined`` names the directions the rests do not determine (empty when all are).
    """

    R: np.ndarray
    dip_deg: float
    se_dip_deg: float
    se_rotation: np.ndarray
    dips: np.ndarray
    n: int
    residual_rms: float
    undetermined: tuple[str, ...] = ()

    @property
    def angle_deg(self) -> float:
        """The angle of the rotation between the two sensors' axes."""
        return float(np.degrees(np.arccos(np.clip((np.trace(self.R) - 1) / 2, -1, 1))))


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=1)[:, None]


def _polar(X) -> tuple[np.ndarray, float]:
    """Nearest rotation to ``X = R / c`` and the sign of ``c``."""
    sgn = 1.0 if np.linalg.det(X) >= 0 else -1.0
    U, _, Vt = np.linalg.svd(sgn * X)
    D = np.diag([1, 1, np.sign(np.linalg.det(U @ Vt))])
    return U @ D @ Vt, sgn


def _residual(p, f, h, R0):
    R = rotvec_to_matrix(p[:3]) @ R0
    return np.einsum("ij,jk,ik->i", f, R, h) + np.sin(p[3])


def _jacobian(p, f, h, R0):
    R = rotvec_to_matrix(p[:3]) @ R0
    Rh = h @ R.T
    J = np.empty((len(f), 4))
    J[:, :3] = np.cross(Rh, f)  # d/dw of fᵀ(I + [w]x)Rh = fᵀ (w x Rh) = w · (Rh x f)
    J[:, 3] = np.cos(p[3])
    return J


def _refine(f, h, R0, dip0):
    p0 = np.array([0.0, 0.0, 0.0, dip0])
    from scipy.optimize import least_squares  # here: scipy.optimize costs 0.2-0.6 s to import

    s = least_squares(_residual, p0, jac=_jacobian, args=(f, h, R0), method="lm", xtol=1e-14, ftol=1e-14)
    return rotvec_to_matrix(s.x[:3]) @ R0, float(s.x[3]), float(s.cost)


def align(f, h, *, dip_noise_deg: float | None = None) -> Alignment:
    """Rotation and dip from specific forces ``f`` (n, 3) and calibrated fields ``h`` (n, 3)
    of the same instants (rests, or samples whose |f| is close to g).

    Standard errors from the residual's own scatter (what the rests show, model errors
    included), or from ``dip_noise_deg`` (the noise of one residual, when it is known and
    larger)."""
    f, h = _unit(f), _unit(h)
    n = len(f)
    if n < MIN_DIRECTIONS:
        raise MagDegenerateError(f"{n} rests with the magnetometer; aligning it to the accelerometer needs at "
                                 f"least {MIN_DIRECTIONS} (more orientations, or --no-mag-align)")
    starts = [np.eye(3)]
    K = np.einsum("ij,ik->ijk", f, h).reshape(n, 9)
    x, *_ = np.linalg.lstsq(K, np.ones(n), rcond=None)
    X = x.reshape(3, 3)
    if np.all(np.isfinite(X)) and np.linalg.norm(X) > 0:
        starts.insert(0, _polar(X)[0])
    best = None
    for R0 in starts:
        c0 = float(np.mean(np.einsum("ij,jk,ik->i", f, R0, h)))
        R, dip, cost = _refine(f, h, R0, float(np.arcsin(np.clip(-c0, -1, 1))))
        if best is None or cost < best[2] - 1e-15:
            best = (R, dip, cost)
    R, dip, _ = best
    p = np.array([0, 0, 0, dip])
    r = _residual(p, f, h, R)
    J = _jacobian(p, f, h, R)
    sv = np.linalg.svd(J, compute_uv=False)
    undetermined = _undetermined(J, sv)
    dof = max(n - 4, 1)
    s2 = float(r @ r) / dof
    if dip_noise_deg is not None:
        s2 = max(s2, np.radians(dip_noise_deg) ** 2 * np.cos(dip) ** 2)
    cov = np.linalg.pinv(J.T @ J) * s2
    dips = np.degrees(np.arcsin(np.clip(-np.einsum("ij,jk,ik->i", f, R, h), -1, 1)))
    return Alignment(R=R, dip_deg=float(np.degrees(dip)), se_dip_deg=float(np.degrees(np.sqrt(cov[3, 3]))),
                     se_rotation=np.sqrt(np.diag(cov)[:3]), dips=dips, n=n,
                     residual_rms=float(np.degrees(np.sqrt(np.mean(r**2)))), undetermined=undetermined)


def _undetermined(J, sv) -> tuple[str, ...]:
    """The parameter combinations whose singular value is below :data:`DEGENERATE_RATIO` of the largest."""
    _, s, Vt = np.linalg.svd(J, full_matrices=False)
    names = ("rotation about x", "rotation about y", "rotation about z", "dip")
    out = []
    for k in np.nonzero(s < DEGENERATE_RATIO * s[0])[0]:
        v = Vt[k]
        out.append(" + ".join(f"{v[i]:+.2f} {names[i]}" for i in np.argsort(-np.abs(v))[:2] if abs(v[i]) > 0.1))
    return tuple(out)


def dip_angles(f, m) -> np.ndarray:
    """Dip [deg] between each specific force ``f`` (up) and field ``m``: positive when the
    field points below the horizon (northern hemisphere)."""
    f, m = _unit(f), _unit(m)
    return np.degrees(np.arcsin(np.clip(-np.sum(f * m, axis=1), -1, 1)))


def heading_deg(f, m) -> np.ndarray:
    """Magnetic heading [deg] of the accelerometer's x axis from the specific force ``f`` and
    field ``m`` in the same axes (tilt-compensated: the field's horizontal part)."""
    up = _unit(f)
    east = _unit(np.cross(m, up))  # the field's vertical part drops out: (north + down) x up = east
    north = np.cross(up, east)
    x = np.array([1.0, 0.0, 0.0])
    return np.degrees(np.arctan2(east @ x, north @ x)) % 360


__all__ = ["Alignment", "MIN_DIRECTIONS", "align", "dip_angles", "heading_deg"]
