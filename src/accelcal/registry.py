"""The one registry of estimators: what each is and what it needs.

Everything that chooses or describes an estimator reads it from here — the CLI
(``--method``), the calibration objects (:mod:`accelcal.calibration`), the measured
stage, the Monte Carlo, the timing benchmark, its cost table and the workflow's config
check — instead of guessing from a name or keeping a table of its own.  Functions and
classes are named by ``module:attribute`` and imported on first use, so that reading
the registry (``accelcal --help``) imports no numerical library.

==================  ======  ===========  ==  ==========  ===========  ==============  ===========================
name                model   fewest       g   noise       family       baseline        what
==================  ======  ===========  ==  ==========  ===========  ==============  ===========================
``full_lls``        full    10 poses     ✓   —           closed form  full_nlls       Burkhard et al., eqs. 3-6
``full_als``        full    10 poses     ✓   correction  closed form  full_nlls       LLS without its O(σ²) bias
``full_nlls``       full    10 poses     ✓   stopping    iterative    —               CasADi/IPOPT, b = 0, M = I
``bias_lls``        bias    4 poses      —   —           closed form  bias_nlls       eq. 7, M = I
``bias_nlls``       bias    4 poses      ✓   stopping    iterative    —               CasADi/IPOPT with M = I
``gyro_iterative``  s.m.    5 motions    —   —           iterative    —               Gauss-Newton (IMU-TK's)
``gyro_one_step``   s.m.    5 motions    —   —           closed form  gyro_iterative  one linearised solve
``gyro_ferraris``   s.m.    3 rotations  —   —           closed form  —               Ferraris (imucal's)
==================  ======  ===========  ==  ==========  ===========  ==============  ===========================

*model*: s.m. is the gyroscope's ``scale_misalignment``.
*fewest*: the fewest poses (motions between rests, rotations: :attr:`Estimator.data`) it
accepts (:attr:`Estimator.min_poses`, a number of the table): enough equations for the unknowns and one more.  *g*: the estimate depends on the gravity
magnitude (every estimator takes g; the bias-only LLS bias does not change with it).
*noise*: what the estimator uses the noise level of the pose means for
(:meth:`Estimator.fit`, ``noise_std``): ALS for its correction (else it estimates the
level from the poses), NLLS for its stopping tolerance (else IPOPT's default).  A
calibration gives them the level measured at the rests.  *baseline*: the estimator its
accuracy and speed are compared with.  The first five calibrate an accelerometer
(``sensor``) from pose means (:meth:`Estimator.fit`); the gyroscope's take the motions
between the rests (:class:`accelcal.gyro.fit.MotionSet`, whose rest noise weights them:
no separate noise level) or rotations of known angle, through their own function
(:meth:`Estimator.load`, :mod:`accelcal.gyro`), and their calibrations are
:class:`accelcal.gyro.result.GyroCalibration` subclasses.  An estimator of another sensor
or model is one more entry, with its own ``sensor`` and a model of :data:`N_PARAMETERS`.

One protocol per kind of data: an entry is a :class:`PoseEstimator`, a
:class:`MotionEstimator` or a :class:`RotationEstimator`, each with the fields that mean
something for its data and a ``fit`` that takes that data, so that no entry raises when
called through its kind's API (:func:`estimators` ``(data=...)`` lists one kind).

Adding an estimator is one entry (a row of ``estimators.json`` beside this module, read
into :data:`ESTIMATORS`, or :func:`register` at run time) naming its function and its calibration class; the CLI, the calibration
files, the Monte Carlo, the timing benchmark, its cost table and the workflow's config
check follow, and ``tests/test_estimator_conformance.py`` checks it like every other
(``tests/test_add_estimator.py`` does it with a toy).
"""

from __future__ import annotations

import importlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from .errors import AccelcalError

#: The registry's table as data (estimators.json beside this module): the workflow reads the
#: same file as plain JSON while it is parsed (the Burkhard grid's pose minima and method
#: order, the config's estimator names), so that parsing imports no accelcal module.
TABLE_PATH = Path(__file__).with_name("estimators.json")
with TABLE_PATH.open(encoding="utf-8") as _f:
    _TABLE = json.load(_f)

#: Unknowns of each model (bias; bias + scale + non-orthogonality; the gyro's scale and
#: misalignment, ``C`` of :mod:`accelcal.gyro.model`, its bias taken from the rests).
N_PARAMETERS: dict[str, int] = _TABLE["n_parameters"]
#: What an estimator fits, and how many equations each of them gives: a pose mean one
#: (its norm), a motion between two rests two (the tangent components of gravity carried
#: over), a rotation of known angle three (its rotation vector).
DATA: dict[str, int] = _TABLE["equations"]
#: What an estimator may use the noise level of the pose means for.
NOISE_USES = ("correction", "stopping")
#: Families: closed forms (microseconds, a batch form that vectorises) and iterative solvers.
FAMILIES = ("closed_form", "iterative")


@dataclass(frozen=True, kw_only=True)
class Estimator:
    """What every estimator is, whatever data it fits: the common part of the registry's entries.

    An entry is of the class of its data (:class:`PoseEstimator`, :class:`MotionEstimator`,
    :class:`RotationEstimator`: :attr:`data`), and only that class's ``fit`` takes that data,
    so no entry raises through the API of its kind.  The fields every kind has:

    Attributes
    ----------
    name : str
        Registry key and the function's name (``'full_lls'``); the CLI spells it with a
        hyphen (:attr:`cli_name`).  It is also the ``cal_type`` of its calibrations.
    sensor : str
        The sensor it calibrates (``'accelerometer'``, ``'gyroscope'``).
    model : str
        A key of :data:`N_PARAMETERS`: ``'full'`` (``z = M x + b``), ``'bias'`` (``M = I``,
        only ``b`` is estimated), ``'scale_misalignment'`` (the gyro's ``C``).
    algorithm : str
        The algorithm whatever the model (``'lls'``, ``'als'``, ``'nlls'``): column names
        of the comparisons (``lls_vs_nlls``).
    label : str
        Short name in tables and figures (``'full LLS'``).
    function : str
        ``'module:function'`` of the estimator (its signature is its kind's: ``fit``).
    calibration : str
        ``'module:Class'`` of its calibration class (whose ``CAL_TYPE`` is :attr:`name`).
    family : {'closed_form', 'iterative'}
    conditioning : str
        ``'module:function'`` giving the singular values that describe how well the data
        determine the estimate.
    description : str
    baseline : str or None
        The estimator this one is compared with (accuracy and speed).
    min_poses : int
        Fewest poses (motions, rotations: :attr:`data`) the estimator accepts: enough
        equations for its unknowns and one more, so that a residual checks the fit (poses:
        one more than the unknowns, Burkhard et al. Sec. 1.2); exactly determined for the
        Ferraris protocol's three rotations.  A number of the table (``estimators.json``),
        which the workflow reads too; an entry with too few equations for its unknowns is
        refused, and the conformance suites check that one datum fewer is refused.
    """

    #: What the entries of the class fit: a key of :data:`DATA`.
    data: ClassVar[str] = ""

    name: str
    sensor: str
    model: str
    algorithm: str
    label: str
    function: str
    calibration: str
    family: str
    conditioning: str
    description: str
    baseline: str | None = None
    min_poses: int

    def __post_init__(self):
        if self.data not in DATA:
            raise ValueError(f"{self.name}: an entry is a PoseEstimator, MotionEstimator or RotationEstimator")
        if self.model not in N_PARAMETERS:
            raise ValueError(f"{self.name}: model {self.model!r} is not one of {', '.join(N_PARAMETERS)}")
        if self.family not in FAMILIES:
            raise ValueError(f"{self.name}: family {self.family!r} is not one of {', '.join(FAMILIES)}")
        if self.min_poses * DATA[self.data] < self.n_parameters:
            raise ValueError(f"{self.name}: {self.min_poses} {self.data} give {self.min_poses * DATA[self.data]} "
                             f"equations for {self.n_parameters} unknowns (min_poses too small)")

    @property
    def n_parameters(self) -> int:
        return N_PARAMETERS[self.model]

    @property
    def cli_name(self) -> str:
        return self.name.replace("_", "-")

    def load(self):
        """The estimator function (imported now)."""
        return resolve(self.function)

    def load_conditioning(self):
        """The function giving the singular values of the problem (:attr:`conditioning`)."""
        return resolve(self.conditioning)

    def load_calibration(self) -> type:
        """Its calibration class (imported now)."""
        return resolve(self.calibration)


@dataclass(frozen=True, kw_only=True)
class PoseEstimator(Estimator):
    """An estimator of static pose means ``z`` (n, 3) and the gravity magnitude: ``f(z, g, **kw)
    -> CalibrationResult``, its calibration an :class:`accelcal.calibration.Calibration`.

    Attributes (beyond :class:`Estimator`'s)
    ----------------------------------------
    batch : str or None
        ``'module:function'`` of the batched form ``f(z (T, n, 3), g[, noise_std]) ->
        BatchResult`` (``status`` per trial); None: :meth:`fit_batch` calls the
        estimator trial by trial.
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
        Its conditioning function is ``f(poses, noise_var)`` instead of ``f(model, poses)``.
    """

    data: ClassVar[str] = "poses"

    sensor: str = "accelerometer"
    batch: str | None = None
    corrects: str | None = None
    compiled: bool = False
    needs_g: bool = True
    noise_use: str | None = None
    conditioning_uses_noise: bool = False

    def __post_init__(self):
        super().__post_init__()
        if self.noise_use not in (None, *NOISE_USES):
            raise ValueError(f"{self.name}: noise_use {self.noise_use!r} is not one of {', '.join(NOISE_USES)}")

    @property
    def needs_noise(self) -> bool:
        """Whether it uses the noise level of the pose means (:attr:`noise_use`)."""
        return self.noise_use is not None

    @property
    def batch_name(self) -> str:
        """Name of its batched form in tables (``'full_lls_batch'``)."""
        return f"{self.name}_batch"

    def load_batch(self):
        """The batched function, or None."""
        return None if self.batch is None else resolve(self.batch)

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
            return resolve("accelcal.batching:batch_of_single")(self, z, g, noise_std)
        if self.needs_noise and noise_std is not None:
            return f(z, g, noise_std=noise_std)
        return f(z, g)


@dataclass(frozen=True, kw_only=True)
class MotionEstimator(Estimator):
    """An estimator of the motions between rests (:class:`accelcal.gyro.fit.MotionSet`, whose rest
    noise weights them): ``f(motions, C0, integrator) -> GyroFit``, its calibration an
    :class:`accelcal.gyro.result.GyroCalibration`."""

    data: ClassVar[str] = "motions"

    sensor: str = "gyroscope"

    def fit(self, motions, C0, integrator: str = "magnus4"):
        """Fit the motions from the start ``C0`` (3, 3) with the rotation ``integrator``."""
        return self.load()(motions, C0, integrator)


@dataclass(frozen=True, kw_only=True)
class RotationEstimator(Estimator):
    """An estimator of rotations of known angle (a Ferraris session): ``f(segments, h, angles_deg,
    **kw) -> FerrarisFit`` (:func:`accelcal.gyro.ferraris.fit_ferraris`)."""

    data: ClassVar[str] = "rotations"

    sensor: str = "gyroscope"

    def fit(self, segments, h: float, angles_deg, **kw):
        """Fit the rotations' samples ``segments`` (bias removed) of interval ``h`` [s] and known angles."""
        return self.load()(segments, h, angles_deg, **kw)


def resolve(path: str):
    """The object a ``'module:attribute'`` string names (imported now): how every registry of
    this package names its functions and classes, so that reading a registry imports nothing."""
    module, _, name = path.partition(":")
    return getattr(importlib.import_module(module), name)


_MISSING = object()  # a field another kind of entry does not have
#: The class of each kind of entry (its :attr:`Estimator.data`).
KINDS = {cls.data: cls for cls in (PoseEstimator, MotionEstimator, RotationEstimator)}


def entry_from_table(row: dict) -> Estimator:
    """The registry entry of one row of the table: its ``data`` names the class, the other keys are its fields."""
    fields = dict(row)
    kind = fields.pop("data")
    if kind not in KINDS:
        raise ValueError(f"{fields.get('name')}: data {kind!r} is not one of {', '.join(KINDS)}")
    return KINDS[kind](**fields)


#: The estimators, by name, in the order tables and help list them (the rows of estimators.json).
ESTIMATORS: dict[str, Estimator] = {e.name: e for e in map(entry_from_table, _TABLE["estimators"])}


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
                 if (sensor is None or e.sensor == sensor) and all(getattr(e, k, _MISSING) == v for k, v in where.items()))


def min_gyro_rests() -> int:
    """Rests a gyro calibration from motions needs: one more than the fewest motions of the
    registered motion estimators (the CLI's parser reads it without importing the gyro)."""
    return 1 + max(e.min_poses for e in estimators("gyroscope", data="motions"))


def class_of_type(root: type, cal_type: str) -> type | None:
    """The subclass of ``root`` whose own ``CAL_TYPE`` is ``cal_type``, or None.

    The class the registry names for that estimator comes first (another subclass may
    declare the same ``CAL_TYPE``: a script's class defined again); else the subclasses are
    walked (as imucal's ``CalibrationInfo``), so that a class defined anywhere loads its
    files.  ``root`` is :class:`accelcal.calibration.Calibration` or
    :class:`accelcal.gyro.result.GyroCalibration`."""
    if cal_type in ESTIMATORS:
        cls = ESTIMATORS[cal_type].load_calibration()
        if issubclass(cls, root) and cls.__dict__.get("CAL_TYPE") == cal_type:
            return cls
    return next((c for c in subclasses(root) if c.__dict__.get("CAL_TYPE") == cal_type), None)


def subclasses(cls):
    """Every subclass of ``cls``, depth first."""
    for sub in cls.__subclasses__():
        yield sub
        yield from subclasses(sub)


def types_of(root: type) -> list[str]:
    """The ``CAL_TYPE`` of every subclass of ``root`` that declares one (the registered classes imported first)."""
    for e in ESTIMATORS.values():
        e.load_calibration()
    return [c.CAL_TYPE for c in subclasses(root) if "CAL_TYPE" in c.__dict__]


def model_of(name: str) -> str:
    """The model (``'full'``, ``'bias'``) of the estimator ``name``."""
    return estimator(name).model


__all__ = ["DATA", "ESTIMATORS", "Estimator", "FAMILIES", "KINDS", "MotionEstimator", "NOISE_USES", "N_PARAMETERS",
           "PoseEstimator", "RotationEstimator", "TABLE_PATH", "class_of_type", "entry_from_table", "estimator", "estimators", "min_gyro_rests", "model_of", "register", "resolve", "subclasses",
           "types_of", "unregister"]
