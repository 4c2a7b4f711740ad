"""What keeps the kernels' cold compile small (a fresh clone compiles each kernel once):
one signature per kernel, whatever its callers pass.  tools/bench_kernel_compile.py
measures the compile itself (tens of seconds, too long for the suite)."""

import numpy as np
import pytest

from accelcal import kernels

pytestmark = pytest.mark.skipif(kernels._resolve("auto") != "numba", reason="numba is not installed")


def _dispatchers(module):
    from numba.core.registry import CPUDispatcher

    return {name: obj for name, obj in vars(module).items() if isinstance(obj, CPUDispatcher)}


def test_each_fit_and_noise_kernel_compiles_one_signature():
    """The callers' argument kinds (a flag passed as a constant inside the kernels, a
    read-only or broadcast input) used to compile kernels twice: _evaluate_batch and
    _jacobian typed on a literal ``True``, the noise kernels on read-only arrays."""
    from accelcal.discrepancy import _fit_kernels as K
    from accelcal.noise import _fast as F

    rng = np.random.default_rng(1)
    n, q = 12, 15
    z = rng.normal(size=(n, 3))
    arrays = (rng.normal(size=(2, n)), np.array([2, 0], np.int64), np.array([False, True]), np.zeros(2, np.bool_),
              np.zeros((2, 1, 3, 3, 3)))
    p = 0.01 * rng.normal(size=q)
    K.lm_fit(p, z, *arrays, 1.0, 1e-12, np.full(n, 0.01), 20, 1e-10)
    K.lopo_step(np.tile(p, (n, 1)), z, *arrays, 1.0, 1e-12, np.full(n, 0.01), True)
    K.lopo_step(np.tile(p, (n, 1)), z, *arrays, 1.0, 1e-12, np.full(n, 0.01), False)
    K.evaluate_batch(np.tile(p, (2, 1)), z, *arrays, 1.0, False, 1e-12)
    H = np.abs(rng.normal(size=(3, 8, 2)))
    F.irls_gamma(H, H.sum(axis=2), np.ones(8))
    F.irls_gamma(np.broadcast_to(H[0], (1, 8, 2)), H[:1].sum(axis=2), np.ones(8))  # read-only, as allan_fit's
    s = rng.normal(size=(200, 3))
    F.allan_sums(s, s.mean(axis=0), np.array([1, 2], np.int64))
    s.flags.writeable = False  # a frozen recording's rests
    F.allan_sums(s, s.mean(axis=0), np.array([1, 2], np.int64))
    F.ar1(s, 0.5)
    twice = {f"{mod.__name__}.{name}": [str(sig) for sig in d.signatures]
             for mod in (K, F) for name, d in _dispatchers(mod).items() if len(d.signatures) > 1}
    assert not twice

