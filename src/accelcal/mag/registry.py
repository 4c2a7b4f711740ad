"""The magnetometer's estimators: one registry for its own kind of data, field samples.

The accelerometer's estimators (:mod:`accelcal.registry`) take pose means and gravity; the
magnetometer's take :class:`~accelcal.mag.fit.FieldSamples` (samples and the noise measured
at the rests) and return an :class:`~accelcal.mag.fit.EllipsoidFit`.  Every entry is called
the same way (:meth:`MagEstimator.fit`): none raises through the common call.
``tests/test_mag_conformance.py`` checks every entry (recovers a simulated ellipsoid
within its standard errors, refuses a planar rotation in one line).

=================  ==========  ===========  ==========================================
name               parameters  family       what
=================  ==========  ===========  ==========================================
``ellipsoid_ml``   9           iterative    maximum likelihood (Sampson), from the closed form
``ellipsoid_lg``   9           closed form  Li & Griffiths 2004 (Magneto 1.2's method)
``hard_iron``      4           iterative    sphere: hard iron and one scale (the nested model)
=================  ==========  ===========  ==========================================
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import AccelcalError
from ..registry import resolve

#: What the magnetometer's estimators fit.
DATA = "field_samples"


@dataclass(frozen=True, kw_only=True)
class MagEstimator:
    """One estimator of the magnetometer's ellipsoid from field samples.

    ``function`` is ``'module:function'`` of ``f(samples: FieldSamples) -> EllipsoidFit``;
    ``n_parameters`` the unknowns it fits (9: hard and symmetric soft iron; 4: hard iron and
    one scale)."""

    name: str
    label: str
    function: str
    family: str
    n_parameters: int
    description: str
    data: str = DATA

    @property
    def cli_name(self) -> str:
        return self.name.replace("_", "-")

    @property
    def min_samples(self) -> int:
        return self.n_parameters + 1

    def load(self):
        return resolve(self.function)

    def fit(self, samples):
        """Fit ``samples`` (:class:`~accelcal.mag.fit.FieldSamples`): an ``EllipsoidFit``."""
        return self.load()(samples)


_FIT = "accelcal.mag.fit"
#: The estimators, in the order help lists them (the first is the default).
MAG_ESTIMATORS: dict[str, MagEstimator] = {e.name: e for e in (
    MagEstimator(name="ellipsoid_ml", label="ellipsoid ML", function=f"{_FIT}:fit_ellipsoid_ml", family="iterative",
                 n_parameters=9, description="maximum likelihood on the Sampson distance, from the closed form"),
    MagEstimator(name="ellipsoid_lg", label="Li-Griffiths", function=f"{_FIT}:fit_ellipsoid_lg",
                 family="closed_form", n_parameters=9,
                 description="closed-form ellipsoid (Li & Griffiths 2004), Magneto 1.2's method"),
    MagEstimator(name="hard_iron", label="hard iron", function=f"{_FIT}:fit_hard_iron", family="iterative",
                 n_parameters=4, description="sphere: hard iron and one scale (the nested model)"),
)}


def mag_estimator(name: str) -> MagEstimator:
    """The magnetometer estimator ``name`` (``'ellipsoid_ml'`` or the CLI's ``'ellipsoid-ml'``)."""
    try:
        return MAG_ESTIMATORS[name.replace("-", "_")]
    except (KeyError, AttributeError):
        raise AccelcalError(f"unknown magnetometer estimator {name!r}; known: {', '.join(MAG_ESTIMATORS)}") from None


def register(entry: MagEstimator) -> MagEstimator:
    if entry.name in MAG_ESTIMATORS:
        raise ValueError(f"a magnetometer estimator named {entry.name!r} is registered already")
    MAG_ESTIMATORS[entry.name] = entry
    return entry


def unregister(name: str) -> None:
    del MAG_ESTIMATORS[name]


__all__ = ["DATA", "MAG_ESTIMATORS", "MagEstimator", "mag_estimator", "register", "unregister"]
