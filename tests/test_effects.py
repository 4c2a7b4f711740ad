"""The effect table and the extended model it declares, implemented once.

A conformance suite over every effect of :data:`accelcal.effects.EFFECTS`, and over two
effects this module adds to the table (a fourth power, and a quadratic scaled by the
temperature: effects of the existing kinds that need nothing but their entry):

* the forward model followed by the inverse :meth:`Calibration.apply` uses is the
  identity, and the fits' pose residuals vanish at the parameters that made the data;
* the analytic Jacobian of the residuals is their finite-difference derivative;
* the compiled kernels give the numpy reference's numbers (when numba is installed);
* what lists the effects (schema enum, command-line help, figure labels) is the table.

Parameter sizes come from the entry (power, covariate range), so a new entry runs
through the suite as it is.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import yaml

from accelcal import kernels
from accelcal.calibration import Calibration, EffectTerm, ExtendedCalibration
from accelcal.discrepancy.fit import evaluate, evaluate_batch, fit, forward, lopo, pose_data
from accelcal.effects import EFFECT_IDS, EFFECTS, TEMPERATURE, TIME, Effect
from accelcal.errors import AccelcalError
from accelcal.model import m_from_params
from accelcal.simulation import random_directions

G = 9.80665
REPO = Path(__file__).resolve().parents[1]
#: Effects of the existing kinds that only this test declares.
SYNTHETIC = (
    dataclasses.replace(EFFECTS["cubic"], id="quartic", power=4, symbol="q", unit="1/G^3", label="quartic",
                        description="per-axis nonlinearity x_j + q_j x_j^4"),
    Effect(id="temperature_quadratic", kind="polynomial", power=2, covariate=TEMPERATURE, symbol="kT",
           unit="1/(G degC)", label="temp. quadratic", description="quadratic term linear in temperature"),
)
ALL = (*EFFECT_IDS, *(e.id for e in SYNTHETIC))
BACKENDS = ("numpy", "numba") if kernels._resolve("auto") == "numba" else ("numpy",)
#: Time [s] and temperature [°C] ranges of the simulated sessions, and their centres.
T_RANGE, TEMP_RANGE, T_REF, TEMP_REF = (0.0, 600.0), (18.0, 30.0), 310.0, 23.5


@pytest.fixture(autouse=True)
def _synthetic_effects(monkeypatch):
    """The synthetic effects in the table (only while a test runs), and the kernel choice restored."""
    for e in SYNTHETIC:
        monkeypatch.setitem(EFFECTS, e.id, e)
    previous = kernels.choice()
    yield
    kernels.set_backend(previous)


def _size(eid: str, rel: float = 1e-3) -> float:
    """A parameter size whose term moves ``z`` by about ``rel`` g at |x| = g and the largest
    covariate of the session (large enough to matter, small enough for a monotonic P)."""
    e = EFFECTS[eid]
    c = {None: 1.0, TIME: max(abs(v - T_REF) for v in T_RANGE),
         TEMPERATURE: max(abs(v - TEMP_REF) for v in TEMP_RANGE)}[e.covariate]
    return rel * G / (G ** e.power * c)


def _params(rng, effects):
    return {e: _size(e) * rng.uniform(0.5, 1.5, EFFECTS[e].size) * rng.choice([-1, 1], EFFECTS[e].size)
            for e in effects}


def _session(rng, n, at_rest: bool):
    x = G * random_directions(rng, n)
    if not at_rest:
        x = x * rng.uniform(0.5, 1.5, (n, 1))
    return x, np.sort(rng.uniform(*T_RANGE, n)), np.sort(rng.uniform(*TEMP_RANGE, n))


M = m_from_params([0.01, -0.02, 0.005], [0.002, -0.001, 0.003])
B = np.array([0.1, -0.05, 0.2])


def _poses(rng, effects, n=40):
    """Noise-free pose means of the model with ``effects`` and the parameter vector that made them."""
    x, t, temp = _session(rng, n, at_rest=True)
    params = _params(rng, effects)
    z = forward(x, M, B, params, dt=t - t.mean(), dtemp=temp - temp.mean())
    s, th = [0.01, -0.02, 0.005], [0.002, -0.001, 0.003]
    p = np.concatenate([B, s, th, *params.values()])
    return pose_data(z, G, np.full((n, 3), 1e-3), t, temp), p, x


@pytest.mark.parametrize("eid", ALL)
def test_forward_then_apply_is_the_identity(eid):
    rng = np.random.default_rng(ALL.index(eid))
    x, t, temp = _session(rng, 500, at_rest=False)
    params = _params(rng, [eid])
    z = forward(x, M, B, params, dt=t - T_REF, dtemp=temp - TEMP_REF)
    ref = {TIME: T_REF, TEMPERATURE: TEMP_REF}.get(EFFECTS[eid].covariate)
    cal = ExtendedCalibration(bias=B, M=M, g=G, unit="m/s^2", input_unit="m/s^2",
                              effects=(EffectTerm(eid, params[eid], ref),))
    np.testing.assert_allclose(cal.apply(z, t=t, temp=temp), x, rtol=0, atol=1e-12 * G)
    back = Calibration.from_json(cal.to_json())
    np.testing.assert_array_equal(back.apply(z, t=t, temp=temp), cal.apply(z, t=t, temp=temp))
    assert np.max(np.abs(cal.apply(z, t=t, temp=temp, effects=False) - x)) > 1e-4 * G  # the effect matters


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("eid", ALL)
def test_the_fit_residual_inverts_the_forward_model(eid, backend):
    """At the parameters that made them, the fits see the pose means as exact: zero
    residuals and the true specific force (one effect, and with every other effect too)."""
    kernels.set_backend(backend)
    rng = np.random.default_rng(10 + ALL.index(eid))
    for effects in ([eid], [e for e in ALL if e != eid] + [eid]):
        data, p, x = _poses(rng, effects)
        r, _, x_fit = evaluate(p, data, effects)
        np.testing.assert_allclose(r, 0, atol=1e-12 * G)
        np.testing.assert_allclose(x_fit, x, rtol=0, atol=1e-12 * G)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("eid", ALL)
def test_the_jacobian_is_the_derivative_of_the_residual(eid, backend):
    kernels.set_backend(backend)
    rng = np.random.default_rng(20 + ALL.index(eid))
    effects = ["quadratic", "bias_drift", eid] if eid not in ("quadratic", "bias_drift") else [eid]
    data, p, _ = _poses(rng, effects)
    p = p + 1e-3 * np.abs(p) * rng.standard_normal(p.size)  # away from the exact fit
    _, J, _ = evaluate(p, data, effects)
    for k in range(p.size):
        h = 1e-6 * G / max(np.max(np.abs(J[:, k])), 1e-300)  # moves r by about 1e-6 g
        up, down = p.copy(), p.copy()
        up[k] += h
        down[k] -= h
        fd = (evaluate(up, data, effects, jacobian=False)[0] - evaluate(down, data, effects, jacobian=False)[0]) / (2 * h)
        np.testing.assert_allclose(J[:, k], fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(J[:, k])),
                                   err_msg=f"column {k} of {effects}")


@pytest.mark.skipif(BACKENDS == ("numpy",), reason="numba (the fast extra) is not installed")
@pytest.mark.parametrize("eid", ALL)
def test_compiled_equals_numpy(eid):
    rng = np.random.default_rng(30 + ALL.index(eid))
    effects = ["temperature", eid] if eid != "temperature" else [eid]
    data, p, _ = _poses(rng, effects)
    noisy = pose_data(data.z + 1e-3 * rng.standard_normal(data.z.shape), G, data.mean_std, data.t, data.temp)
    P = np.tile(p, (5, 1)) * (1 + 1e-3 * rng.standard_normal((5, p.size)))
    out = {}
    for be in ("numpy", "numba"):
        kernels.set_backend(be)
        f = fit(noisy, effects, p0=p[:9])
        out[be] = evaluate_batch(P, data, effects), f, lopo(out["numpy"][1] if out else f, noisy)
    (ra, Ja, xa), fa, la = out["numba"]
    (rb, Jb, xb), fb, lb = out["numpy"]
    np.testing.assert_allclose(ra, rb, rtol=0, atol=1e-12 * G)
    np.testing.assert_allclose(Ja, Jb, rtol=1e-10, atol=1e-12 * np.abs(Jb).max())
    np.testing.assert_allclose(xa, xb, rtol=1e-13)
    np.testing.assert_allclose(fa.chi2, fb.chi2, rtol=1e-9)
    np.testing.assert_allclose(fa.p, fb.p, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(la, lb, rtol=0, atol=1e-4)


@pytest.mark.parametrize("eid", [e.id for e in SYNTHETIC])
def test_a_new_entry_is_fitted_and_applied_from_the_table_alone(eid):
    """A synthetic effect hidden in noisy pose means: the fit recovers it within its
    standard errors, and the calibration made from the fit inverts the model."""
    rng = np.random.default_rng(40 + ALL.index(eid))
    data, p, x = _poses(rng, [eid], n=60)
    noise = 1e-4 * G
    noisy = pose_data(data.z + noise * rng.standard_normal(data.z.shape), G, np.full(data.z.shape, noise), data.t,
                      data.temp)
    f = fit(noisy, [eid])
    se = f.standard_errors(scaled=False)
    assert np.all(np.abs(f.block(eid) - p[9:]) < 5 * se[9:]), (f.block(eid), p[9:], se[9:])
    assert np.all(np.abs(p[9:]) > 5 * se[9:])  # and the effect was there to be seen


def test_the_loop_names_a_new_entry():
    """The discrepancy loop, given the table's candidates and a fourth power, names the
    fourth power hidden in noisy pose means."""
    from accelcal.discrepancy.detect import Rules, discrepancy

    rng = np.random.default_rng(3)
    n = 60
    x, t, temp = _session(rng, n, at_rest=True)
    se = np.full((n, 3), 1e-3)
    z = forward(x, np.eye(3), np.zeros(3), {"quartic": 1e-6 * np.array([1.0, -1.0, 1.0])})  # 9 noise units at g
    data = pose_data(z + se * rng.standard_normal((n, 3)), G, se, t, temp)
    result = discrepancy(data, Rules(null="white", candidates=(*EFFECT_IDS, "quartic")))
    assert result.effects == ("quartic",)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_fourth_power_is_modelled_as_a_fourth_power(backend):
    """The residual paths once modelled every power but 1 and 2 as a cube (while the
    forward model and the Jacobian used the power): pose means made with a fourth-power
    term then had residuals at the parameters that made them, and a Jacobian that was
    not their derivative.  Now the same terms everywhere."""
    kernels.set_backend(backend)
    rng = np.random.default_rng(50)
    data, p, x = _poses(rng, ["quartic"])
    r, J, x_fit = evaluate(p, data, ["quartic"])
    np.testing.assert_allclose(r, 0, atol=1e-12 * G)
    np.testing.assert_allclose(x_fit, x, rtol=0, atol=1e-12 * G)
    v = x / np.linalg.norm(x, axis=1, keepdims=True) / (1 + 4 * p[9:] * x ** 3)  # x̂ / P'(x)
    np.testing.assert_allclose(J[:, 9:], -v * x ** 4, rtol=1e-12)


def test_the_table_refuses_what_the_model_cannot_represent():
    ok = dict(id="e", kind="polynomial", power=2, covariate=None, symbol="e", unit="1/G", label="e", description="")
    Effect(**ok)
    for bad, why in [({"kind": "multiplicative"}, "kind"), ({"covariate": "humidity"}, "covariate"),
                     ({"kind": "additive"}, "additive"), ({"kind": "additive", "power": 0}, "additive"),
                     ({"power": 1}, "scale factor"), ({"power": 0, "covariate": TIME}, "polynomial"),
                     ({"kind": "harmonic", "power": 3}, "harmonic"),
                     ({"kind": "harmonic", "covariate": TEMPERATURE}, "harmonic")]:
        with pytest.raises(AccelcalError, match=why):
            Effect(**{**ok, **bad})


def test_a_missing_covariate_is_one_error_on_both_paths():
    rng = np.random.default_rng(60)
    data, p, _ = _poses(rng, ["temperature"])
    no_temp = pose_data(data.z, G, data.mean_std, data.t)
    for be in BACKENDS:
        kernels.set_backend(be)
        with pytest.raises(AccelcalError, match="temperature needs the temperature of every row"):
            evaluate(p, no_temp, ["temperature"])


def test_the_schema_lists_the_table():
    schema = yaml.safe_load((REPO / "workflow" / "schemas" / "discrepancy.schema.yaml").read_text())
    assert schema["$defs"]["effect"]["enum"] == list(EFFECT_IDS)


def test_the_command_line_help_lists_the_table(capsys):
    from accelcal.cli import main

    with pytest.raises(SystemExit):
        main(["discrepancy", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert f"candidate effects ({', '.join(EFFECT_IDS)})" in text


@pytest.mark.parametrize("eid", ALL)
def test_the_detectable_size_in_the_data_unit_is_the_model_s_own_sensitivity(eid):
    """The identifiability check's data-unit size per unit parameter (the MDE's scale) is
    the change of the pose means the forward model makes: ``|∂z_i/∂c_j|``, covariate included."""
    from accelcal.discrepancy.identifiability import pose_mean_change

    rng = np.random.default_rng(100 + ALL.index(eid))
    data, p, x = _poses(rng, [], n=30)
    base = fit(data)
    dt, dtemp = data.t - data.t.mean(), data.temp - data.temp.mean()
    k = EFFECTS[eid].size
    zero = {eid: np.zeros(k)}
    z0 = forward(base.x, base.M, base.bias, zero, dt=dt, dtemp=dtemp)
    h = _size(eid, 1e-6)
    expected = np.empty((len(data), k))
    for j in range(k):
        step = np.zeros(k)
        step[j] = h
        dz = forward(base.x, base.M, base.bias, {eid: step}, dt=dt, dtemp=dtemp) - z0
        expected[:, j] = np.linalg.norm(dz, axis=1) / h
    np.testing.assert_allclose(pose_mean_change(eid, data, base), expected, rtol=1e-5, atol=1e-8 * expected.max())
