"""The library of effects, where the discrepancy loop has always found it: :mod:`accelcal.effects`."""

from ..effects import EFFECT_IDS, EFFECTS, TEMPERATURE, TIME, Effect, effect

__all__ = ["EFFECTS", "EFFECT_IDS", "Effect", "TEMPERATURE", "TIME", "effect"]
