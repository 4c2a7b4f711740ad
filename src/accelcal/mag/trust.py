"""What the magnetometer's samples say before and after a fit: bad columns, the noise at
the rests, disturbances, the sphere coverage, and the dip's consistency.

Coverage follows ArduPilot's ``CompassCalibrator::update_completion_mask``
(``libraries/AP_Compass/CompassCalibrator.cpp``): the corrected field's direction is
binned into the 80 sections of a geodesic grid (an icosahedron with each face cut in four,
``AP_GeodesicGrid``) and the share of sections visited is the coverage.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import MagDegenerateError, MagInputError

#: Share of samples pinned at one axis's extreme value above which the axis is saturated.
SATURATED_SHARE = 0.01
#: Coverage (share of the 80 sections) below which the fit is flagged, and below which it is refused.
COVERAGE_WARN, COVERAGE_REFUSE = 0.5, 0.1
#: The quietest windows are rests only when their variance is below this share of the whole session's.
QUIET_SHARE = 1e-2
#: A rest whose field moves by more than this many standard errors (and ``DISTURBANCE_REL`` of the field) is disturbed.
DISTURBANCE_Z, DISTURBANCE_REL = 6.0, 0.01


@dataclass(frozen=True)
class Prepared:
    """Magnetometer samples checked for use: ``keep`` masks the rows used, ``notes`` says why rows were dropped."""

    m: np.ndarray
    keep: np.ndarray
    notes: tuple[str, ...]


def prepare(m, source: str = "magnetometer") -> Prepared:
    """Refuse what no fit can use (one line each); drop leading all-zero rows with a note
    (the SNU files' first row: a magnetometer that had not reported yet)."""
    m = np.asarray(m, dtype=float)
    if m.ndim != 2 or m.shape[1] != 3:
        raise MagInputError(f"{source}: magnetometer data of shape {m.shape}, expected (n, 3)")
    finite = np.all(np.isfinite(m), axis=1)
    zero = np.all(m == 0, axis=1)
    keep = finite & ~zero
    notes = []
    if zero.any():
        lead = int(np.argmax(~zero)) if (~zero).any() else zero.size
        where = f"the first {lead} row(s)" if lead == zero.sum() else f"{int(zero.sum())} row(s)"
        notes.append(f"magnetometer: {where} all zero (no reading yet): dropped")
    if (~finite).any():
        notes.append(f"magnetometer: {int((~finite).sum())} row(s) not finite: dropped")
    mk = m[keep]
    if mk.shape[0] < 10:
        raise MagInputError(f"{source}: the magnetometer columns are zero or missing in all but {mk.shape[0]} rows "
                            "(no magnetometer on this device?): pass --no-mag")
    for i, ax in enumerate("xyz"):
        col = mk[:, i]
        if np.ptp(col) == 0:
            raise MagInputError(f"{source}: magnetometer {ax} is constant ({col[0]:g}) in every row: the sensor "
                                "did not report; fix the log or pass --no-mag")
        for extreme in (col.max(), col.min()):
            share = float(np.mean(col == extreme))
            if share > SATURATED_SHARE and _pinned(col, extreme):
                raise MagInputError(f"{source}: magnetometer {ax} sits at {extreme:g} in {100 * share:.1f} % of the "
                                    "samples (saturated: a magnet or the wrong range); record again away from it, "
                                    "or pass --no-mag")
    return Prepared(m=mk, keep=keep, notes=tuple(notes))


def _pinned(col, extreme) -> bool:
    """Pinned at a range limit: the extreme value repeats in runs (a clipped signal), not
    merely the most common value of a quantised one."""
    at = col == extreme
    runs = np.diff(np.flatnonzero(np.diff(np.concatenate([[0], at.astype(int), [0]]))))[::2]
    return runs.size > 0 and runs.max() >= 5


def rest_noise(m, intervals) -> tuple[np.ndarray | None, int, str]:
    """Pooled noise covariance of one sample [raw²] over the rests (each rest's own mean and
    linear drift removed), the samples it rests on, and where it came from."""
    resid = []
    for a, b in intervals:
        seg = m[a:b]
        if len(seg) < 5:
            continue
        t = np.arange(len(seg)) - (len(seg) - 1) / 2
        X = np.column_stack([np.ones_like(t), t])
        coef, *_ = np.linalg.lstsq(X, seg, rcond=None)
        resid.append(seg - X @ coef)
    if not resid:
        return None, 0, "no rest long enough"
    r = np.concatenate(resid)
    dof = max(len(r) - 2 * len(resid), 1)
    return r.T @ r / dof, len(r), f"{len(resid)} rests, {len(r)} samples"


def quiet_intervals(m, window: int = 50) -> list[tuple[int, int]]:
    """Stretches where the field does not move (a magnetometer without an accelerometer's
    rests): windows whose variance is within 3x the quietest 5 %."""
    n = len(m) // window
    if n < 3:
        return []
    v = np.array([m[i * window:(i + 1) * window].var(axis=0).sum() for i in range(n)])
    floor = np.percentile(v, 5)
    if floor > QUIET_SHARE * m.var(axis=0).sum():
        return []  # nothing rests: the noise is unknown (estimated from the fit's residual)
    return [(i * window, (i + 1) * window) for i in np.flatnonzero(v <= 3 * max(floor, 1e-300))]


def disturbed_rests(m, intervals, noise_cov, field_scale: float) -> list[int]:
    """Indices of rests whose field moves between their first and last third beyond the noise
    and :data:`DISTURBANCE_REL` of the field: a disturbance (a car passing, a door, a motor)."""
    out = []
    for k, (a, b) in enumerate(intervals):
        seg = m[a:b]
        n3 = len(seg) // 3
        if n3 < 3:
            continue
        d = seg[-n3:].mean(axis=0) - seg[:n3].mean(axis=0)
        se = np.sqrt(2 * np.diag(noise_cov) / n3) if noise_cov is not None else np.full(3, 0.0)
        z = np.max(np.abs(d) / np.maximum(se, 1e-300))
        if z > DISTURBANCE_Z and np.linalg.norm(d) > DISTURBANCE_REL * field_scale:
            out.append(k)
    return out


def _geodesic_centres() -> np.ndarray:
    """Centres of the 80 triangles of an icosahedron whose faces are cut in four."""
    p = (1 + 5 ** 0.5) / 2
    v = np.array([[-1, p, 0], [1, p, 0], [-1, -p, 0], [1, -p, 0], [0, -1, p], [0, 1, p], [0, -1, -p], [0, 1, -p],
                  [p, 0, -1], [p, 0, 1], [-p, 0, -1], [-p, 0, 1]], float)
    v /= np.linalg.norm(v, axis=1)[:, None]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
             (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    out = []
    for i, j, k in faces:
        a, b, c = v[i], v[j], v[k]
        ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
        for tri in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)):
            s = np.sum(tri, axis=0)
            out.append(s / np.linalg.norm(s))
    return np.array(out)


_CENTRES = _geodesic_centres()


def coverage(h) -> float:
    """Share of the 80 geodesic sections that the calibrated field directions ``h`` visit."""
    h = np.asarray(h, float)
    h = h / np.linalg.norm(h, axis=1)[:, None]
    sections = np.argmax(h @ _CENTRES.T, axis=1)
    return np.unique(sections).size / len(_CENTRES)


def planar(h, ratio: float = 0.05) -> bool:
    """Whether the samples ``h`` (raw or calibrated) lie about a plane (rotations about one
    axis only trace a circle): their smallest spread is below ``ratio`` of the largest."""
    h = np.asarray(h, float)
    s = np.linalg.svd(h - h.mean(axis=0), compute_uv=False)
    return bool(s[-1] < ratio * s[0])


def check_coverage(h, source: str = "magnetometer") -> float:
    """The coverage, refusing a rotation about one axis only or almost no rotation."""
    c = coverage(h)
    if planar(h):
        raise MagDegenerateError(f"{source}: the field turns about one axis only (a planar rotation): the soft "
                                 "iron along that axis is undetermined; rotate the device about all three axes "
                                 "(or pass --no-mag)")
    if c < COVERAGE_REFUSE:
        raise MagDegenerateError(f"{source}: the field visits {100 * c:.0f} % of the directions (ArduPilot-style "
                                 f"coverage): too little rotation for an ellipsoid; rotate the device through "
                                 "all orientations (or pass --no-mag)")
    return c


__all__ = ["COVERAGE_REFUSE", "COVERAGE_WARN", "Prepared", "check_coverage", "coverage", "disturbed_rests",
           "planar", "prepare", "quiet_intervals", "rest_noise"]
