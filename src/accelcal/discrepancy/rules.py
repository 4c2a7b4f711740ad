"""The decision rules of the discrepancy loop (config ``discrepancy.rules``): :class:`Rules`.

The loops (:mod:`.white_loop` under the white null, :mod:`.wander_loop` under the wander
null; :func:`accelcal.discrepancy.detect.discrepancy` chooses) test every candidate effect
of the library as a nested extension of the current model; what decides is here, the
statistics in :mod:`.statistics`, the checks before any test in :mod:`.identifiability`,
the rows and the result in :mod:`.results`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..effects import EFFECT_IDS, effect
from ..errors import AccelcalError
from .wander_process import FAMILIES

CORRECTIONS = ("holm", "bonferroni", "none")
#: The noise models of the null hypothesis: ``wander`` (white per-pose noise + a bias wander
#: estimated jointly, :mod:`.wander_loop`), ``white`` (white per-pose noise times a common scale:
#: the F-test loop of this module).
NULLS = ("wander", "white")
#: Earlier names of the nulls, still read (configs, reports): ``colored`` is the wander null.
OLD_NULL_NAMES = {"colored": "wander"}


def null_name(null: str) -> str:
    """The current name of a null hypothesis (an earlier name, :data:`OLD_NULL_NAMES`, read as its new one)."""
    return OLD_NULL_NAMES.get(null, null)


#: The members the wander null's noise model is chosen from (REML, by likelihood: one size
#: parameter each): the entries of :data:`.wander_process.FAMILIES`, where each says what
#: it holds and what its problem is joined with.
WANDER_FAMILIES = tuple(FAMILIES)


@dataclass(frozen=True)
class Rules:
    """Decision rules of the loop (config ``discrepancy.rules``; defaults = config/config.yaml).

    ``null`` selects the noise model of the tests (:data:`NULLS`); ``n_boot`` and ``seed``
    the parametric bootstrap of the wander null; ``outlier_pose`` / ``max_outliers`` the
    outlier family (wander null only); ``max_wander_inflation`` when a candidate that did
    not pass counts as not identifiable against the wander (:mod:`.wander_loop`);
    ``wander_family`` the members the wander is chosen from by REML (:data:`WANDER_FAMILIES`).
    """

    null: str = "wander"
    alpha: float = 0.05
    correction: str = "holm"
    bic_threshold: float = 2.0
    lopo_min_improvement: float = 0.0
    max_rounds: int = 3
    power: float = 0.8
    max_absorbed: float = 0.9999
    max_mde_g: float = 0.01
    min_temp_range: float = 0.5
    candidates: tuple[str, ...] = EFFECT_IDS
    n_boot: int = 199
    seed: int = 20240709
    outlier_pose: bool = True
    max_outliers: int = 3
    max_wander_inflation: float = 3.0
    wander_family: str = "flicker"

    def __post_init__(self):
        if self.wander_family not in WANDER_FAMILIES:
            raise AccelcalError(f"wander_family must be one of {', '.join(WANDER_FAMILIES)}, got {self.wander_family!r}")
        object.__setattr__(self, "null", null_name(self.null))
        if self.null not in NULLS:
            raise AccelcalError(f"null must be one of {', '.join(NULLS)}, got {self.null!r}")
        if int(self.n_boot) != self.n_boot or self.n_boot < 19:
            raise AccelcalError(f"n_boot must be an integer >= 19 (p-values down to 0.05), got {self.n_boot}")
        if self.max_outliers < 0 or not self.max_wander_inflation >= 1:
            raise AccelcalError("need max_outliers >= 0 and max_wander_inflation >= 1")
        family = len(self.candidates) + bool(self.outlier_pose)
        if self.null == "wander" and (self.n_boot + 1) * self.alpha < family * (1 - 1e-9):
            raise AccelcalError(f"n_boot = {self.n_boot} cannot reach Holm's first level alpha/{family} (the smallest "
                                f"bootstrap p-value is 1/(n_boot + 1)): use n_boot >= {int(np.ceil(family / self.alpha)) - 1}")
        if not 0 < self.alpha < 1 or not 0 < self.power < 1:
            raise AccelcalError(f"need 0 < alpha < 1 and 0 < power < 1, got {self.alpha}, {self.power}")
        if self.correction not in CORRECTIONS:
            raise AccelcalError(f"correction must be one of {', '.join(CORRECTIONS)}, got {self.correction!r}")
        if self.max_rounds < 1 or not 0 < self.max_absorbed <= 1:
            raise AccelcalError("need max_rounds >= 1 and 0 < max_absorbed <= 1")
        object.__setattr__(self, "candidates", tuple(self.candidates))
        for e in self.candidates:
            effect(e)
        if len(set(self.candidates)) != len(self.candidates) or not self.candidates:
            raise AccelcalError("candidates must be a non-empty list of distinct effect ids")

    @classmethod
    def from_config(cls, cfg: dict) -> Rules:
        # YAML reads an unquoted ``null:`` key as None: take it for the ``null`` field
        cfg = {("null" if k is None else k): v for k, v in cfg.items()}
        return cls(**{k: (tuple(v) if k == "candidates" else v) for k, v in cfg.items()})


__all__ = ["CORRECTIONS", "NULLS", "OLD_NULL_NAMES", "Rules", "WANDER_FAMILIES", "null_name"]
