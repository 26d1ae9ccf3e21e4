"""The loop's exploration kept on a finite track, and the growth's processes.

Ground truth: MuJoCo is the plant (the track's end is where the task's rule stops it); the
recorded forces are checked against the system's Lagrangian equations (sympy,
:class:`~pysindy_xl.MassMatrixDynamics`) along the recorded motion."""

import numpy as np
import pytest
from support.control import true_model

from pysindy_xl.control import AutomaticGrowth, TrackGuard, exploration_policy, get_task
from pysindy_xl.control.discrete import continuous_dynamics
from pysindy_xl.control.loop import learn_to_control, noisy_positions
from pysindy_xl.control.plant import MuJoCoPlant

CDP = "cart-double-pendulum"


def _explore(name, force_limit, seconds, seed, guard):
    """The loop's first exploration of ``seed`` (the same draws), guarded or not, stopped at
    the end of the track."""
    task = get_task(name, force_limit=force_limit)
    plant = MuJoCoPlant(name, task.actuated, force_limit, 0.02)
    rng = np.random.default_rng(seed)
    plant.reset(np.r_[0.0, rng.uniform(-0.05, 0.05, plant.n - 1)])
    policy = exploration_policy(force_limit, rng)
    if guard:
        policy = TrackGuard(policy, task.track_limit, force_limit)
    episode = plant.run(policy, seconds, stop=lambda s, t: "track" if task.outside_track(
        s, plant.system)[0] else None)
    return episode, policy, plant


def test_the_guard_keeps_a_fast_exploration_on_the_track_for_the_seconds_asked():
    """Cart double pendulum at 20 N, the loop's seed 11: unguarded, the cart runs off the
    track within a second; guarded, it stays at |x| <= 1.3 m for the 8 s asked, every one of
    them plant time, with the first link still swung past the horizontal."""
    alone, _, _ = _explore(CDP, 20.0, 8.0, 11, guard=False)
    assert alone.stopped == "track" and alone.duration < 1.0
    episode, guard, plant = _explore(CDP, 20.0, 8.0, 11, guard=True)
    assert episode.stopped == "duration"
    assert episode.duration == pytest.approx(8.0)
    assert plant.interaction_s == pytest.approx(8.0)
    assert np.abs(episode.q[:, 0]).max() <= 1.3
    assert guard.returns >= 1 and 0 < sum(guard.guarded) < len(guard.guarded) / 2
    assert np.abs(episode.q[:, 1]).max() > np.pi / 2  # the first link swung past horizontal
    assert np.abs(episode.controls).max() <= 20.0


def test_a_guarded_recording_obeys_the_equations_of_motion():
    """The returns to the centre are recorded like the excitation: along the guarded
    recording (noise-free), the true equations with the recorded forces give the
    accelerations MuJoCo produced (central differences of its velocities), within 1 % RMS,
    on the samples under the guard as on the others; noisy positions keep the recording's
    shape."""
    episode, guard, _ = _explore(CDP, 20.0, 8.0, 11, guard=True)
    n = episode.q.shape[1]
    dt = episode.t[1] - episode.t[0]
    inner = slice(1, -1)
    measured = (episode.qd[2:] - episode.qd[:-2]) / (2 * dt)
    states, tau = np.c_[episode.q, episode.qd][inner], episode.tau[inner]
    predicted = np.asarray(continuous_dynamics(true_model(CDP))(states, tau))[:, n:]
    under = np.repeat(np.asarray(guard.guarded), 20)  # 20 MuJoCo steps per period
    under = np.r_[under, under[-1]][inner]
    assert under.any() and (~under).any()
    # the samples whose neighbours share a control period (the force is held in between)
    held = np.r_[False, tau[1:, 0] == tau[:-1, 0]] & np.r_[tau[1:, 0] == tau[:-1, 0], False]
    for mask in (under & held, ~under & held):
        error = np.linalg.norm(predicted[mask] - measured[mask], axis=0) \
            / np.linalg.norm(measured[mask], axis=0)
        assert np.all(error < 0.01), error
    noisy = noisy_positions(episode, 0.01, np.random.default_rng(0))
    assert noisy.shape == episode.q.shape


def test_the_cart_pole_exploration_never_needs_the_guard():
    """At 10 N the cart-pole's 2.5 s exploration stays far from the track's end: the guard
    never takes over, so the recording is the unguarded one, sample for sample."""
    for seed in (0, 9, 11):
        guarded, guard, _ = _explore("cart-pole", 10.0, 2.5, seed, guard=True)
        alone, _, _ = _explore("cart-pole", 10.0, 2.5, seed, guard=False)
        assert guard.returns == 0
        np.testing.assert_array_equal(guarded.q, alone.q)


def test_the_loop_records_the_exploration_seconds_asked():
    """The loop's seed 11 at 20 N: guarded, one 8 s recording with a return to the centre;
    without the guard, the exploration reaches the end of the track, restarts at the centre
    (a new plant episode) and records the remaining seconds; the 0.78 s piece is counted but
    not identified from. Every plant second is in ``interaction_s``."""
    guarded = learn_to_control(CDP, force_limit=20.0, seed=11, max_episodes=1)
    (explore,) = guarded.history
    assert guarded.interaction_s == pytest.approx(8.0) and guarded.restarts == 0
    assert explore["segments"] == 1 and explore["returns"] >= 1
    assert 0 < explore["return_s"] < 4.0 and explore["unused_s"] == 0.0
    restarted = learn_to_control(CDP, force_limit=20.0, seed=11, max_episodes=1,
                                 keep_on_track=False)
    (explore,) = restarted.history
    assert restarted.interaction_s == pytest.approx(8.0) and restarted.restarts == 1
    assert restarted.episodes == 1
    assert explore["segments"] == 2 and explore["returns"] == 0
    assert explore["unused_s"] == pytest.approx(0.78, abs=0.03)
    assert explore["duration_s"] == pytest.approx(8.0)


@pytest.mark.parametrize("kwargs, match", [
    ({"policy": None}, "policy"),
    ({"track_limit": -1.0}, "track_limit"),
    ({"force_limit": 0.0}, "force_limit"),
    ({"margin": 0.8}, "margin"),
    ({"lookahead": float("nan")}, "lookahead"),
])
def test_bad_input_to_the_guard(kwargs, match):
    arguments = {"policy": lambda s, t: np.zeros(1), "track_limit": 1.5, "force_limit": 10.0}
    arguments.update(kwargs)
    with pytest.raises((ValueError, TypeError), match=match):
        TrackGuard(**arguments)


@pytest.mark.slow
def test_the_growth_gives_the_same_model_with_one_or_two_processes():
    """The automatic catalog grown on 2 s of a cart-pole exploration: the same steps, the
    same catalog (the law's, with configuration-dependent kinetic terms) and the same
    coefficients with ``n_jobs=1`` and ``n_jobs=2``."""
    plant = MuJoCoPlant("cart-pole", ["x"], 10.0, 0.02)
    rng = np.random.default_rng(0)
    plant.reset(np.r_[0.0, rng.uniform(-0.05, 0.05, plant.n - 1)])
    episode = plant.run(exploration_policy(10.0, rng), 2.0)
    data = [(noisy_positions(episode, 0.01, rng), episode.t, episode.tau)]
    one, two = (AutomaticGrowth(moves=("kinetic",), n_jobs=n_jobs)("cart-pole", data)
                for n_jobs in (1, 2))
    assert [s.description for s in one.steps] == [s.description for s in two.steps]
    assert [s.chosen for s in one.steps] == [s.chosen for s in two.steps]
    assert len(one.steps) >= 3 and "kinetic configuration" in one.catalog.describe()
    assert one.catalog.describe() == two.catalog.describe()
    np.testing.assert_array_equal(one.model.coefficients(), two.model.coefficients())
    assert "n_jobs=2" in repr(AutomaticGrowth(n_jobs=2))


def test_the_command_line_hands_n_jobs_to_the_growth(monkeypatch):
    """``pysindy-xl control --n-jobs 2`` runs the loop with ``AutomaticGrowth(n_jobs=2)``;
    without it, with the catalog's name."""
    import argparse

    import pysindy_xl.control.loop as loop
    from pysindy_xl.control.command import add_parser, run_control

    seen = []

    def fake(system, task, catalog, **kwargs):
        seen.append(catalog)
        raise ValueError("stop here")

    monkeypatch.setattr(loop, "learn_to_control", fake)
    parser = argparse.ArgumentParser()
    add_parser(parser.add_subparsers(dest="command"))
    for extra in (["--n-jobs", "2"], []):
        assert run_control(parser.parse_args(["control", "cart-pole", "--quiet", *extra])) == 1
    assert isinstance(seen[0], AutomaticGrowth) and seen[0].n_jobs == 2
    assert seen[1] == "automatic"
