"""Kernels that live in the reproductions (accelcal_repro) and call the core's compiled kernels:
their disk cache must go stale when the core kernel they call changes, and their compiled and
reference forms agree."""

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from tests.test_kernels import both

pytest.importorskip("numba")

CALLEE = "from accelcal.kernels import jit\n\n@jit\ndef f(x):\n    return x + {step}\n"
CALLER = textwrap.dedent("""
    import callee
    from accelcal.kernels import jit
    from accelcal_repro.batista2011._shared_gain_kernels import _also_depends_on
    from callee import f

    @jit
    def g(x):
        return f(x) * 10

    if {depend}:
        _also_depends_on(g, callee.__file__)
    print(g(1), sum(g.stats.cache_hits.values()))
""")


def _run(folder):
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}  # cache beside the sources
    env["PYTHONPATH"] = os.pathsep.join([str(folder), *sys.path])
    out = subprocess.run([sys.executable, str(folder / "caller.py")], cwd=folder, env=env, capture_output=True,
                         text=True, check=True, timeout=300).stdout.split()
    return int(out[0]), int(out[1])


@pytest.mark.parametrize("depend", [False, True], ids=["numba_alone", "also_depends_on"])
def test_a_change_to_a_called_kernel_in_another_file_recompiles_the_caller(tmp_path, depend):
    (tmp_path / "callee.py").write_text(CALLEE.format(step=1))
    (tmp_path / "caller.py").write_text(CALLER.format(depend=depend))
    assert _run(tmp_path) == (20, 0)  # compiled and cached
    assert _run(tmp_path) == (20, 1)  # loaded from the cache
    (tmp_path / "callee.py").write_text(CALLEE.format(step=22))  # another size: another stamp at any clock
    result = _run(tmp_path)
    if depend:
        assert result == (230, 0)  # recompiled with the new callee
    else:
        assert result == (20, 1)  # numba alone serves the stale kernel: why the helper exists


def test_the_shared_gain_kernel_depends_on_the_core_filter_kernels():
    from accelcal import kernels

    previous = kernels.set_backend("numba")
    try:
        from accelcal_repro.batista2011 import _shared_gain_kernels as K
    finally:
        kernels.set_backend(previous)
    st = os.stat(K._FILTER_KERNELS.__file__)
    cache_file = getattr(getattr(K.shared_gain_block, "_cache", None), "_cache_file", None)
    if cache_file is None:
        pytest.skip("no writable numba cache folder here")
    assert cache_file._source_stamp[1] == (st.st_mtime, st.st_size)


def test_shared_gain_monte_carlo_agrees():
    from accelcal_repro.batista2011.montecarlo import filter_montecarlo, filter_scenario, run_streams
    from accelcal_repro.batista2011.trajectory import euler_sinusoid_attitude

    t = np.arange(2001) / 100.0
    att = euler_sinusoid_attitude(t, [0, 0, 0], [90, 45, 180], [0.03, 0.02, 0.01], [0, 45, 0], [0, 0, 0])
    sc = filter_scenario(att, [0.1, -0.05, 0.025], 0.0013, 0.05, 0.01, 9.81, [0.05, -0.03, 0.1])
    P0 = np.repeat([0.01**2, 0.2**2, 0.2**2], 3)
    a, b = both(lambda: filter_montecarlo(sc, run_streams(1, "f", range(6)), P0, record_every_s=0.37,
                                          summary_every_s=1.0, block=300, sub_block=17))
    cols = [c for c in a.runs.columns if c.startswith("e_")]
    np.testing.assert_array_equal(a.runs[["run", "t"]].to_numpy(), b.runs[["run", "t"]].to_numpy())
    np.testing.assert_allclose(a.runs[cols].to_numpy(), b.runs[cols].to_numpy(), rtol=0, atol=1e-11)
    np.testing.assert_allclose(a.moments["m2"], b.moments["m2"], rtol=1e-9, atol=1e-20)
