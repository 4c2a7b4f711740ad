"""One recording through both layers: the report of ``accelcal discrepancy`` and of the workflow.

:func:`discrepancy_report` detects the static poses (as ``accelcal calibrate`` does), runs the
deterministic layer (:func:`accelcal.discrepancy.detect.discrepancy`) on the pose means
and the stochastic layer (:func:`accelcal.discrepancy.stochastic.stochastic_layer`) on
the same rests, joins them (:func:`accelcal.discrepancy.noise_implication.noise_implication`:
what the named noise terms imply for the pose residuals) and runs the gyro's and the
magnetometer's loops.  The algorithm lives here; its result, :class:`DiscrepancyReport`,
with its JSON and summary, in :mod:`.results` (imucal's split of algorithm and result).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import AccelcalError
from ..recording import Recording
from ..registry import estimator
from ..static_auto import find_static_poses
from .detect import discrepancy
from .fit import pose_data_from_static
from .gyro_loop import gyro_layer
from .mag_loop import mag_layer
from .noise_implication import noise_implication
from .results import DiscrepancyReport
from .rules import Rules
from .stochastic.layer import DEFAULT_CANDIDATES, rest_segments, stochastic_layer


@dataclass(frozen=True)
class StochasticSettings:
    """Settings of the stochastic layer (config ``discrepancy.stochastic``)."""

    seed: int = 20240708
    alpha: float = 0.05
    max_terms: int = 3
    candidates: tuple[str, ...] = DEFAULT_CANDIDATES
    n_boot: int = 199
    n_resim: int = 16

    @classmethod
    def from_config(cls, cfg: dict) -> StochasticSettings:
        return cls(**{k: (tuple(v) if k == "candidates" else v) for k, v in cfg.items()})


#: What ``accelcal discrepancy`` uses (config/config.yaml's ``discrepancy`` section holds the
#: same values; tests/test_discrepancy_cli.py checks that they agree).
DEFAULT_STOCHASTIC = StochasticSettings()


def discrepancy_report(rec: Recording, g: float, *, rules: Rules | None = None,
                       stochastic: StochasticSettings | None = DEFAULT_STOCHASTIC, unit: str = "u",
                       static_kw: dict | None = None, search: bool = False,
                       min_poses: int = 0, gyro: bool = True, mag: bool = True) -> DiscrepancyReport:
    """The discrepancy report of a recording: static poses, both layers and their join.

    Finds the static poses as ``accelcal calibrate`` does (one code path,
    :func:`accelcal.static_auto.find_static_poses`: the settings ``static_kw``, and with
    ``search`` the candidates' best when they give fewer poses than the full model needs,
    or ``min_poses`` if more), runs the deterministic layer on their means and the
    stochastic layer on the same rests (``stochastic=None`` skips it), and joins them
    (:func:`noise_implication`); the gyro's loop (``gyro``) and the magnetometer's
    (``mag``, :func:`accelcal.discrepancy.mag_loop.mag_layer`) when the recording has them.

    Raises
    ------
    AccelcalError
        From the static detection or the deterministic layer (too few poses, no rest...).
        A recording whose rests are too short for the stochastic layer is not an error:
        the report says why that layer is missing.
    """
    need = max(estimator("full_lls").min_poses, min_poses) if search else 0
    poses, searched = find_static_poses(rec, g, static_kw, need)
    static = {**(static_kw or {}), "known_intervals": rec.intervals is not None}
    if searched is not None:
        static.update({**searched["settings"], "search": searched})
    det = discrepancy(pose_data_from_static(poses, g, rec.acc, rec.rate), rules or Rules())
    stoch, err, impl = None, "", {}
    if stochastic is not None:
        try:
            stoch = stochastic_layer(rest_segments(rec.acc, poses.intervals), rec.rate, seed=stochastic.seed,
                                     alpha=stochastic.alpha, max_terms=stochastic.max_terms,
                                     candidates=stochastic.candidates, intervals=poses.intervals,
                                     n_boot=stochastic.n_boot, n_resim=stochastic.n_resim, unit=unit)
        except AccelcalError as e:
            err = str(e).splitlines()[0]
        else:
            iv = poses.intervals
            impl = noise_implication(det, stoch, iv[:, 0] / rec.rate, (iv[:, 1] - iv[:, 0]) / rec.rate,
                                     (rules or Rules()).alpha)
    else:
        err = "not run"
    gyro_result, gyro_err = (gyro_layer(rec, g, poses, alpha=(rules or Rules()).alpha) if gyro and rec.gyro is not None
                             else (None, "no gyro in the recording" if rec.gyro is None else "gyro left out (--no-gyro)"))
    mag_result, mag_err = (mag_layer(rec, poses, alpha=(rules or Rules()).alpha) if mag and rec.mag is not None
                           else (None, "no magnetometer in the recording" if rec.mag is None else
                                 "magnetometer left out (--no-mag)"))
    return DiscrepancyReport(poses, det, stoch, err, impl, rec.rate, unit, static, gyro_result, gyro_err or "",
                             mag_result, mag_err or "")


__all__ = ["DEFAULT_STOCHASTIC", "StochasticSettings", "discrepancy_report"]
