"""A fit evaluates what it needs once: the weak entries of each smoothed state, the sympy
matrix only when read, the compiled entries in threads; all bit-identical to doing it
again. Ground truth: the same fit without the reuse (coefficients equal bit for bit), sympy's
own free symbols and terms of the built matrix, and the serial evaluation."""

import warnings

import numpy as np
import pytest
import sympy as sp
from kinematic_models import PLANAR_ARM
from scipy.integrate import solve_ivp

import pysindy_xl as px
from pysindy_xl.feature_library import _base, _compile, _weak_evaluation
from pysindy_xl.mujoco import MJCFSystem, generate_dataset, kinematic_catalog


def _pendulum_with_noisy_torques(duration=8.0, rate=500.0):
    """``q'' + 9.81 sin q = tau`` (scipy, tight tolerance), encoders quantized at 1e-5 rad,
    torques with noise and an offset: a fit that chooses its noise model."""
    t = np.arange(0.0, duration, 1.0 / rate)

    def torque(s):
        return 3.0 * np.sin(1.1 * s) + 2.0 * np.sin(2.3 * s + 1.0) + 1.5 * np.sin(4.1 * s)

    solution = solve_ivp(lambda s, y: [y[1], torque(s) - 9.81 * np.sin(y[0])], (0, t[-1]),
                         [0.3, 0.0], t_eval=t, rtol=1e-11, atol=1e-12, method="DOP853")
    q = np.round(solution.y[0][:, None] / 1e-5) * 1e-5
    tau = torque(t)[:, None] + 0.5 + 0.3 * np.random.default_rng(0).normal(size=(len(t), 1))
    return q, t, tau


def test_noise_model_choice_evaluates_each_smoothed_state_once(monkeypatch):
    q, t, tau = _pendulum_with_noisy_torques()
    c = px.Coordinates(["q"])
    library = px.LagrangeLibrary(c, [c.qd[0] ** 2, sp.cos(c.q[0]), c.q[0] ** 2])
    evaluated = []
    compile_terms = _weak_evaluation.compile_terms

    def counting(variables, terms):
        evaluate = compile_terms(variables, terms)

        def wrapped(z, *args, **kwargs):
            if kwargs.get("stacked"):  # the weak entries (columns are written to targets)
                evaluated.append(len(z))
            return evaluate(z, *args, **kwargs)
        return wrapped

    monkeypatch.setattr(_weak_evaluation, "compile_terms", counting)
    model = px.XLSINDy(library).fit(q, t, u=tau)
    assert "noise_model" in model.weak_info_  # candidates and scoring rows were built
    once = sum(evaluated)
    evaluated.clear()
    monkeypatch.setattr(_weak_evaluation, "_WEAK_MEMO_BYTES", 0)  # nothing kept: all evaluated
    again = px.XLSINDy(library).fit(q, t, u=tau)
    np.testing.assert_array_equal(model.coef_, again.coef_)
    assert model.weak_info_["noise_model"] == again.weak_info_["noise_model"]
    # the states and the noise draws of the position-noise rows, evaluated once for the
    # force-noise candidate (the scoring rows) and their draws as well
    n_draws = int(np.clip(np.ceil(24_000 / len(t)), 1, 16))
    assert once == (1 + n_draws) * len(t)
    assert sum(evaluated) == (2 + 2 * n_draws) * len(t)
    assert "_weak_memo" not in model.feature_library_.__dict__


def test_kinematic_fit_reads_the_structure_not_the_sympy_matrix():
    system = MJCFSystem(PLANAR_ARM, force_amplitude=4.0)
    data = generate_dataset(system, n_trajectories=1, duration=2.0, seed=0, sample_every=5,
                            progress=False)
    model = px.XLSINDy(kinematic_catalog(system).library()).fit(**data.fit_arguments("tau"))
    library = model.feature_library_
    assert isinstance(library.__dict__["_symbolic_matrix"], _base.DeferredMatrix)
    sizes, coords = library.entry_sizes(), library.coords
    uses = {v: library.involves([v]) for v in coords.variables}
    matrix = library.symbolic_matrix_  # built now, by sympy
    for c in range(matrix.shape[0]):
        for j in range(matrix.shape[1]):
            entry = matrix[c, j]
            assert sizes[c, j] == (len(sp.Add.make_args(entry)) if entry != 0 else 0)
            assert {v for v in coords.variables if uses[v][c, j]} == entry.free_symbols
    assert str(model.equations()[0])  # printing builds what it reads


def test_threaded_evaluation_is_the_serial_one(monkeypatch):
    a, b = sp.symbols("a b")
    evaluate = _compile.compile_entries([a, b], [a * b + sp.sin(a) ** 2, a ** 4 * b])
    z = np.random.default_rng(0).normal(size=(40_000, 2))  # several blocks
    z[::7, 0] = 1e100  # a ** 4 overflows, in the workers' products
    monkeypatch.setattr(_compile, "THREADS", 1)
    with np.errstate(all="ignore"):
        serial = evaluate(z, stacked=True)
    monkeypatch.setattr(_compile, "THREADS", 4)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the workers keep the caller's error handling
        with np.errstate(all="ignore"):
            threaded = evaluate(z, stacked=True)
    np.testing.assert_array_equal(threaded, serial)
    assert np.isinf(serial[1]).any()
    with pytest.warns(RuntimeWarning, match="overflow"):
        evaluate(z, stacked=True)
