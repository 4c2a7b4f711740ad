"""The magnetometer's calibration: model, fit, alignment, trust; JSON and a summary."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..summary import Summary
from .align import Alignment, dip_angles
from .fit import EllipsoidFit
from .model import PARAMETERS, MagModel
from .trust import COVERAGE_WARN

#: χ²/dof above this says the ellipsoid misses something the noise does not explain.
CHI2_WARN = 2.0
#: Dip spread above this many times the alignment's residual expected from the noise names a bending field.
DIP_SPREAD_WARN_DEG = 1.0


def spreads(h, f=None) -> dict:
    """Tool-independent measures: the relative spread of |h| and, with specific forces ``f``
    of the same instants, the spread [deg] of the dip between each field and its vertical."""
    h = np.asarray(h, float)
    n = np.linalg.norm(h, axis=1)
    out = {"norm_spread": float(np.std(n) / np.mean(n))}
    if f is not None:
        out["dip_spread_deg"] = float(np.std(dip_angles(f, h), ddof=1 if len(h) > 1 else 0))
    return out


@dataclass(frozen=True)
class MagCalibration:
    """One session's magnetometer calibration (:func:`accelcal.mag.calibrate_magnetometer`)."""

    model: MagModel
    fit: EllipsoidFit | None
    alignment: Alignment | None
    estimator: str
    trust: dict = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    def apply(self, raw) -> np.ndarray:
        """Calibrated field of raw samples (n, 3)."""
        return self.model.correct(raw)

    def warnings(self) -> list[str]:
        """What the trust checks flag, one line each."""
        t, out = self.trust, []
        if t.get("coverage") is not None and t["coverage"] < COVERAGE_WARN:
            out.append(f"the field visits {100 * t['coverage']:.0f} % of the directions (80 sections): the soft "
                       "iron rests on few of them; rotate through more orientations")
        if t.get("chi2_dof") is not None and t["chi2_dof"] > CHI2_WARN:
            out.append(f"residual chi2/dof {t['chi2_dof']:.1f} against the rests' noise: the ellipsoid misses "
                       "something (a disturbance during the rotation, a time lag, or a field that bends)")
        if t.get("disturbed_rests"):
            out.append(f"the field moves at rest in rest(s) {', '.join(map(str, t['disturbed_rests']))}: left out "
                       "of the alignment")
        if self.alignment is not None and self.alignment.undetermined:
            out.append("alignment undetermined along " + "; ".join(self.alignment.undetermined))
        if t.get("dip_spread_deg") is not None and t["dip_spread_deg"] > DIP_SPREAD_WARN_DEG:
            out.append(f"the dip varies by {t['dip_spread_deg']:.2f} deg (sd) across orientations after alignment: "
                       "a field that bends (steel, a motor nearby) or an accelerometer error, not fitted away")
        if t.get("dip_model_deg") is not None and self.alignment is not None:
            d = self.alignment.dip_deg - t["dip_model_deg"]
            if abs(d) > max(3 * self.alignment.se_dip_deg, 1.0):
                out.append(f"the dip {self.alignment.dip_deg:.2f} deg differs from the model's "
                           f"{t['dip_model_deg']:.2f} by {d:+.2f} deg: a local disturbance")
        return out

    def summary(self, *, written_to=None) -> Summary:
        """The magnetometer in a few lines: the model with ±, the fit and the trust lines."""
        m, f = self.model, self.fit
        se = f.se if f is not None and f.se is not None else np.full(9, np.nan)
        lines = [f"magnetometer ({self.estimator}, {self.trust.get('n_samples', '?')} samples, raw unit "
                 f"{m.raw_unit}):"]
        lines.append("  hard iron b = " + ", ".join(f"{v:.6g} ± {s:.2g}" for v, s in zip(m.b, se[:3])))
        lines.append("  soft iron A = " + ", ".join(f"{PARAMETERS[3 + i][2:]} {v:.6g} ± {s:.2g}"
                                                     for i, (v, s) in enumerate(zip(f.theta[3:], se[3:])))
                     if f is not None else "  soft iron: none")
        if self.alignment is not None:
            a = self.alignment
            lines.append(f"  aligned to the accelerometer ({self.trust.get('alignment_from')}): rotation "
                         f"{a.angle_deg:.2f} deg (s.e. {np.degrees(np.max(a.se_rotation)):.2g} deg per axis), dip "
                         f"{a.dip_deg:.3f} ± {a.se_dip_deg:.2g} deg")
        else:
            lines.append(f"  not aligned to the accelerometer: {self.trust.get('alignment_from')}")
        t = self.trust
        chi = "n/a" if t.get("chi2_dof") is None else f"{t['chi2_dof']:.2f}"
        lines.append(f"  trust: coverage {100 * t.get('coverage', float('nan')):.0f} % of directions, chi2/dof {chi} "
                     f"(noise: {t.get('noise_source')})")
        if t.get("chi2_dof") is not None and t["chi2_dof"] > CHI2_WARN:
            lines.append(f"  ±: the Cramér-Rao bound for the rests' noise, x{np.sqrt(t['chi2_dof']):.2f} for the excess")
        if t.get("soft_iron_F") is not None:
            needed = t["soft_iron_p"] < 0.01
            lines.append(f"  soft iron against a sphere: F = {t['soft_iron_F']:.3g} (p = {t['soft_iron_p']:.2g}): "
                         + ("needed" if needed else "not distinguishable: the hard iron alone (--mag-method "
                                                   "hard-iron) fits as well"))
        if "dip_spread_deg" in t:
            lines.append(f"  |m| spread {100 * t['norm_spread']:.2f} %, dip spread {t['dip_spread_deg']:.3f} deg "
                         f"(without the alignment {t['dip_spread_unaligned_deg']:.3f} deg)")
        lines += [f"  note: {n}" for n in self.notes]
        lines += [f"  warning: magnetometer: {w}" for w in self.warnings()]
        if written_to is not None:
            lines.append(f"written to {written_to}")
        return Summary(lines)

    def to_dict(self) -> dict:
        f, a = self.fit, self.alignment
        return {
            "cal_type": self.estimator, "model": self.model.to_dict(),
            "se": None if f is None or f.se is None else dict(zip(PARAMETERS, f.se.tolist())),
            "cov": None if f is None or f.cov is None else f.cov.tolist(),
            "alignment": None if a is None else {
                "R": a.R.tolist(), "dip_deg": a.dip_deg, "se_dip_deg": a.se_dip_deg,
                "se_rotation_rad": a.se_rotation.tolist(), "n": a.n, "residual_rms_deg": a.residual_rms,
                "undetermined": list(a.undetermined)},
            "trust": {k: v for k, v in self.trust.items()}, "notes": list(self.notes)}

    @classmethod
    def from_dict(cls, d: dict) -> "MagCalibration":
        model = MagModel.from_dict(d["model"])
        fit = None
        if d.get("cov") is not None:
            fit = EllipsoidFit(A=model.A, b=model.b, method=d["cal_type"], cov=np.array(d["cov"]))
        a = d.get("alignment")
        al = None if a is None else Alignment(
            R=np.array(a["R"]), dip_deg=a["dip_deg"], se_dip_deg=a["se_dip_deg"],
            se_rotation=np.array(a["se_rotation_rad"]), dips=np.zeros(0), n=a["n"],
            residual_rms=a["residual_rms_deg"], undetermined=tuple(a.get("undetermined", ())))
        return cls(model=model, fit=fit, alignment=al, estimator=d["cal_type"], trust=dict(d.get("trust", {})),
                   notes=tuple(d.get("notes", ())))


__all__ = ["CHI2_WARN", "MagCalibration", "spreads"]
