"""MuJoCo's dry friction (``frictionloss``) as the kinematic catalog models it.

Ground truth: MuJoCo's own friction forces (``qfrc_constraint`` of a model whose only
constraints are its friction rows) against the scales that ``dry_friction_scales`` derives
from the model's frictionloss, solref, solimp and dof inverse inertia.
"""

import numpy as np
import pytest
import sympy as sp

mujoco = pytest.importorskip("mujoco")

from pysindy_xl.mujoco.systems.friction import dry_friction_scales  # noqa: E402
from pysindy_xl.physical.friction import regularized_dry_friction  # noqa: E402

# a heavy shoulder and a light wrist (its soft friction never saturates at moderate speeds),
# one joint with the default friction regularization, one with its own
ARM = """
<mujoco>
  <option timestep="{step}" integrator="RK4"/>
  <worldbody>
    <body>
      <joint name="shoulder" axis="0 0 1" frictionloss="1.5" damping="0.2"/>
      <geom type="capsule" fromto="0 0 0 .4 0 0" size=".04" mass="2" contype="0"
            conaffinity="0"/>
      <body pos=".4 0 0">
        <joint name="wrist" axis="0 0 1" frictionloss="0.3" solreffriction="0.01 1"
               solimpfriction="0.8 0.9 0.001" damping="0.01"/>
        <geom type="capsule" fromto="0 0 0 .05 0 0" size=".01" mass=".05" contype="0"
              conaffinity="0"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor joint="shoulder"/><motor joint="wrist"/></actuator>
</mujoco>
"""


def _run(step=1e-4, duration=2.0, seed=0):
    """A run under random smooth torques: friction force, velocity, acceleration per step."""
    model = mujoco.MjModel.from_xml_string(ARM.format(step=step))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration / step)) * step
    freqs, phases = rng.uniform(0.5, 3.0, (2, 4)), rng.uniform(0, 2 * np.pi, (2, 4))
    torque = np.array([2.0, 0.2])[:, None] * np.sin(
        2 * np.pi * freqs[:, :, None] * t + phases[:, :, None]).sum(axis=1)
    friction, velocity, acceleration = (np.empty((len(t), 2)) for _ in range(3))
    for k in range(len(t)):
        data.ctrl[:] = torque[:, k]
        mujoco.mj_forward(model, data)
        friction[k], velocity[k], acceleration[k] = data.qfrc_constraint, data.qvel, data.qacc
        mujoco.mj_step(model, data)
    return model, t, friction, velocity, acceleration


@pytest.fixture(scope="module")
def run():
    return _run()


def test_scales_give_mujocos_friction_force(run):
    """f = -F sat((v + tau a) / s) with the derived scales, to round-off, in both regimes."""
    model, _, friction, velocity, acceleration = run
    scale, lead = dry_friction_scales(model)
    loss = model.dof_frictionloss
    argument = (velocity + lead * acceleration) / scale
    assert np.abs(friction + loss * np.clip(argument, -1, 1)).max() < 1e-8 * loss.max()
    saturated = np.abs(argument) >= 1
    # the shoulder mostly slides, the light wrist mostly sticks (soft-constraint inertia)
    assert saturated[:, 0].mean() > 0.5 and saturated[:, 1].mean() < 0.5
    assert saturated[:, 1].any() and not saturated[:, 0].all()
    # the wrist's own solref / solimp are used: a lead of d_max t_c / 2
    assert lead[1] == pytest.approx(0.9 * 0.01 / 2) and lead[0] == pytest.approx(0.95 * 0.02 / 2)


def test_refsafe_and_direct_solref():
    """solref's time constant is raised to two time steps (MuJoCo's refsafe); a negative
    solref gives the damping directly."""
    model = mujoco.MjModel.from_xml_string(ARM.format(step=0.01))
    assert dry_friction_scales(model)[1][1] == pytest.approx(0.9 * 0.02 / 2)
    model.dof_solref[1] = (-100.0, -50.0)
    assert dry_friction_scales(model)[1][1] == pytest.approx(0.9 / 50.0)


def test_weak_projection_of_the_candidate_matches_mujoco(run):
    """Against test functions wider than the lead, the candidate -F [sat(v/s) + tau d/dt
    sat(v/s)] carries MuJoCo's friction impulses, exactly on the sticking wrist (damping and
    inertia of the soft constraint), to first order in the lead on the sliding shoulder
    (MuJoCo switches the friction tau early and relaxes into sticking over a few tau: the
    candidate halves the gap of tanh(v / 0.01) there, and removes it on the wrist)."""
    model, t, friction, velocity, acceleration = run
    scale, lead = dry_friction_scales(model)
    v, a = sp.symbols("v a", real=True)
    step = t[1] - t[0]
    centers = np.arange(0.15, t[-1] - 0.15, 0.05)
    phi = np.clip(1 - ((t[None, :] - centers[:, None]) / 0.15) ** 2, 0, None) ** 2
    gaps = {}
    for j in range(2):
        term = sp.lambdify((v, a), regularized_dry_friction(v, a, scale[j], lead[j]))
        candidate = -model.dof_frictionloss[j] * term(velocity[:, j], acceleration[:, j])
        smooth = -model.dof_frictionloss[j] * np.tanh(velocity[:, j] / 0.01)
        truth = phi @ friction[:, j] * step
        norm = np.linalg.norm(truth)
        gaps[j] = [np.linalg.norm(phi @ model_force * step - truth) / norm
                   for model_force in (candidate, smooth)]
    (shoulder, shoulder_smooth), (wrist, wrist_smooth) = gaps[0], gaps[1]
    assert shoulder < 0.05 and shoulder < shoulder_smooth / 2, gaps
    assert wrist < 0.01 and wrist < wrist_smooth / 50, gaps


@pytest.mark.filterwarnings("ignore")  # the fit only gives the model its structure
def test_mujoco_law_model_reads_its_rigid_mass_and_exports_its_frictionloss():
    """With MuJoCo's regularized dry friction in the catalog, the model with the MJCF's own
    coefficients has the soft constraint's inertia 1/R inside the sticking zone (as MuJoCo
    does); the mass matrix compared with mj_fullM is the rigid body's, read where the joints
    slide; the law counts as dry friction, and the MJCF export states it as frictionloss."""
    import pysindy_xl as px
    from pysindy_xl.evaluation.physics import compare_physics
    from pysindy_xl.export.mjcf import identified_mj_model
    from pysindy_xl.mujoco import MJCFSystem, generate_dataset, kinematic_catalog
    from pysindy_xl.physical import friction_columns

    # a stiff friction regularization on the wrist: its sticking inertia 1/R is ~100 times
    # the link's, over a sticking zone of 0.3 rad/s
    system = MJCFSystem(ARM.format(step=1e-3).replace('solimpfriction="0.8 0.9 0.001"',
                                                       'solimpfriction="0.99 0.99 0.001"'))
    scale = dry_friction_scales(system.mj_model())[0]
    assert 0.1 < scale[1] < 1.0
    catalog = kinematic_catalog(system, coulomb_law="mujoco")
    assert sum(term.has(sp.Abs) for term in catalog.classical_terms) == 2
    assert not any(term.has(sp.Abs) for term in kinematic_catalog(system).classical_terms)
    data = generate_dataset(system, n_trajectories=1, duration=0.5, seed=0, progress=False)
    model = px.XLSINDy(catalog.library(), px.ExplicitOptimizer(), formulation="strong")
    model.fit(**data.fit_arguments())
    model.coef_ = catalog.true_coefficients()  # the MJCF's own model
    model._build_dynamics()
    library = model.feature_library_
    dry = [j for j in friction_columns(library) if library.feature_terms_[j].has(sp.Abs)]
    assert len(dry) == 2
    # inside the wrist's sticking zone the model carries MuJoCo's soft inertia
    mj_model = system.mj_model()
    inverse_r = 0.99 / 0.01 / mj_model.dof_invweight0[1]
    z = px.stack_variables(np.zeros((1, 2)), np.array([[1.0, 0.5 * scale[1]]]), None,
                           np.zeros((1, 2)), np.zeros(1))
    sliding = px.stack_variables(np.zeros((1, 2)), np.array([[1.0, 3 * scale[1]]]), None,
                                 np.zeros((1, 2)), np.zeros(1))
    dynamics = model._require_dynamics()
    gap = dynamics.mass_and_forcing(z)[0] - dynamics.mass_and_forcing(sliding)[0]
    assert gap[0, 1, 1] == pytest.approx(inverse_r, rel=1e-9)
    assert inverse_r > 0.01 * np.abs(dynamics.mass_and_forcing(sliding)[0]).max()
    physics = compare_physics(model, system, n_states=8, seed=0)
    assert physics["mass_error"] < 1e-8
    exported, reason = identified_mj_model(model, system)
    assert reason is None
    np.testing.assert_allclose(exported.dof_frictionloss, mj_model.dof_frictionloss, rtol=1e-9)
    np.testing.assert_allclose(exported.dof_damping, mj_model.dof_damping, rtol=1e-9)


def test_coulomb_law_is_checked():
    from pysindy_xl.mujoco import kinematic_catalog
    from pysindy_xl.mujoco.catalogs.reference import reference_catalog

    with pytest.raises(ValueError, match="coulomb_law: expected one of"):
        kinematic_catalog(ARM.format(step=1e-3), coulomb_law="tanh")
    with pytest.raises(ValueError, match="coulomb_law: only the 'kinematic' catalog"):
        reference_catalog("cart-pole", "mixed", coulomb_law="mujoco")


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_auto_formulation_fits_the_mujoco_law_in_the_weak_form():
    """Measured derivatives normally mean the strong form; MuJoCo's law has an impulse at each
    reversal (its lead), which samples miss, so "auto" integrates it by parts instead. On
    noise-free data of an arm with frictionloss, the smooth sign (strong form) moves the
    sticking zone into the inertia; MuJoCo's law recovers the mass matrix (mj_fullM) and the
    MJCF's friction."""
    import pysindy_xl as px
    from pysindy_xl.evaluation.physics import compare_physics
    from pysindy_xl.mujoco import MJCFSystem, generate_dataset, kinematic_catalog

    # dry friction the default forcing overcomes (the shoulder's 1.5 N m would hold it)
    system = MJCFSystem(ARM.format(step=1e-3).replace('frictionloss="1.5"', 'frictionloss="0.2"')
                        .replace('frictionloss="0.3"', 'frictionloss="0.02"'))
    data = generate_dataset(system, n_trajectories=2, duration=2.0, seed=2, progress=False)
    arguments = data.fit_arguments(forces="tau")
    assert arguments["x_dot"] is not None and arguments["x_ddot"] is not None
    smooth = px.XLSINDy(kinematic_catalog(system).library()).fit(**arguments)
    model = px.XLSINDy(kinematic_catalog(system, coulomb_law="mujoco").library())
    model.fit(**arguments)
    assert (smooth.formulation_, model.formulation_) == ("strong", "weak")
    smooth_error = compare_physics(smooth, system)["mass_error"]
    error = compare_physics(model, system)["mass_error"]
    assert error < 0.02 and error < smooth_error / 3, (error, smooth_error)
    friction = model.physical_parameters()["friction"]
    assert friction["wrist"]["dry"] == pytest.approx(0.02, rel=0.05)
    assert friction["shoulder"]["dry"] == pytest.approx(0.2, rel=0.2)
    assert friction["wrist"]["viscous"] == pytest.approx(0.01, rel=0.05)



@pytest.mark.filterwarnings("ignore::UserWarning")
def test_mujoco_law_model_saves_loads_and_exports_to_jax(tmp_path):
    """The law's Abs and sign survive the model file and the JAX export: the same
    accelerations inside and outside the sticking zones."""
    import pysindy_xl as px
    from pysindy_xl.mujoco import MJCFSystem, generate_dataset, kinematic_catalog

    system = MJCFSystem(ARM.format(step=1e-3))
    data = generate_dataset(system, n_trajectories=1, duration=1.0, seed=0, progress=False)
    model = px.XLSINDy(kinematic_catalog(system, coulomb_law="mujoco").library(),
                       px.ExplicitOptimizer()).fit(**data.fit_arguments(forces="tau"))
    assert sum(c != 0 for name, c in zip(model.get_feature_names(), model.coefficients(),
                                         strict=True) if "Abs" in name) == 2  # both joints'
    scale = dry_friction_scales(system.mj_model())[0]
    rng = np.random.default_rng(0)
    q = rng.uniform(-1, 1, (40, 2))
    # velocities inside and outside each joint's sticking zone
    qd = scale * rng.choice([0.3, 0.9, 1.5, 4.0], (40, 2)) * rng.choice([-1, 1], (40, 2))
    u = rng.normal(size=(40, 2))
    expected = model.predict(q, qd, u)
    model.save(tmp_path / "model.json")
    np.testing.assert_allclose(px.XLSINDy.load(tmp_path / "model.json").predict(q, qd, u),
                               expected, rtol=1e-12, atol=1e-12)
    jax = pytest.importorskip("jax")
    with jax.enable_x64(True):
        derivative = np.asarray(model.to_jax()(np.hstack([q, qd]), u))
    np.testing.assert_allclose(derivative[:, 2:], expected, rtol=1e-9, atol=1e-9)
