"""``pysindy-xl identify`` on data given coordinates: the automatic catalog and the honest exit."""

import contextlib
import io

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pysindy_xl.cli import main


def _hardening_spring_csv(path, forces=None, noise=0.01):
    """A forced mass on a hardening spring: 2 xdd + 0.3 xd + 3 x + x^3 = tau (positions only)."""
    t = np.arange(0.0, 12.0, 0.005)
    rows = []
    for run in range(2):
        rng = np.random.default_rng(run)
        frequencies, phases = rng.uniform(0.2, 1.2, 4), rng.uniform(0, 2 * np.pi, 4)

        def tau(time, frequencies=frequencies, phases=phases):
            return 3.0 * np.sin(2 * np.pi * frequencies * time + phases).sum() / 2

        solution = solve_ivp(lambda time, y: [y[1], (tau(time) - 0.3 * y[1] - 3 * y[0]
                                                     - y[0] ** 3) / 2],
                             (t[0], t[-1]), [0.5, 0.0], t_eval=t, method="DOP853",
                             rtol=1e-10, atol=1e-10)
        x = solution.y[0] + noise * solution.y[0].std() * rng.normal(size=len(t))
        u = np.array([tau(time) for time in t]) if forces is None else forces(rng, len(t))
        rows.append(np.c_[t, x, u, np.full(len(t), run)])
    np.savetxt(path, np.vstack(rows), delimiter=",", header="t,x,tau_x,trajectory",
               comments="")
    return path


def _lagrangian(out):
    return next(line for line in out.splitlines() if line.startswith("L = "))


@pytest.fixture(scope="module")
def spring_identified(tmp_path_factory):
    """The hardening spring's CSV and what ``identify`` prints for it (one process)."""
    path = _hardening_spring_csv(tmp_path_factory.mktemp("spring") / "spring.csv")
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["identify", str(path), "--coordinates", "x", "--quiet"])
    return path, code, out.getvalue()


def test_identify_grows_a_catalog_and_prints_the_lagrangian(spring_identified):
    _, code, out = spring_identified
    assert code == 0
    assert "automatic catalog: x: x..x^4" in out
    assert "step  move" in out and "degree" in out
    lagrangian = _lagrangian(out)
    assert "x**4" in lagrangian and "x_dot**2" in lagrangian
    assert "automatic catalog, explicit solver" in out


def test_identify_exits_non_zero_when_the_model_explains_nothing(tmp_path, capsys):
    path = _hardening_spring_csv(tmp_path / "garbage.csv",
                                 forces=lambda rng, n: rng.normal(size=n))
    assert main(["identify", str(path), "--coordinates", "x", "--quiet"]) == 1
    captured = capsys.readouterr()
    assert "fitted" not in captured.out
    assert "the identified model explains nothing" in captured.err
    assert "try: --angles" in captured.err


def test_help_says_what_is_tried(capsys):
    with pytest.raises(SystemExit):
        main(["identify", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for phrase in ("automatic", "B-splines", "Coulomb", "held-out", "--max-terms"):
        assert phrase in text


def test_identify_n_jobs_gives_the_same_model(spring_identified, capsys):
    path, _, alone = spring_identified  # one process (the default --n-jobs 1)
    assert main(["identify", str(path), "--coordinates", "x", "--quiet", "--n-jobs", "2"]) == 0
    assert _lagrangian(capsys.readouterr().out) == _lagrangian(alone)


def test_n_jobs_must_be_a_positive_integer(tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(["identify", str(tmp_path / "absent.csv"), "--coordinates", "x", "--n-jobs", "0"])
    assert "--n-jobs" in capsys.readouterr().err


@pytest.mark.parametrize("value", ["0", "ten", "2.5"])
def test_max_terms_must_be_a_positive_integer_or_auto(tmp_path, capsys, value):
    with pytest.raises(SystemExit):
        main(["identify", str(tmp_path / "absent.csv"), "--coordinates", "x",
              "--max-terms", value])
    assert "--max-terms" in capsys.readouterr().err


def test_the_default_ceiling_follows_the_data_and_an_int_still_binds(tmp_path, capsys):
    path = _hardening_spring_csv(tmp_path / "garbage.csv",
                                 forces=lambda rng, n: rng.normal(size=n))
    assert main(["identify", str(path), "--coordinates", "x"]) == 1
    captured = capsys.readouterr()
    ceiling = int(next(line for line in captured.err.splitlines()
                       if "] ceiling" in line).split("] ceiling")[1].split()[0])
    assert 1 <= ceiling <= 400
    assert f"--max-terms above {ceiling}" in captured.err  # the advice names the data's ceiling
    assert main(["identify", str(path), "--coordinates", "x", "--max-terms", "2"]) == 1
    assert "max_terms=2" in capsys.readouterr().err  # the smallest catalog is over it
