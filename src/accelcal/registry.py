"""The one registry of estimators: what each is and what it needs.

Everything that chooses or describes an estimator reads it from here — the CLI
(``--method``), the calibration objects (:mod:`accelcal.calibration`), the measured
stage, the Monte Carlo and the timing benchmark — instead of guessing from a name
prefix.  Functions are named by ``module:function`` and imported on first use, so that
reading the registry (``accelcal --help``) imports no numerical library.

=============  ======  =========  =========  =======  ===========  ======================================
name           model   min poses  needs g    noise    family       what
=============  ======  =========  =========  =======  ===========  ======================================
``full_lls``   full    10         yes        no       closed form  Burkhard et al. 2024, eqs. 3-6 (SVD)
``full_als``   full    10         yes        yes      closed form  full LLS without its O(σ²) bias
``full_nlls``  full    10         yes        yes      iterative    CasADi/IPOPT from b = 0, M = I
``bias_lls``   bias    4          no         no       closed form  eq. 7, M = I; b does not depend on g
``bias_nlls``  bias    4          yes        yes      iterative    CasADi/IPOPT with M = I
=============  ======  =========  =========  =======  ===========  ======================================

*needs g*: the estimate depends on the gravity magnitude (every estimator takes g; the
bias-only LLS bias does not change with it).  *noise*: the estimator uses the noise
level of the pose means (:meth:`Estimator.fit`, ``noise_std``): ALS for its correction
(else it estimates it from the poses), NLLS for its stopping tolerance (else IPOPT's
default).  A calibration gives them the level measured at the rests.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass

from .errors import AccelcalError

#: Unknowns of each model (bias; bias + scale + non-orthogonality).
N_PARAMETERS = {"full": 9, "bias": 3}


@dataclass(frozen=True)
class Estimator:
    """One estimator of the model ``z = M x + b`` from static pose means.

    Attributes
    ----------
    name : str
        Registry key, the function's name (``'full_lls'``); the CLI spells it with a
        hyphen (:attr:`cli_name`).
    model : {'full', 'bias'}
        ``'bias'``: ``M = I`` is assumed, only ``b`` is estimated.
    function : str
        ``'module:function'`` of ``f(z, g, **kw) -> CalibrationResult``.
    batch : str or None
        ``'module:function'`` of the batched form ``f(z (T, n, 3), g) -> BatchResult``, if any.
    needs_g : bool
        Whether the estimate depends on g.
    needs_noise : bool
        Whether the estimator uses the noise level of the pose means (``noise_std``).
    family : {'closed_form', 'iterative'}
    conditioning : str
        ``'module:function'`` giving the singular values that describe how well the poses
        determine the estimate (:attr:`accelcal.results.LLSResult.singular_values`):
        ``f(model, poses)``, or ``f(poses, noise_var)`` when ``conditioning_uses_noise``.
    description : str
    conditioning_uses_noise : bool
    """

    name: str
    model: str
    function: str
    batch: str | None
    needs_g: bool
    needs_noise: bool
    family: str
    conditioning: str
    description: str
    conditioning_uses_noise: bool = False

    @property
    def n_parameters(self) -> int:
        return N_PARAMETERS[self.model]

    @property
    def min_poses(self) -> int:
        """Fewest poses the estimator accepts: one more than its unknowns (Burkhard et al. Sec. 1.2)."""
        return self.n_parameters + 1

    @property
    def cli_name(self) -> str:
        return self.name.replace("_", "-")

    def load(self):
        """The estimator function (imported now)."""
        return _resolve(self.function)

    def load_conditioning(self):
        """The function giving the singular values of the problem (:attr:`conditioning`)."""
        return _resolve(self.conditioning)

    def load_batch(self):
        """The batched function, or None."""
        return None if self.batch is None else _resolve(self.batch)

    def fit(self, z, g: float, noise_std: float | None = None):
        """Run the estimator on pose means ``z`` (n, 3) with gravity ``g``.

        ``noise_std`` (the standard error of one pose-mean coordinate, same unit as
        ``z``) is passed to the estimators that use it and ignored by the others.
        """
        f = self.load()
        if self.needs_noise and noise_std is not None:
            return f(z, g, noise_std=noise_std)
        return f(z, g)


def _resolve(path: str):
    module, _, name = path.partition(":")
    return getattr(importlib.import_module(module), name)


#: The estimators, by name, in the order tables and help list them.
ESTIMATORS: dict[str, Estimator] = {e.name: e for e in (
    Estimator("full_lls", "full", "accelcal.lls:full_lls", "accelcal.lls:full_lls_batch", True, False,
              "closed_form", "accelcal.lls:design_singular_values",
              "closed form (SVD), bias + scale + non-orthogonality (Burkhard et al. 2024)"),
    Estimator("full_als", "full", "accelcal.als:full_als", "accelcal.als:full_als_batch", True, True, "closed_form",
              "accelcal.als:moment_singular_values",
              "full LLS with its O(noise^2) bias removed (adjusted least squares)", conditioning_uses_noise=True),
    Estimator("full_nlls", "full", "accelcal.nlls:full_nlls", None, True, True, "iterative",
              "accelcal.lls:design_singular_values", "iterative (CasADi/IPOPT) from b = 0, M = I"),
    Estimator("bias_lls", "bias", "accelcal.lls:bias_lls", "accelcal.lls:bias_lls_batch", False, False,
              "closed_form", "accelcal.lls:design_singular_values",
              "closed form with M = I; the bias does not depend on g"),
    Estimator("bias_nlls", "bias", "accelcal.nlls:bias_nlls", None, True, True, "iterative",
              "accelcal.lls:design_singular_values", "iterative with M = I"),
)}


def estimator(name: str) -> Estimator:
    """The estimator called ``name`` (``'full_lls'`` or the CLI's ``'full-lls'``)."""
    try:
        return ESTIMATORS[name.replace("-", "_")]
    except (KeyError, AttributeError):
        raise AccelcalError(f"unknown estimator {name!r}; known: {', '.join(ESTIMATORS)}") from None


def model_of(name: str) -> str:
    """``'full'`` or ``'bias'``: the model of the estimator ``name``."""
    return estimator(name).model


__all__ = ["ESTIMATORS", "Estimator", "N_PARAMETERS", "estimator", "model_of"]
