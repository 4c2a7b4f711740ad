"""The library of effects: parametric extensions of the model of Burkhard et al. (2024).

Every effect extends ``z = M x + b + e`` (eq. 1, ``|x| = g`` at rest) by one block of
parameters ``φ`` (three, one per axis, for the per-axis kinds) and has a stable id.  The
extended model is::

    z = M P(x) + b + Σ_additive c φ + e,
    P_j(x) = x_j + Σ_polynomial c φ_j x_j^p + Σ_harmonic Σ_m φ_m ∂_j H_m(x)/(p + 1)   (axis j)

where each effect's ``c`` is its centred covariate (``Δt = t - t̄``, the time of the pose
minus the mean pose time, or ``ΔT = T - T̄`` for the temperature) or 1, and ``p`` its
power.  With the effects below: ``z = M P(x) + b + β Δt + γ ΔT``,
``P_j(x) = x_j (1 + κ_j ΔT) + k_j x_j² + c_j x_j³ + Σ_kl K_jkl x_k x_l``.

A *harmonic* effect of power ``p`` is the full (cross-axis) polynomial of order ``p`` of
which a pose residual can see anything: with ``H_m`` the ``2l + 1`` real harmonic
homogeneous polynomials of degree ``l = p + 1`` (orthonormal over the unit sphere), the
vector field ``Σ_m φ_m ∇H_m(x)/l``.  For ``p = 2`` it is ``K(x, x)`` with
``K_jkl = Σ_m φ_m T_m,jkl`` the totally symmetric, traceless part of a general
second-order tensor (18 coefficients ``K_j,kl``, ``k ≤ l``): its other 11 combinations
are absorbed by the bias (a degree-1 radial signature) or invisible to ``|x|`` (tangential),
so the 7 ``φ_m`` are what a multi-position calibration can identify.  Centring the covariates keeps ``b``
the bias at the session's mean time and temperature, so that adding a drift or
temperature term does not move the bias by the (absorbed) mean offset.

This module is the table only (no numerical code: the command line reads it for its
help); :mod:`accelcal.extended_model` implements the model for every entry.  An effect
of an existing kind (additive or polynomial, any power, time, temperature or no
covariate) is one more :class:`Effect` in :data:`EFFECTS`.

=====================  ======  =====================================================  ===================
id                     block   meaning                                                unit (z in unit Z)
=====================  ======  =====================================================  ===================
``quadratic``          ``k``   even nonlinearity, the F2 term of Batista et al. 2011   1/(unit of g)
                               (``a_m = F[a + F2 a²] + b``, F2 diagonal)
``cubic``              ``c``   odd nonlinearity (third order)                           1/(unit of g)²
``bias_drift``         ``β``   bias changing linearly with time over the session       Z/s
``temperature``        ``γ``   bias linear in temperature                              Z/°C
``temperature_scale``  ``κ``   scale factor linear in temperature                      1/°C
``second_order``       ``h``   full second-order (cross-axis) nonlinearity ``K(x,x)``,  1/(unit of g)
                               its 7 identifiable combinations (harmonic, power 2)
=====================  ======  =====================================================  ===================

``x`` is in the unit of g (m/s²); ``z`` and ``b`` in the unit of the data (m/s² or raw
counts, in which case ``M`` carries counts per m/s²).

What a pose residual ``r = ||x|| - g`` sees of each effect (at the base fit, to first
order, ``u`` the pose's gravity direction) explains the identifiability results:
``quadratic`` gives ``-g² u_j³`` against the bias's ``-u_j`` (equal on the six faces
``u = ±e_j``, so the six-position design cannot see it), ``cubic`` gives ``-g³ u_j⁴``
against the scale factor's ``-g u_j²`` (equal on the faces too), ``bias_drift`` and
``temperature`` give ``-Δt u_j`` and ``-ΔT u_j`` (indistinguishable if the temperature is
linear in time, zero if it never changes), ``temperature_scale`` ``-g ΔT u_j²``,
``second_order`` ``-g² Σ_m φ_m H_m(u)``: the seven degree-3 harmonics, which vanish
together on the six faces and whose ``u_x u_y u_z`` member vanishes on every face and edge
(the design needs poses with three non-zero components, e.g. corners); with the nine base
parameters it needs at least 16 poses, and more to test it (:mod:`accelcal.discrepancy`).
"""

from __future__ import annotations

from dataclasses import dataclass

from .errors import AccelcalError

#: Covariates an effect can be multiplied by (centred over the recording's poses).
TIME = "time"
TEMPERATURE = "temperature"
COVARIATES = (TIME, TEMPERATURE)
#: Where an effect enters: added to ``z`` (outside ``M``), or to ``P(x)`` (inside ``M``).
#: Or the harmonic part of a full (cross-axis) polynomial of order ``power``, inside ``M``.
ADDITIVE = "additive"
POLYNOMIAL = "polynomial"
HARMONIC = "harmonic"
KINDS = (ADDITIVE, POLYNOMIAL, HARMONIC)
#: Powers of the harmonic effects :mod:`accelcal.extended_model` has the basis of.
HARMONIC_POWERS = (2,)


@dataclass(frozen=True)
class Effect:
    """One candidate effect: a block of parameters (:attr:`size`: three, one per axis, or the
    ``2 power + 3`` of a harmonic effect).

    Attributes
    ----------
    id : str
        Stable identifier (the name reports use).
    kind : {'additive', 'polynomial', 'harmonic'}
        ``additive``: enters as ``c φ`` added to ``z``; ``polynomial``: as ``c φ_j x_j^p``
        added to ``P_j(x)`` (inside ``M``); ``harmonic``: as ``Σ_m φ_m ∇H_m(x)/(p + 1)``
        added to ``P(x)`` (module docstring).
    power : int
        ``p``: power of ``x_j`` (polynomial effects, at least 1; 0 for additive ones), the
        order of the harmonic effect's polynomial (:data:`HARMONIC_POWERS`).
    covariate : str or None
        ``'time'`` or ``'temperature'`` (``c`` is the centred covariate), or None (``c = 1``).
    symbol : str
        Parameter symbol in reports.
    unit : str
        Unit of the parameters, with ``Z`` the data unit and ``G`` the unit of g.
    label : str
        Short name in figures.
    description : str
    """

    id: str
    kind: str
    power: int
    covariate: str | None
    symbol: str
    unit: str
    label: str
    description: str

    def __post_init__(self):
        if self.kind not in KINDS:
            raise AccelcalError(f"effect {self.id!r}: kind {self.kind!r} is not one of {', '.join(KINDS)}")
        if self.covariate is not None and self.covariate not in COVARIATES:
            raise AccelcalError(f"effect {self.id!r}: covariate {self.covariate!r} is not one of "
                                f"{', '.join(COVARIATES)} (or None)")
        if self.kind == ADDITIVE and (self.power != 0 or self.covariate is None):
            raise AccelcalError(f"effect {self.id!r}: an additive effect has power 0 and a covariate "
                                "(without one it is the bias)")
        if self.kind == POLYNOMIAL and not (self.power >= 2 or (self.power == 1 and self.covariate is not None)):
            raise AccelcalError(f"effect {self.id!r}: a polynomial effect has power >= 2, or power 1 and a "
                                "covariate (power 1 alone is the scale factor)")
        if self.kind == HARMONIC and (self.power not in HARMONIC_POWERS or self.covariate is not None):
            raise AccelcalError(f"effect {self.id!r}: a harmonic effect has no covariate and a power of "
                                f"{', '.join(map(str, HARMONIC_POWERS))} (the harmonic bases implemented)")

    @property
    def degree(self) -> int:
        """Degree ``l = p + 1`` of a harmonic effect's polynomials (0 for the per-axis kinds)."""
        return self.power + 1 if self.kind == HARMONIC else 0

    @property
    def size(self) -> int:
        """Number of parameters: 3 (one per axis), or ``2 l + 1`` for a harmonic effect."""
        return 2 * self.degree + 1 if self.kind == HARMONIC else 3

    @property
    def parameters(self) -> tuple[str, ...]:
        if self.kind == HARMONIC:
            return tuple(f"{self.symbol}_{m}" for m in range(-self.degree, self.degree + 1))
        return tuple(f"{self.symbol}_{a}" for a in "xyz")


#: The library, in a fixed order (ties and tables follow it).
EFFECTS: dict[str, Effect] = {e.id: e for e in (
    Effect(id="quadratic", kind=POLYNOMIAL, power=2, covariate=None, symbol="k", unit="1/G", label="quadratic",
           description="per-axis even nonlinearity x_j + k_j x_j^2 (Batista et al. 2011, F2)"),
    Effect(id="cubic", kind=POLYNOMIAL, power=3, covariate=None, symbol="c", unit="1/G^2", label="cubic",
           description="per-axis odd nonlinearity x_j + c_j x_j^3"),
    Effect(id="bias_drift", kind=ADDITIVE, power=0, covariate=TIME, symbol="beta", unit="Z/s", label="bias drift",
           description="bias changing linearly with time over the session"),
    Effect(id="temperature", kind=ADDITIVE, power=0, covariate=TEMPERATURE, symbol="gamma", unit="Z/degC",
           label="temperature", description="bias linear in temperature"),
    Effect(id="temperature_scale", kind=POLYNOMIAL, power=1, covariate=TEMPERATURE, symbol="kappa",
           unit="1/degC", label="temp. scale", description="scale factor linear in temperature"),
    Effect(id="second_order", kind=HARMONIC, power=2, covariate=None, symbol="h", unit="1/G", label="2nd order",
           description="full second-order (cross-axis) nonlinearity x + K(x, x): the 7 identifiable combinations of "
                       "K (its totally symmetric traceless part, degree-3 harmonics)"),
)}

#: Ids of the library, in order.
EFFECT_IDS: tuple[str, ...] = tuple(EFFECTS)


def effect(effect_id: str) -> Effect:
    """The effect with id ``effect_id`` (``AccelcalError`` naming the known ids otherwise)."""
    try:
        return EFFECTS[effect_id]
    except KeyError:
        raise AccelcalError(f"unknown effect {effect_id!r}; known: {', '.join(EFFECTS)}") from None


__all__ = ["ADDITIVE", "COVARIATES", "EFFECTS", "EFFECT_IDS", "Effect", "HARMONIC", "HARMONIC_POWERS", "KINDS", "POLYNOMIAL",
           "TEMPERATURE", "TIME", "effect"]
