"""Kernels that live in the reproductions (accelcal_repro) and call the core's compiled kernels:
their disk cache must go stale when the core kernel they call changes."""

import os
import subprocess
import sys
import textwrap

import pytest

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
