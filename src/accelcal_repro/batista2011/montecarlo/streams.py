"""Random streams of the Monte Carlos: one per experiment, or one per run (so that a run's
numbers do not depend on which other runs share its job)."""

from __future__ import annotations

import zlib

import numpy as np


def stream(seed: int, name: str) -> np.random.Generator:
    """Independent random stream per experiment: derived from the master seed and a name."""
    return np.random.default_rng([int(seed), zlib.crc32(name.encode())])


def run_streams(seed: int, name: str, run_ids) -> list[np.random.Generator]:
    """One independent random stream per run: derived from the master seed, the
    experiment's name and the run's number (not from its position in a job)."""
    key = zlib.crc32(name.encode())
    return [np.random.default_rng([int(seed), key, int(r)]) for r in run_ids]


__all__ = ["run_streams", "stream"]
