"""Compiled kernels (numba) against the numpy reference implementations.

Every public function with a compiled path is run under both backends
(:func:`accelcal.kernels.set_backend`) on many random problems and on degenerate and
edge inputs: the results agree to rounding, or both raise the same typed error with the
same message.  Where the Gram-matrix route of the full LLS would lose accuracy the SVD
keeps (squared conditioning), the compiled path hands the problem to the SVD, as the
numpy route does.
"""

import os
import subprocess
import sys

import numpy as np
import pytest

from accelcal import kernels
from accelcal.als import full_als, full_als_batch
from accelcal.errors import AccelcalError
from accelcal.lls import bias_lls, full_lls
from accelcal.lls_batch import bias_lls_batch, full_lls_batch
from accelcal.simulation import random_directions, sample_truth, simulate_poses

pytestmark = pytest.mark.skipif(kernels._resolve("auto") != "numba",
                                reason="numba (the optional fast extra) is not installed: only the numpy path runs")

G = 9.8055


@pytest.fixture(autouse=True)
def _restore_backend():
    previous = kernels.choice()
    yield
    kernels.set_backend(previous)


def both(f, *args, **kwargs):
    """``(compiled, reference)``: the value or the raised AccelcalError of each backend."""
    out = []
    for be in ("numba", "numpy"):
        kernels.set_backend(be)
        try:
            out.append(f(*args, **kwargs))
        except AccelcalError as e:
            out.append(e)
    return tuple(out)


def assert_same_error_or_close(a, b, scale, rtol=1e-10):
    """Both raised the same error (class and message), or both returned estimates whose
    bias agrees to ``rtol * scale`` and whose M agrees to ``rtol`` (relative to |M|)."""
    if isinstance(a, Exception) or isinstance(b, Exception):
        assert type(a) is type(b) and str(a) == str(b), (a, b)
        return
    np.testing.assert_allclose(a.bias, b.bias, rtol=0, atol=rtol * scale)
    np.testing.assert_allclose(a.M, b.M, rtol=0, atol=rtol * np.abs(b.M).max())
    assert a.method == b.method and a.g == b.g
    np.testing.assert_array_equal(a.poses, b.poses)


def _problem(rng, n, noise, identity=False, offset=0.0, sens=1.0, hemisphere=False):
    tr = sample_truth(rng, 1)
    u = random_directions(rng, n)
    if hemisphere:
        u[:, 2] = np.abs(u[:, 2])
    M = np.eye(3) if identity else tr["M"][0]
    return simulate_poses(u, G, sens * M, tr["bias"][0] + offset, noise, rng)


def _random_problems(seed, count=150):
    """Poses of every kind the estimators meet: 4-200 poses, noise-free to 0.3 g, raw
    counts (offset 32768, 415 counts per m/s²), hemispheres, M = I."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        n = int(rng.choice([4, 6, 10, 11, 12, 16, 24, 40, 100, 200]))
        noise = float(rng.choice([0.0, 1e-7, 1e-5, 1e-3, 1e-2, 0.1, 3.0]))
        raw = rng.random() < 0.2
        yield _problem(rng, n, noise * (415 if raw else 1), identity=rng.random() < 0.3,
                       offset=32768.0 if raw else 0.0, sens=415.0 if raw else 1.0, hemisphere=rng.random() < 0.15)


def _degenerate(rng):
    """Inputs that must be refused or that sit at the edge of the fast routes."""
    z = _problem(rng, 24, 1e-4)
    a = rng.uniform(0, 2 * np.pi, 12)
    circle = np.column_stack([np.cos(a), np.sin(a), 0 * a])
    two_planes = G * np.vstack([circle, np.column_stack([np.cos(a), 0 * a, np.sin(a)])]) + 0.01
    near_plane = G * np.column_stack([np.cos(a), np.sin(a), 1e-3 * rng.normal(size=12)])
    near_plane = np.vstack([near_plane, near_plane * [1, -1, 1]])
    hyperboloid = (lambda h: np.column_stack([np.sqrt(25 + h**2) * np.cos(np.arange(12.0)),
                                              np.sqrt(25 + h**2) * np.sin(np.arange(12.0)), h]))(
        rng.uniform(-3, 3, 12))
    nan, inf, huge = z.copy(), z.copy(), z * 1e160
    nan[3, 1], inf[0, 0] = np.nan, np.inf
    return {
        "coplanar": G * circle[np.r_[:12, :12]] + rng.normal(size=(24, 3)) * 0,
        "two_great_circles": two_planes,
        "near_plane": near_plane,
        "one_axis": np.outer(np.linspace(-1, 1, 24), [1, 0, 0]) * G + 1e-3,
        "identical": np.tile(z[0], (24, 1)),
        "zeros": np.zeros((24, 3)),
        "hyperboloid": hyperboloid,
        "nan": nan, "inf": inf, "overflow": huge,
        "too_few": z[:3],
        "wrong_shape": z[:, :2],
        "list": z.tolist(),
        "fortran_order": np.asfortranarray(z),
        "strided": np.hstack([z, z])[:, ::2],
        "ints": np.round(z * 1000).astype(int),
        "raw_counts_far_offset": _problem(rng, 30, 0.05, offset=32768.0, sens=415.0),
        "noise_free_exact": _problem(rng, 10, 0.0),
    }


@pytest.mark.parametrize("seed", range(3))
def test_full_and_bias_lls_agree_on_random_problems(seed):
    for z in _random_problems(seed):
        scale = np.abs(z).max()
        for est in (full_lls, bias_lls):
            a, b = both(est, z, G)
            assert_same_error_or_close(a, b, scale)
            if not isinstance(a, Exception):
                assert a.lam == pytest.approx(b.lam, rel=1e-9, nan_ok=True)
                assert a.c == pytest.approx(b.c, rel=1e-9, abs=1e-9 * scale**2, nan_ok=True)


@pytest.mark.parametrize("est", [full_lls, bias_lls, full_als])
def test_edge_inputs_give_the_same_result_or_error(est):
    rng = np.random.default_rng(7)
    for name, z in _degenerate(rng).items():
        for g in (G, -1.0, float("nan"), "9.81", None):
            a, b = both(est, z, g)
            scale = float(np.nanmax(np.abs(np.asarray(z, float)[np.isfinite(np.asarray(z, float))]), initial=1.0))
            assert_same_error_or_close(a, b, scale, rtol=1e-9)


def test_batches_agree_with_the_reference_trial_by_trial():
    rng = np.random.default_rng(11)
    for n, noise in ((10, 1e-4), (24, 1e-3), (24, 0.3), (100, 1e-7), (12, 1.0)):
        T = 300
        tr = sample_truth(rng, T)
        u = random_directions(rng, n, T)
        u[:20, :, 2] = np.abs(u[:20, :, 2])  # hemispheres: the SVD fallback inside a batch
        zf = simulate_poses(u, G, tr["M"], tr["bias"], noise, rng)
        zb = simulate_poses(u, G, np.eye(3), tr["bias"], noise, rng)
        zf[5] = G * np.column_stack([np.cos(np.arange(n)), np.sin(np.arange(n)), 0 * np.arange(n)])  # coplanar
        zb[6] = zb[6, :1]  # all poses equal: singular bias-only normal equations
        for est, z in ((full_lls_batch, zf), (bias_lls_batch, zb)):
            a, b = both(est, z, G)
            np.testing.assert_array_equal(a.valid, b.valid)
            np.testing.assert_allclose(a.bias, b.bias, rtol=0, atol=1e-10 * G)
            np.testing.assert_allclose(a.M, b.M, rtol=0, atol=1e-10)
            assert np.isnan(a.bias[~a.valid]).all()
        assert not bias_lls_batch(zb, G).valid[6]


def test_batches_raise_the_same_errors():
    rng = np.random.default_rng(3)
    z = simulate_poses(random_directions(rng, 24, 5), G, np.eye(3), np.zeros(3), 1e-3, rng)
    bad = {"nan": z.copy(), "shape": z[:, :, :2], "few": z[:, :3], "2d": z[0]}
    bad["nan"][2, 3, 1] = np.nan
    for est in (full_lls_batch, bias_lls_batch, full_als_batch):
        for name, zz in bad.items():
            a, b = both(est, zz, G)
            assert isinstance(a, AccelcalError) and type(a) is type(b) and str(a) == str(b), (est, name, a, b)
        a, b = both(est, z, -1.0)
        assert isinstance(a, AccelcalError) and type(a) is type(b) and str(a) == str(b)


@pytest.mark.parametrize("noise", [1e-6, 1e-4, 1e-2, 0.3])
def test_als_agrees_with_known_and_estimated_noise(noise):
    rng = np.random.default_rng(int(noise * 1e7) + 5)
    for _ in range(10):
        z = _problem(rng, int(rng.choice([12, 24, 60])), noise)
        for ns in (noise, None):
            a, b = both(full_als, z, G, ns)
            if ns is not None or isinstance(a, Exception):
                assert_same_error_or_close(a, b, G, rtol=1e-9)
                continue
            # σ² is the root of λmin(Ψ(σ²)): both eigen-solvers are accurate to eps |Ψ|, which
            # moves the root by ~1e-16 in scaled units; the estimate moves far less than the noise
            k2 = np.mean(np.sum(z**2, axis=1))
            assert abs(a.noise_var - b.noise_var) / k2 < 1e-13
            np.testing.assert_allclose(a.bias, b.bias, rtol=0, atol=1e-6 * noise)
            np.testing.assert_allclose(a.M, b.M, rtol=0, atol=1e-6 * noise / G)
            np.testing.assert_allclose(a.singular_values**2, b.singular_values**2, rtol=0, atol=1e-12)


def test_als_batch_agrees_with_single_calls():
    rng = np.random.default_rng(2)
    T = 60
    tr = sample_truth(rng, T)
    z = simulate_poses(random_directions(rng, 16, T), G, tr["M"], tr["bias"], 0.05, rng)
    z[3] = G * np.column_stack([np.cos(np.arange(16)), np.sin(np.arange(16)), 0 * np.arange(16)])
    for ns in (0.05, None):
        a, b = both(full_als_batch, z, G, ns)
        np.testing.assert_array_equal(a.status, b.status)
        np.testing.assert_array_equal(a.valid, b.valid)
        tol = 1e-10 if ns else 1e-6 * 0.05
        np.testing.assert_allclose(a.bias, b.bias, rtol=0, atol=tol)
        assert a.status[3] == "DegeneratePosesError"
        kernels.set_backend("numba")
        for t in range(T):
            try:
                r = full_als(z[t], G, ns)
            except AccelcalError as e:
                assert a.status[t] == type(e).__name__
                continue
            np.testing.assert_allclose(a.bias[t], r.bias, rtol=0, atol=1e-12)


def test_gram_route_hands_ill_conditioned_problems_to_the_svd(monkeypatch):
    """Raw counts far from the origin (σ0/σ8 in the thousands) and near-degenerate pose
    sets: forming XᵀX would square the condition number; the compiled route declines and
    the SVD computes (the same object as the reference returns)."""
    from accelcal import lls

    calls = []
    svd = lls._full_lls_svd
    monkeypatch.setattr(lls, "_full_lls_svd", lambda z, g: calls.append(1) or svd(z, g))
    rng = np.random.default_rng(5)
    ill = {"raw_counts": _problem(rng, 30, 0.05, offset=32768.0, sens=415.0),
           "hemisphere_10": _problem(rng, 10, 1e-3, hemisphere=True),
           "high_noise": _problem(rng, 24, 0.3 * G)}
    for name, z in ill.items():
        calls.clear()
        r, ref = both(full_lls, z, G)  # the compiled backend first
        assert calls[:1] == [1], name
        assert_same_error_or_close(r, ref, np.abs(z).max(), rtol=0)
    # and on the problems it is meant for it takes the fast route
    calls.clear()
    kernels.set_backend("numba")
    full_lls(_problem(rng, 24, 1e-4), G)
    assert calls == []


def test_gram_route_without_its_safeguards_loses_accuracy(monkeypatch):
    """Switch the gap requirement and the eigenvector bound off (they are kernel
    arguments): the raw-count problem then goes through XᵀX and loses accuracy the SVD
    keeps, so the certification is what keeps the compiled route as accurate as the SVD."""
    from accelcal import lls

    rng = np.random.default_rng(8)
    tr = sample_truth(rng, 1)
    Mc = np.array([415.0, 413.0, 415.0])[:, None] * tr["M"][0]
    bc = np.array([32768.0, 32700.0, 32800.0])
    z = simulate_poses(random_directions(rng, 30), G, Mc, bc, 0.0, rng)
    kernels.set_backend("numba")
    exact = lls._full_lls_svd(z, G)
    monkeypatch.setattr(lls, "MIN_GAP", 1e-12)
    monkeypatch.setattr(lls, "EIGVEC_TOL", 1.0)
    monkeypatch.setattr(lls, "_full_lls_svd", None)  # must not be needed now
    unsafe = full_lls(z, G)
    assert np.abs(unsafe.bias - bc).max() > 100 * np.abs(exact.bias - bc).max()


# ----------------------------------------------------------------------------- filters
def _filter_inputs(rng, n=1500, dt=0.01):
    t = np.arange(n) * dt
    w = 0.3 * np.column_stack([np.sin(0.3 * t), np.cos(0.2 * t), np.sin(0.1 * t + 1)])
    w[:40] *= 1e-4  # rotation angle per step below the series threshold
    a = rng.normal(size=(n, 3)) * 0.01 + [0, 0, -9.81]
    y = rng.normal(size=(n, 3)) * 0.01
    return t, a, w, y


@pytest.mark.parametrize("record_every", [1, 7])
def test_kalman_filter_and_covariance_sequence_agree(record_every):
    from accelcal.batista.filter import covariance_sequence, kalman_filter

    rng = np.random.default_rng(record_every)
    t, a, w, y = _filter_inputs(rng)
    x0 = np.concatenate([y[0], -a[0], np.zeros(3)])
    P0 = np.repeat([0.01**2, 0.2**2, 0.2**2], 3)
    full_P0 = np.diag(P0) + 1e-5 * np.ones((9, 9))
    for p0, theta, xi in ((P0, 0.1, (1e-3, 1e-4, 1e-5)), (full_P0, np.diag([0.1, 0.2, 0.05]), (1e-2, 0.0, 1e-6))):
        fa, fb = both(kalman_filter, t, a, w, y, x0, p0, xi, theta, record_every)
        np.testing.assert_array_equal(fa.t, fb.t)
        np.testing.assert_allclose(fa.x, fb.x, rtol=0, atol=1e-11)
        np.testing.assert_allclose(fa.sigma, fb.sigma, rtol=1e-11)
        ca, cb = both(covariance_sequence, t, w, p0, xi, theta, return_covariance=True)
        for u, v in zip(ca, cb):
            np.testing.assert_allclose(u, v, rtol=1e-11, atol=1e-16)


def test_filters_raise_the_same_errors():
    from accelcal.batista.filter import covariance_sequence, kalman_filter

    rng = np.random.default_rng(0)
    t, a, w, y = _filter_inputs(rng, 50)
    x0, P0 = np.zeros(9), np.ones(9)
    nan = a.copy()
    nan[4, 2] = np.nan
    for args in ((t, a, w, y, np.zeros(6), P0), (t, a, w, y, x0, np.ones(8)), (t, a, w, y, x0, P0, (1, 2)),
                 (t, nan, w, y, x0, P0), (t[::-1], a, w, y, x0, P0), (t, a[:10], w, y, x0, P0),
                 (t, a, w, y, x0, P0, (1e-3, 1e-4, 1e-5), np.ones(2))):
        ea, eb = both(kalman_filter, *args)
        assert isinstance(ea, AccelcalError) and type(ea) is type(eb) and str(ea) == str(eb), args
    ea, eb = both(covariance_sequence, t, w, np.ones(5))
    assert isinstance(ea, AccelcalError) and type(ea) is type(eb) and str(ea) == str(eb)


@pytest.mark.parametrize("variant", [{}, {"accel_formula": "eq13"}, {"accel_feedback": False},
                                     {"estimate_gyro_z": False, "update_gyro": False}])
def test_tereshkov_estimator_agrees_also_in_chunks(variant):
    from accelcal.tereshkov.estimator import TereshkovParams, concat_results, run_estimator

    rng = np.random.default_rng(4)
    R, n, dt = 3, 6000, 0.04
    tt = np.arange(n) * dt
    yaw = np.where((tt % 120) < 40, 0.0, np.where((tt % 120) < 80, 0.2, -0.15))
    gyro = np.zeros((R, n, 3))
    gyro[..., 2] = yaw
    gyro += rng.normal(size=gyro.shape) * 1e-3 + [1e-3, -2e-3, 5e-4]
    accel = rng.normal(size=(R, n, 3)) * 0.01 + [0.05, -0.03, -9.80665]
    f_ext = np.zeros((R, n, 3))
    f_ext[..., 1], f_ext[..., 2] = 5.0 * yaw, -9.80665
    course = np.cumsum(yaw) * dt + np.zeros((R, 1))
    speed = np.where(tt < 20, 0.5, 5.0) + np.zeros((R, 1))
    p = TereshkovParams(**variant)
    out = {}
    for be in ("numba", "numpy"):
        kernels.set_backend(be)
        parts, state = [], None
        for s in (slice(0, 1700), slice(1700, 4000), slice(4000, n)):  # chunks continue the state
            r, state = run_estimator(gyro[:, s], accel[:, s], f_ext[:, s], course[:, s], speed[:, s], dt, p, state,
                                     record_every=25)
            parts.append(r)
        out[be] = concat_results(parts), state
    (a, sa), (b, sb) = out["numba"], out["numpy"]
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.mode, b.mode)
    for name in ("gyro_bias", "accel_bias", "u", "C", "mode_time", "gyro_time", "accel_time"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-9, atol=1e-11, err_msg=name)
    assert a.accel_time.max() > 0 or not p.update_accel
    for name in ("C", "gyro_bias", "accel_bias", "rate_z", "mode_time", "gyro_time", "accel_time"):
        np.testing.assert_allclose(getattr(sa, name), getattr(sb, name), rtol=1e-9, atol=1e-11, err_msg=name)
    np.testing.assert_array_equal(sa.mode, sb.mode)
    assert sa.k == sb.k == n


# ----------------------------------------------------------------------------- cache
def test_no_writable_cache_compiles_in_memory_with_one_warning(tmp_path):
    """With no writable cache folder (only the user-provided locator, pointing at a file)
    the kernels still run, compiled in memory, and say so once."""
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(blocker / "cache"),
               NUMBA_CACHE_LOCATOR_CLASSES="UserProvidedCacheLocator", ACCELCAL_KERNELS="numba")
    code = ("import warnings, numpy as np\n"
            "from accelcal import bias_lls_batch\n"
            "with warnings.catch_warnings(record=True) as w:\n"
            "    warnings.simplefilter('always')\n"
            "    z = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1.0]])\n"
            "    r = bias_lls_batch(z[None] + 0.1, 1.0)\n"
            "print(np.abs(r.bias - 0.1).max() < 1e-12, sum('no writable numba cache' in str(x.message) for x in w))\n")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["True", "1"]


def test_processes_starting_together_compile_each_kernel_once(tmp_path):
    """Two processes that call the same kernel at once on an empty disk cache: one compiles
    it, the other waits and loads what the first saved (kernels._one_compiler_at_a_time);
    both get the same numbers."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), ACCELCAL_KERNELS="numba")
    code = ("import numpy as np\n"
            "from accelcal import bias_lls_batch\n"
            "from accelcal._lls_kernels import bias_lls_batch as kernel\n"
            "z = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1.0]])\n"
            "r = bias_lls_batch(z[None] + 0.1, 1.0)\n"
            "s = kernel.stats\n"
            "print(sum(s.cache_misses.values()), sum(s.cache_hits.values()), repr(r.bias[0, 0]))\n")
    procs = [subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True) for _ in range(2)]
    outs = [p.communicate(timeout=600) for p in procs]
    assert all(p.returncode == 0 for p in procs), [err for _, err in outs]
    misses, hits, values = zip(*(out.split() for out, _ in outs))
    assert sorted(misses) == ["0", "1"] and sorted(hits) == ["0", "1"], outs  # one compiled, one loaded
    assert values[0] == values[1]


def test_backend_choice_from_the_environment():
    assert kernels._resolve("numpy") == "numpy"
    assert kernels._resolve("auto") == "numba"
    with pytest.raises(ValueError, match="ACCELCAL_KERNELS"):
        kernels._resolve("fortran")


def test_auto_loads_numba_for_batches_and_filters_not_for_one_problem():
    """Under ``auto`` a one-off single-problem call stays in numpy (no numba start-up);
    a batched call loads the kernels, and single-problem calls use them from then on."""
    code = ("import sys, numpy as np\n"
            "from accelcal import full_lls, bias_lls, full_lls_batch, kernels\n"
            "from accelcal.simulation import random_directions, simulate_poses\n"
            "rng = np.random.default_rng(0)\n"
            "z = simulate_poses(random_directions(rng, 24), 9.8, np.eye(3), np.full(3, 0.01), 1e-4, rng)\n"
            "full_lls(z, 9.8); bias_lls(z, 9.8)\n"
            "before = 'numba' in sys.modules\n"
            "full_lls_batch(z[None], 9.8)\n"
            "print(kernels.choice(), before, 'numba' in sys.modules, kernels.compiled('_lls_kernels', single=True) is not None)\n")
    env = {k: v for k, v in os.environ.items() if k != "ACCELCAL_KERNELS"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["auto", "False", "True", "True"]


def test_auto_switches_one_problem_calls_to_the_kernels_once_they_would_have_repaid_the_start_up():
    """Under ``auto`` a process's single-problem solves run in numpy until the time their
    compiled forms would have saved (accelcal.lls.SAVES_S per call; ALS adds its LLS's)
    reaches STARTUP_S, then load the kernels by themselves (numba imported in that call)
    and run compiled; the forced backends start compiled or stay in numpy."""
    code = ("import sys, numpy as np\n"
            "from accelcal import full_lls, bias_lls, full_als, kernels, lls\n"
            "from accelcal.simulation import random_directions, simulate_poses\n"
            "kernels.STARTUP_S = 3.5 * lls.SAVES_S['full_lls']\n"
            "rng = np.random.default_rng(0)\n"
            "z = simulate_poses(random_directions(rng, 24), 9.8, np.eye(3), np.full(3, 0.01), 1e-4, rng)\n"
            "def run(calls):\n"
            "    seen = []\n"
            "    for f in calls:\n"
            "        f(z, 9.8); seen.append(int('numba' in sys.modules))\n"
            "    return ''.join(map(str, seen))\n"
            "print(kernels.choice(), run([WHICH] * 20), sorted(kernels._loaded))\n")
    outs = {}
    for choice, which in (("auto", "full_lls"), ("auto", "bias_lls"), ("auto", "full_als"), ("numpy", "full_lls"),
                          ("numba", "bias_lls")):
        env = dict(os.environ, ACCELCAL_KERNELS=choice)
        outs[choice, which] = subprocess.run([sys.executable, "-c", code.replace("WHICH", which)], env=env,
                                             capture_output=True, text=True, check=True).stdout.split()
    from accelcal.lls import SAVES_S

    # full LLS: 3 calls in numpy (3 x 35 µs < 3.5 x 35 µs), the 4th loads the kernels
    assert outs["auto", "full_lls"] == ["auto", "0" * 3 + "1" * 17, "['_lls_kernels']"]
    # bias-only LLS saves less per call: more calls before the switch
    n = int(np.ceil(3.5 * SAVES_S["full_lls"] / SAVES_S["bias_lls"]))
    assert outs["auto", "bias_lls"] == ["auto", "0" * (n - 1) + "1" * (21 - n), "['_lls_kernels']"]
    # ALS adds its own saving and its LLS's: two calls add 2 x (35 + 22) = 114 µs < 122.5, the third's LLS crosses
    assert outs["auto", "full_als"] == ["auto", "00" + "1" * 18, "['_lls_kernels']"]
    assert outs["numpy", "full_lls"] == ["numpy", "0" * 20, "[]"]
    assert outs["numba", "bias_lls"] == ["numba", "1" * 20, "['_lls_kernels']"]


def test_the_switch_adds_up_the_calls_savings_not_a_clock(monkeypatch):
    """In process: numpy until the savings reach STARTUP_S, then the kernels."""
    monkeypatch.setattr(kernels, "STARTUP_S", 3.0)
    monkeypatch.setattr(kernels, "_loaded", {})
    kernels.set_backend(None)
    kernels.set_backend("auto")
    got = [kernels.compiled("_lls_kernels", single=True, saves_s=1.0) is not None for _ in range(5)]
    assert got == [False, False, True, True, True]  # 1, 2 < 3; the third reaches it
    assert kernels.compiled("_lls_kernels") is not None  # batched callers: at once
    kernels.set_backend(None)  # the sum starts again with the choice
    kernels.set_backend("auto")
    monkeypatch.setattr(kernels, "_loaded", {})
    assert kernels.compiled("_lls_kernels", single=True) is None  # a caller that saves nothing never switches


# ----------------------------------------------------------------------------- discrepancy fits
def _pose_set(seed, n=30):
    """Raw-count pose means (415 counts per m/s², offset 32768) with a quadratic term, time and
    temperature: the benchmark's kind of problem."""
    from accelcal.discrepancy.fit import forward, pose_data

    rng = np.random.default_rng(seed)
    tr = sample_truth(rng, 1)
    M, bias = 415.0 * tr["M"][0], 32768.0 + 300 * rng.standard_normal(3)
    t = np.sort(rng.uniform(0, 250, n))
    temp = 25 + 5 * np.sin(t / 40)
    z = forward(G * random_directions(rng, n), M, bias, {"quadratic": 2e-4 * rng.standard_normal(3)})
    se = np.full((n, 3), 0.14)
    return pose_data(z + se * rng.standard_normal((n, 3)), G, se, t, temp)


@pytest.mark.parametrize("effects", [(), ("quadratic",), ("cubic",), ("bias_drift",), ("temperature",),
                                     ("temperature_scale",), ("quadratic", "temperature", "bias_drift")])
def test_discrepancy_fits_agree(effects):
    """The extended model, its Levenberg–Marquardt fit and the leave-one-pose-out refits: the
    compiled kernels against the numpy reference (NaN rows where the model cannot be inverted)."""
    from accelcal.discrepancy.fit import evaluate_batch, fit, lopo, n_parameters

    rng = np.random.default_rng(len(effects))
    for seed in range(4):
        data = _pose_set(seed)
        base = fit(data)
        P = np.tile(np.concatenate([base.p, np.zeros(n_parameters(effects) - 9)]), (6, 1))
        P[:, 3:] += 1e-3 * rng.standard_normal((6, P.shape[1] - 3)) * (P[:, 3:] != 0)
        P[:, 9:] += 1e-5 * rng.standard_normal((6, P.shape[1] - 9))
        P[2, 7:9] = [1.2, 1.0]  # angles that make M invalid
        (ra, Ja, xa), (rb, Jb, xb) = both(evaluate_batch, P, data, effects)
        np.testing.assert_array_equal(np.isnan(ra), np.isnan(rb))
        ok = ~np.isnan(rb[:, 0])
        np.testing.assert_allclose(ra[ok], rb[ok], rtol=0, atol=1e-12)
        np.testing.assert_allclose(Ja[ok], Jb[ok], rtol=1e-10, atol=1e-12 * np.abs(Jb[ok]).max())
        np.testing.assert_allclose(xa[ok], xb[ok], rtol=1e-12)
        # the fits stop once a step predicts a χ² decrease below 1e-10: rounding can move that
        # stop by an iteration, i.e. the residuals by up to ~1e-5 noise units
        fa, fb = both(fit, data, effects, p0=base.p)
        np.testing.assert_allclose(fa.chi2, fb.chi2, rtol=1e-9)
        np.testing.assert_allclose(fa.residuals / fa.sigma, fb.residuals / fb.sigma, rtol=0, atol=1e-4)
        la, lb = both(lopo, fb, data)
        np.testing.assert_allclose(la, lb, rtol=0, atol=1e-4)


def test_discrepancy_white_loop_agrees():
    from accelcal.discrepancy.detect import discrepancy
    from accelcal.discrepancy.rules import Rules

    rules = Rules(null="white")
    for seed in range(3):
        a, b = both(discrepancy, _pose_set(seed), rules)
        assert a.outcome == b.outcome and a.effects == b.effects
        for ca, cb in zip(a.candidates, b.candidates):
            assert (ca.effect, ca.identifiable, ca.passed, ca.named) == (cb.effect, cb.identifiable, cb.passed, cb.named)
            np.testing.assert_allclose(ca.p_value, cb.p_value, rtol=1e-7)


@pytest.mark.parametrize("rho", [0.0, 0.3, 0.999, 0.99999])
def test_gauss_markov_simulation_is_bit_for_bit_lfilter(rho):
    """The compiled AR(1) recursion gives exactly scipy.signal.lfilter's numbers, so the
    simulated noise (and every benchmark table built on it) does not depend on the path."""
    from scipy.signal import lfilter

    from accelcal.noise import _fast, simulate_noise

    e = np.random.default_rng(7).standard_normal((5000, 3))
    assert np.array_equal(_fast.ar1(e, rho), lfilter([1.0], [1.0, -rho], e, axis=0))
    terms = {"white": 1e-3, "gauss_markov": (2e-3, 30.0)}
    a, b = both(lambda: simulate_noise(np.random.default_rng(3), 20000, 100.0, terms, size=3))
    assert np.array_equal(a, b)
