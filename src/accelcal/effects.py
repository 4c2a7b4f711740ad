"""The library of candidate effects: parametric extensions of the model of Burkhard et al. (2024).

Every effect extends ``z = M x + b + e`` (eq. 1, ``|x| = g`` at rest) by one block of
three parameters, one per axis, and has a stable id.  The extended model is::

    z = M P(x) + b + β Δt + γ ΔT + e,
    P_j(x) = x_j (1 + κ_j ΔT) + k_j x_j² + c_j x_j³            (per axis j)

with ``Δt = t - t̄`` (time of the pose minus the mean pose time) and ``ΔT = T - T̄``
(temperature of the pose minus the mean pose temperature).  Centring the covariates
keeps ``b`` the bias at the session's mean time and temperature, so that adding a
drift or temperature term does not move the bias by the (absorbed) mean offset.

=====================  ======  =====================================================  ===================
id                     block   meaning                                                unit (z in unit Z)
=====================  ======  =====================================================  ===================
``quadratic``          ``k``   even nonlinearity, the F2 term of Batista et al. 2011   1/(unit of g)
                               (``a_m = F[a + F2 a²] + b``, F2 diagonal)
``cubic``              ``c``   odd nonlinearity (third order)                           1/(unit of g)²
``bias_drift``         ``β``   bias changing linearly with time over the session       Z/s
``temperature``        ``γ``   bias linear in temperature                              Z/°C
``temperature_scale``  ``κ``   scale factor linear in temperature                      1/°C
=====================  ======  =====================================================  ===================

``x`` is in the unit of g (m/s²); ``z`` and ``b`` in the unit of the data (m/s² or raw
counts, in which case ``M`` carries counts per m/s²).

What a pose residual ``r = ||x|| - g`` sees of each effect (at the base fit, to first
order, ``u`` the pose's gravity direction) explains the identifiability results:
``quadratic`` gives ``-g² u_j³`` against the bias's ``-u_j`` (equal on the six faces
``u = ±e_j``, so the six-position design cannot see it), ``cubic`` gives ``-g³ u_j⁴``
against the scale factor's ``-g u_j²`` (equal on the faces too), ``bias_drift`` and
``temperature`` give ``-Δt u_j`` and ``-ΔT u_j`` (indistinguishable if the temperature is
linear in time, zero if it never changes), ``temperature_scale`` ``-g ΔT u_j²``.
"""

from __future__ import annotations

from dataclasses import dataclass

from .errors import AccelcalError

#: Covariates an effect needs from the recording.
TIME = "time"
TEMPERATURE = "temperature"


@dataclass(frozen=True)
class Effect:
    """One candidate effect: a block of three parameters (x, y, z axis).

    Attributes
    ----------
    id : str
        Stable identifier (the name reports use).
    kind : {'additive', 'polynomial'}
        ``additive``: enters as ``covariate · φ`` added to ``z``; ``polynomial``: enters
        ``P(x)`` (inside ``M``).
    power : int
        Power of ``x_j`` in ``P_j`` (polynomial effects; 1 for the temperature scale).
    covariate : str or None
        ``'time'`` or ``'temperature'`` (the effect is multiplied by the centred
        covariate), or None.
    symbol : str
        Parameter symbol in reports.
    unit : str
        Unit of the parameters, with ``Z`` the data unit and ``G`` the unit of g.
    description : str
    """

    id: str
    kind: str
    power: int
    covariate: str | None
    symbol: str
    unit: str
    description: str

    @property
    def parameters(self) -> tuple[str, str, str]:
        return tuple(f"{self.symbol}_{a}" for a in "xyz")


#: The library, in a fixed order (ties and tables follow it).
EFFECTS: dict[str, Effect] = {e.id: e for e in (
    Effect("quadratic", "polynomial", 2, None, "k", "1/G",
           "per-axis even nonlinearity x_j + k_j x_j^2 (Batista et al. 2011, F2)"),
    Effect("cubic", "polynomial", 3, None, "c", "1/G^2",
           "per-axis odd nonlinearity x_j + c_j x_j^3"),
    Effect("bias_drift", "additive", 0, TIME, "beta", "Z/s",
           "bias changing linearly with time over the session"),
    Effect("temperature", "additive", 0, TEMPERATURE, "gamma", "Z/degC",
           "bias linear in temperature"),
    Effect("temperature_scale", "polynomial", 1, TEMPERATURE, "kappa", "1/degC",
           "scale factor linear in temperature"),
)}

#: Ids of the library, in order.
EFFECT_IDS: tuple[str, ...] = tuple(EFFECTS)


def effect(effect_id: str) -> Effect:
    """The effect with id ``effect_id`` (``AccelcalError`` naming the known ids otherwise)."""
    try:
        return EFFECTS[effect_id]
    except KeyError:
        raise AccelcalError(f"unknown effect {effect_id!r}; known: {', '.join(EFFECT_IDS)}") from None


__all__ = ["EFFECTS", "EFFECT_IDS", "Effect", "TEMPERATURE", "TIME", "effect"]
