"""Benchmark grid definition, per-run time limit and isolation, and one real end-to-end run."""

import json
import os
import signal
import time

import numpy as np
import pytest

from pysindy_xl.benchmark.grid import (
    PRESETS,
    GridSettings,
    Task,
    TrajectorySpec,
    all_configurations,
    config_label,
)
from pysindy_xl.benchmark.runner import run_task, system_for

SETTINGS = GridSettings(systems=("cart-pole",), forcings=("explicit",), timeout=2.0,
                        configurations=(("mixed", "explicit"),), name="test")
TASK = SETTINGS.tasks()[0]


# -- grid --------------------------------------------------------------------------------------
def test_grid_follows_the_papers_protocol():
    settings = GridSettings(systems=("cart-pole", "double-pendulum"), noise_levels=(0.0, 0.01))
    tasks = settings.tasks()
    per_forcing = {}
    for t in tasks:
        per_forcing.setdefault(t.trajectory.forcing, set()).add((t.catalog, t.solver))
    # explicit solver only with forces, implicit solver only without; mixed and SINDy always
    assert {s for _, s in per_forcing["implicit"]} == {"mixed", "implicit", "pysindy"}
    assert {s for _, s in per_forcing["explicit"]} == {"mixed", "explicit", "pysindy"}
    assert per_forcing["mixed"] == per_forcing["explicit"]
    assert len(settings.trajectories()) == 2 * 3 * 2
    # per trajectory: 4 catalogs (the paper's 3 + kinematic) x the 2 solvers that apply to
    # its forcing (mixed + explicit or implicit), + the SINDy baseline = 9 runs
    assert len(tasks) == 12 * 9 and len({t.run_id for t in tasks}) == len(tasks)
    assert len(all_configurations()) == 13 and len(all_configurations(False)) == 12
    assert {(c, s) for c, s in all_configurations() if c == "kinematic"} == {
        ("kinematic", "mixed"), ("kinematic", "explicit"), ("kinematic", "implicit")}
    assert {c for t in tasks for c in [t.catalog]} == {"mixed", "lagrange", "classical",
                                                       "kinematic"}
    # tasks of one trajectory are consecutive, so a worker reuses its data
    keys = [t.trajectory.key for t in tasks]
    assert keys == sorted(keys, key=keys.index)


def test_run_ids_depend_on_the_data_settings_but_not_the_timeout():
    base = PRESETS["quick"]
    ids = {t.run_id for t in base.tasks()}
    assert {t.run_id for t in base.with_options(timeout=5.0).tasks()} == ids
    assert not {t.run_id for t in base.with_options(duration=7.0).tasks()} & ids
    assert config_label("mixed", "mixed") == "mixed x mixed"


def test_presets_scale():
    # quick: 3 systems x 3 forcings x (2 levels of the paper's noise + 2 positions-only) = 36
    # trajectories x 9 runs (4 catalogs x 2 applicable solvers + SINDy) = 324
    assert len(PRESETS["quick"].trajectories()) == 36
    assert len(PRESETS["quick"].tasks()) == 36 * 9 == 324
    full = PRESETS["full"]
    # the paper's 162 trajectories, plus 108 with positions-only noise (1 % and 5 %)
    assert len(full.trajectories()) == 162 + 108 and full.timeout == 3600.0
    assert len(full.tasks()) == 270 * 9


@pytest.mark.parametrize("changes, match", [
    ({"forcings": ("pushed",)}, "forcings"),
    ({"noise_levels": (-0.1,)}, "noise_levels"),
    ({"seeds": (0, 0)}, "duplicate"),
    ({"configurations": (("mixed", "lasso"),)}, "configurations"),
    ({"timeout": 0.0}, "timeout"),
    ({"systems": "cart-pole"}, "systems"),
    ({"sample_every": 0}, "sample_every"),
])
def test_bad_grid_settings_are_rejected(changes, match):
    with pytest.raises(ValueError, match=match):
        GridSettings(**changes)


def test_friction_level_scales_the_joint_damping():
    spec = TrajectorySpec("double-pendulum", 2.0, "explicit", 0.0, 0)
    default = system_for(TrajectorySpec("double-pendulum", 1.0, "explicit", 0.0, 0))
    doubled = system_for(spec)
    np.testing.assert_allclose(doubled.joint_damping, 2 * default.joint_damping)
    frictionless = system_for(TrajectorySpec("cart-pole", 0.0, "implicit", 0.0, 0))
    assert not np.any(frictionless.joint_damping)


# -- time limit and isolation --------------------------------------------------------------------
def sleeps_forever(task, settings, deadline, stage):
    if stage:
        stage("fit")
    time.sleep(60)


def raises(task, settings, deadline, stage):
    raise np.linalg.LinAlgError("SVD did not converge")


def crashes(task, settings, deadline, stage):
    os.kill(os.getpid(), signal.SIGKILL)  # like an out-of-memory kill


def busy_python(task, settings, deadline, stage):
    while True:
        sum(range(1000))


@pytest.mark.parametrize("isolation", ["process", "signal"])
def test_timeout_is_enforced(isolation):
    function = sleeps_forever if isolation == "process" else busy_python
    start = time.perf_counter()
    record = run_task(TASK, SETTINGS, timeout=0.5, isolation=isolation, function=function)
    elapsed = time.perf_counter() - start
    assert record["status"] == "timeout" and elapsed < 5
    assert "0.5 s" in record["message"]
    if isolation == "process":
        assert "during fit" in record["message"]
    json.dumps(record, allow_nan=False)
    assert record["run_id"] == TASK.run_id and "finished_at" in record


@pytest.mark.parametrize("isolation", ["process", "signal", "none"])
def test_an_exception_becomes_an_error_record(isolation):
    record = run_task(TASK, SETTINGS, isolation=isolation, function=raises)
    assert record["status"] == "error"
    assert record["message"].startswith("LinAlgError: SVD did not converge")


def test_a_crashing_run_becomes_an_error_record():
    record = run_task(TASK, SETTINGS, isolation="process", function=crashes)
    assert record["status"] == "error"
    assert "exit code -9" in record["message"]


def test_bad_run_arguments():
    with pytest.raises(ValueError, match="isolation"):
        run_task(TASK, SETTINGS, isolation="thread", function=raises)
    with pytest.raises(ValueError, match="timeout"):
        run_task(TASK, SETTINGS, timeout=0, function=raises)


# -- real runs -------------------------------------------------------------------------------
@pytest.mark.slow
def test_real_grid_and_report(tmp_path):
    """Cart-pole, explicit forcing: XL-SINDy explicit run and the SINDy baseline, end to end."""
    from pysindy_xl.benchmark.cli import main

    out = tmp_path / "results"
    # --position-noise with no level: the quick preset's positions-only trajectories left out
    argv = ["--quick", "--systems", "cart-pole", "--forcing", "explicit", "--noise", "0",
            "--position-noise", "--configs", "mixed:explicit", "sindy", "-j", "1", "--no-progress",
            "--out", str(out)]
    assert main(argv) == 0
    lines = (out / "records.jsonl").read_text().splitlines()
    records = {json.loads(line)["config"]: json.loads(line) for line in lines}
    assert set(records) == {"mixed x explicit", "pysindy.SINDy (classical)"}
    ours = records["mixed x explicit"]
    # noise-free data and the true model in the catalog: exact identification, valid model
    assert ours["status"] == "ok", ours["message"]
    assert ours["metrics"]["position_rmse"] < 1e-2
    assert ours["model"]["coefficient_error"] < 1e-3
    assert ours["time_s"]["run"] < SETTINGS.timeout * 60
    baseline = records["pysindy.SINDy (classical)"]
    assert baseline["status"] in ("ok", "invalid") and baseline["model"]["n_terms"] > 0
    for name in ("table.md", "table.csv", "table.png", "summary.json", "machine.json"):
        assert (out / name).stat().st_size > 0
    table = (out / "table.csv").read_text().splitlines()
    assert table[1].startswith("mixed x explicit,0,0,0,1,")
    # rerun: nothing left to do, the records are untouched; report-only rebuilds the table
    assert main(argv) == 0
    assert (out / "records.jsonl").read_text().splitlines() == lines
    assert main(argv + ["--report-only"]) == 0
    # --fresh keeps the old records aside and starts over (here: nothing run, --limit 0)
    assert main(argv + ["--fresh", "--limit", "0"]) == 0
    kept = list(out.glob("records.*.jsonl"))
    assert len(kept) == 1 and kept[0].read_text().splitlines() == lines
    assert not (out / "records.jsonl").exists() or not (out / "records.jsonl").read_text()
    assert "0 | 0 | 0 | 0 | 0 | 0 | 0 | - | 0 |" in (out / "table.md").read_text()


# -- command line ------------------------------------------------------------------------------
def test_command_line_options_build_the_grid():
    import argparse

    from pysindy_xl.benchmark.cli import add_parser, settings_from_args

    parser = argparse.ArgumentParser(prog="pysindy-xl")
    add_parser(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["benchmark", "--full", "--systems", "cart-pole", "--noise", "0",
                              "0.05", "--configs", "mixed:mixed", "sindy", "--timeout", "10"])
    settings = settings_from_args(args)
    assert settings.name == "full" and settings.systems == ("cart-pole",)
    assert settings.noise_levels == (0.0, 0.05) and settings.timeout == 10.0
    assert settings.configurations == (("mixed", "mixed"), ("classical", "pysindy"))
    assert callable(args.func)
    args = parser.parse_args(["benchmark", "--no-baseline"])
    assert ("classical", "pysindy") not in settings_from_args(args).configurations
    assert settings_from_args(args).name == "quick"
    with pytest.raises(SystemExit):
        parser.parse_args(["benchmark", "--configs", "mixed:lasso"])


def test_missing_cluster_backend_is_a_clear_error(tmp_path, capsys):
    import importlib.util

    from pysindy_xl.benchmark.cli import main

    if importlib.util.find_spec("dask") is not None:
        pytest.skip("dask is installed")
    status = main(["--quick", "--backend", "dask", "--limit", "0", "--no-progress",
                   "--out", str(tmp_path)])
    assert status == 1
    assert "dask[distributed]" in capsys.readouterr().err


def test_positions_only_noise_gives_noisy_positions_and_no_derivatives():
    from pysindy_xl.benchmark.runner import trajectory_data

    spec = TrajectorySpec("cart-pole", 1.0, "explicit", 0.02, 0, noise_model="positions")
    assert spec.key.endswith("noise=0.02(positions)/seed=0")
    clean, _, _ = trajectory_data(TrajectorySpec("cart-pole", 1.0, "explicit", 0.0, 0), 1, 2.0,
                                  5, 1.0)
    noisy, _, _ = trajectory_data(spec, 1, 2.0, 5, 1.0)
    assert noisy.metadata["noise_model"] == "positions"
    arguments = noisy.fit_arguments()
    assert arguments["x_dot"] is None and arguments["x_ddot"] is None
    q_clean, q_noisy = clean.trajectories[0].q, noisy.trajectories[0].q
    relative = np.std(q_noisy - q_clean, axis=0) / np.std(q_clean, axis=0)
    np.testing.assert_allclose(relative, 0.02, rtol=0.25)
    np.testing.assert_array_equal(noisy.trajectories[0].tau, clean.trajectories[0].tau)
    settings = GridSettings(systems=("cart-pole",), forcings=("explicit",),
                            position_noise_levels=(0.01,))
    assert [s.noise_model for s in settings.trajectories()] == ["all", "positions"]


def test_kinematic_catalog_row_runs_end_to_end():
    """The kinematic-catalog row on clean cart-pole data: exact model, valid, few columns."""
    settings = GridSettings(systems=("cart-pole",), forcings=("explicit",), duration=3.0,
                            validation_duration=3.0, sample_every=5, timeout=120.0,
                            configurations=(("kinematic", "explicit"),), name="test")
    (task,) = settings.tasks()
    assert task.config == "kinematic x explicit"
    record = run_task(task, settings, isolation="none")
    assert record["status"] == "ok", record["message"]
    assert record["metrics"]["position_rmse"] < 1e-2
    # the kinematic catalog of the cart-pole: 9 columns (the paper's mixed one has 38)
    assert record["model"]["n_features"] == 9


@pytest.mark.slow
@pytest.mark.parametrize("level", [0.01, 0.05])
def test_explicit_double_pendulum_from_noisy_positions_validates(level):
    """The quick grid's explicitly forced double pendulum from noisy positions (two 5 s runs),
    mixed catalog x mixed solver: valid on a fresh MuJoCo run for seeds 0-2 with the true
    support's scale kept (the narrow force-noise reading, 45 % shrunk by the errors in its
    variables, must not replace the default that the short runs cannot score)."""
    settings = PRESETS["quick"]
    for seed in range(3):
        spec = TrajectorySpec("double-pendulum", 1.0, "explicit", level, seed,
                              noise_model="positions")
        record = run_task(Task(spec, "mixed", "mixed"), settings, isolation="none")
        assert record["status"] == "ok", (seed, record["message"])
        assert abs(record["model"]["coefficient_scale"] - 1.0) < 0.05, seed
