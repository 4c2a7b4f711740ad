"""The one registry of estimators: what each is and what it needs.

Everything that chooses or describes an estimator reads it from here — the CLI
(``--method``), the calibration objects (:mod:`accelcal.calibration`), the measured
stage, the Monte Carlo, the timing benchmark, its cost table and the workflow's config
check — instead of guessing from a name or keeping a table of its own.  Functions and
classes are named by ``module:attribute`` and imported on first use, so that reading
the registry (``accelcal --help``) imports no numerical library.

=============  =====  =====  ==  ==========  ===========  =========  ======================================
name           model  poses  g   noise       family       baseline   what
=============  =====  =====  ==  ==========  ===========  =========  ======================================
``full_lls``   full   10     ✓   —           closed form  full_nlls  Burkhard et al. 2024, eqs. 3-6 (SVD)
``full_als``   full   10     ✓   correction  closed form  full_nlls  full LLS without its O(σ²) bias
``full_nlls``  full   10     ✓   stopping    iterative    —          CasADi/IPOPT from b = 0, M = I
``bias_lls``   bias   4      —   —           closed form  bias_nlls  eq. 7, M = I; b does not depend on g
``bias_nlls``  bias   4      ✓   stopping    iterative    —          CasADi/IPOPT with M = I
=============  =====  =====  ==  ==========  ===========  =========  ======================================

*poses*: the fewest poses it accepts.  *g*: the estimate depends on the gravity
magnitude (every estimator takes g; the bias-only LLS bias does not change with it).
*noise*: what the estimator uses the noise level of the pose means for
(:meth:`Estimator.fit`, ``noise_std``): ALS for its correction (else it estimates the
level from the poses), NLLS for its stopping tolerance (else IPOPT's default).  A
calibration gives them the level measured at the rests.  *baseline*: the estimator its
accuracy and speed are compared with.  All five calibrate an accelerometer (``sensor``);
an estimator of another sensor or model is one more entry, with its own ``sensor`` and a
model of :data:`N_PARAMETERS`.

Adding an estimator is one entry (a line of :data:`ESTIMATORS`, or :func:`register` at
run time) naming its function and its calibration class; the CLI, the calibration
files, the Monte Carlo, the timing benchmark, its cost table and the workflow's config
check follow, and ``tests/test_estimator_conformance.py`` checks it like every other
(``tests/test_add_estimator.py`` does it with a toy).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass

from .errors import AccelcalError

#: Unknowns of each model (bias; bias + scale + non-orthogonality).
N_PARAMETERS = {"full": 9, "bias": 3}
#: What an estimator may use the noise level of the pose means for.
NOISE_USES = ("correction", "stopping")
#: Families: closed forms (microseconds, a batch form that vectorises) and iterative solvers.
FAMILIES = ("closed_form", "iterative")


@dataclass(frozen=True, kw_only=True)
class Estimator:
    """One estimator of a sensor model from static pose means.

    Attributes
    ----------
    name : str
        Registry key and the function's name (``'full_lls'``); the CLI spells it with a
        hyphen (:attr:`cli_name`).  It is also the ``cal_type`` of its calibrations.
    sensor : str
        The sensor it calibrates (``'accelerometer'``).
    model : str
        A key of :data:`N_PARAMETERS`: ``'full'`` (``z = M x + b``) or ``'bias'``
        (``M = I``, only ``b`` is estimated).
    algorithm : str
        The algorithm whatever the model (``'lls'``, ``'als'``, ``'nlls'``): column names
        of the comparisons (``lls_vs_nlls``).
    label : str
        Short name in tables and figures (``'full LLS'``).
    function : str
        ``'module:function'`` of ``f(z, g, **kw) -> CalibrationResult``.
    calibration : str
        ``'module:Class'`` of its :class:`accelcal.calibration.Calibration` subclass
        (whose ``CAL_TYPE`` is :attr:`name`).
    family : {'closed_form', 'iterative'}
    conditioning : str
        ``'module:function'`` giving the singular values that describe how well the poses
        determine the estimate (:attr:`accelcal.results.LLSResult.singular_values`):
        ``f(model, poses)``, or ``f(poses, noise_var)`` when ``conditioning_uses_noise``.
    description : str
    batch : str or None
        ``'module:function'`` of the batched form ``f(z (T, n, 3), g[, noise_std]) ->
        BatchResult`` (``status`` per trial); None: :meth:`fit_batch` calls the
        estimator trial by trial.
    baseline : str or None
        The estimator this one is compared with (accuracy and speed).
    corrects : str or None
        The estimator whose estimate this one corrects (compared trial by trial with it).
    compiled : bool
        Whether it has a compiled kernel (:mod:`accelcal.kernels`): timed under every
        backend, and checked against the numpy reference.
    needs_g : bool
        Whether the estimate depends on g.
    noise_use : {'correction', 'stopping'} or None
        What it uses the noise level of the pose means for (``noise_std``), if anything.
    conditioning_uses_noise : bool
    """

    name: str
    sensor: str = "accelerometer"
    model: str
    algorithm: str
    label: str
    function: str
    calibration: str
    family: str
    conditioning: str
    description: str
    batch: str | None = None
    baseline: str | None = None
    corrects: str | None = None
    compiled: bool = False
    needs_g: bool = True
    noise_use: str | None = None
    conditioning_uses_noise: bool = False

    def __post_init__(self):
        if self.model not in N_PARAMETERS:
            raise ValueError(f"{self.name}: model {self.model!r} is not one of {', '.join(N_PARAMETERS)}")
        if self.family not in FAMILIES:
            raise ValueError(f"{self.name}: family {self.family!r} is not one of {', '.join(FAMILIES)}")
        if self.noise_use not in (None, *NOISE_USES):
            raise ValueError(f"{self.name}: noise_use {self.noise_use!r} is not one of {', '.join(NOISE_USES)}")

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

    @property
    def needs_noise(self) -> bool:
        """Whether it uses the noise level of the pose means (:attr:`noise_use`)."""
        return self.noise_use is not None

    @property
    def batch_name(self) -> str:
        """Name of its batched form in tables (``'full_lls_batch'``)."""
        return f"{self.name}_batch"

    def load(self):
        """The estimator function (imported now)."""
        return _resolve(self.function)

    def load_conditioning(self):
        """The function giving the singular values of the problem (:attr:`conditioning`)."""
        return _resolve(self.conditioning)

    def load_batch(self):
        """The batched function, or None."""
        return None if self.batch is None else _resolve(self.batch)

    def load_calibration(self) -> type:
        """Its calibration class (imported now)."""
        return _resolve(self.calibration)

    def fit(self, z, g: float, noise_std: float | None = None):
        """Run the estimator on pose means ``z`` (n, 3) with gravity ``g``.

        ``noise_std`` (the standard error of one pose-mean coordinate, same unit as
        ``z``) is passed to the estimators that use it and ignored by the others.
        """
        f = self.load()
        if self.needs_noise and noise_std is not None:
            return f(z, g, noise_std=noise_std)
        return f(z, g)

    def fit_batch(self, z, g: float, noise_std: float | None = None):
        """Run the estimator on every trial of ``z`` (T, n, 3): a ``BatchResult``.

        The batched form if there is one, else :meth:`fit` trial by trial; either way a
        trial that fails is NaN, ``valid=False``, with the name of its error in
        ``status`` (``'ok'`` otherwise).  ``noise_std`` as for :meth:`fit`.
        """
        f = self.load_batch()
        if f is None:
            # by name, as every function here: the batched loop builds results, which read the registry
            return _resolve("accelcal.batching:batch_of_single")(self, z, g, noise_std)
        if self.needs_noise and noise_std is not None:
            return f(z, g, noise_std=noise_std)
        return f(z, g)


def _resolve(path: str):
    module, _, name = path.partition(":")
    return getattr(importlib.import_module(module), name)


_CAL = "accelcal.calibration"

#: The estimators, by name, in the order tables and help list them.
ESTIMATORS: dict[str, Estimator] = {e.name: e for e in (
    Estimator(name="full_lls", model="full", algorithm="lls", label="full LLS", family="closed_form",
              function="accelcal.lls:full_lls", batch="accelcal.lls_batch:full_lls_batch",
              calibration=f"{_CAL}:FullLLSCalibration", baseline="full_nlls", compiled=True,
              conditioning="accelcal.lls:design_singular_values",
              description="closed form (SVD), bias + scale + non-orthogonality (Burkhard et al. 2024)"),
    Estimator(name="full_als", model="full", algorithm="als", label="full ALS", family="closed_form",
              function="accelcal.als:full_als", batch="accelcal.als:full_als_batch",
              calibration=f"{_CAL}:FullALSCalibration", baseline="full_nlls", corrects="full_lls", compiled=True,
              noise_use="correction", conditioning="accelcal.als:moment_singular_values",
              conditioning_uses_noise=True,
              description="full LLS with its O(noise^2) bias removed (adjusted least squares)"),
    Estimator(name="full_nlls", model="full", algorithm="nlls", label="full NLLS", family="iterative",
              function="accelcal.nlls:full_nlls", batch="accelcal.nlls:full_nlls_batch",
              calibration=f"{_CAL}:FullNLLSCalibration", noise_use="stopping",
              conditioning="accelcal.lls:design_singular_values",
              description="iterative (CasADi/IPOPT) from b = 0, M = I"),
    Estimator(name="bias_lls", model="bias", algorithm="lls", label="bias-only LLS", family="closed_form",
              function="accelcal.lls:bias_lls", batch="accelcal.lls_batch:bias_lls_batch",
              calibration=f"{_CAL}:BiasLLSCalibration", baseline="bias_nlls", compiled=True, needs_g=False,
              conditioning="accelcal.lls:design_singular_values",
              description="closed form with M = I; the bias does not depend on g"),
    Estimator(name="bias_nlls", model="bias", algorithm="nlls", label="bias-only NLLS", family="iterative",
              function="accelcal.nlls:bias_nlls", batch="accelcal.nlls:bias_nlls_batch",
              calibration=f"{_CAL}:BiasNLLSCalibration", noise_use="stopping",
              conditioning="accelcal.lls:design_singular_values",
              description="iterative with M = I"),
)}


def register(entry: Estimator) -> Estimator:
    """Add ``entry`` to :data:`ESTIMATORS` (after the others); a name taken, or a baseline
    that is not registered, is refused."""
    if entry.name in ESTIMATORS:
        raise ValueError(f"an estimator named {entry.name!r} is registered already")
    for role in ("baseline", "corrects"):
        other = getattr(entry, role)
        if other is not None and other not in ESTIMATORS:
            raise ValueError(f"{entry.name}: {role} {other!r} is not a registered estimator")
    ESTIMATORS[entry.name] = entry
    return entry


def unregister(name: str) -> None:
    """Remove the estimator ``name`` (what :func:`register` added; tests)."""
    del ESTIMATORS[name]


def estimator(name: str) -> Estimator:
    """The estimator called ``name`` (``'full_lls'`` or the CLI's ``'full-lls'``)."""
    try:
        return ESTIMATORS[name.replace("-", "_")]
    except (KeyError, AttributeError):
        raise AccelcalError(f"unknown estimator {name!r}; known: {', '.join(ESTIMATORS)}") from None


def estimators(sensor: str | None = None, **where) -> tuple[Estimator, ...]:
    """The registered estimators (in order) of ``sensor`` (all if None) whose attributes
    equal ``where`` (``estimators('accelerometer', model='full')``)."""
    return tuple(e for e in ESTIMATORS.values()
                 if (sensor is None or e.sensor == sensor) and all(getattr(e, k) == v for k, v in where.items()))


def model_of(name: str) -> str:
    """The model (``'full'``, ``'bias'``) of the estimator ``name``."""
    return estimator(name).model


__all__ = ["ESTIMATORS", "Estimator", "FAMILIES", "NOISE_USES", "N_PARAMETERS", "estimator", "estimators", "model_of",
           "register", "unregister"]
