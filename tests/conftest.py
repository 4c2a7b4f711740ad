import numpy as np
import pytest

from accelcal.simulation import random_directions, sample_truth, simulate_poses

G = 9.8055  # Burkhard et al. (2024), Sec. 2


@pytest.fixture
def rng():
    return np.random.default_rng(20240601)


@pytest.fixture
def truth(rng):
    t = sample_truth(rng, 1)
    return {k: v[0] for k, v in t.items()}


def make_poses(rng, truth, n, noise, identity=False):
    M = np.eye(3) if identity else truth["M"]
    return simulate_poses(random_directions(rng, n), G, M, truth["bias"], noise, rng)
