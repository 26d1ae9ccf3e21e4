"""MuJoCo systems: the generated data satisfy the true equations of motion.

Two independent checks of the coordinate and force transforms:

* the residual of the Euler-Lagrange equations derived here with sympy from each system's
  Lagrangian and friction is at rounding level relative to the size of the equation's terms;
* MuJoCo's accelerations equal those of ``tests/ground_truth.py`` (sympy.physics.mechanics,
  built from particle positions, not from our Lagrangians).
"""

import mujoco
import numpy as np
import pytest
import sympy as sp
from ground_truth import cart_double_pendulum, cart_pole, double_pendulum, triple_pendulum

from pysindy_xl.mujoco import (
    SYSTEMS,
    CartDoublePendulum,
    CartPole,
    DoublePendulum,
    MJCFSystem,
    TriplePendulum,
    default_xml_path,
    generate_dataset,
    get_system,
    simulate_trajectory,
)


def euler_lagrange_lhs(system):
    """``d/dt dL/dqd - dL/dq + friction`` written out independently with sympy's chain rule."""
    coords = system.coords
    lagrangian = system.lagrangian()
    t = sp.Symbol("t")
    paths = {q: sp.Function(f"path_{q}")(t) for q in coords.q}
    back = {}
    for q, qd, qdd in zip(coords.q, coords.qd, coords.qdd, strict=True):
        back[paths[q].diff(t, 2)] = qdd
        back[paths[q].diff(t)] = qd
        back[paths[q]] = q
    as_path = {q: paths[q] for q in coords.q}
    as_path.update({qd: paths[q].diff(t) for q, qd in zip(coords.q, coords.qd, strict=True)})
    out = []
    for i, (q, qd) in enumerate(zip(coords.q, coords.qd, strict=True)):
        momentum = lagrangian.diff(qd).subs(as_path)
        lhs = momentum.diff(t).subs(back) - lagrangian.diff(q)
        for (term, c), value in system.friction().items():
            if c == i:
                lhs += value * term
        out.append(lhs)
    return coords, out


def relative_residual(system, trajectory):
    coords, lhs = euler_lagrange_lhs(system)
    args = coords.q + coords.qd + coords.qdd
    values = sp.lambdify(args, lhs)
    # scale of each equation: the size of its individual terms
    sizes = sp.lambdify(args, [sum(abs(a) for a in sp.Add.make_args(sp.expand(e))) for e in lhs])
    data = (*trajectory.q.T, *trajectory.qd.T, *trajectory.qdd.T)
    residual = np.array(values(*data)).T - trajectory.tau
    scale = np.sqrt(np.mean(np.array(sizes(*data)).T ** 2, axis=0))
    return np.max(np.abs(residual) / scale)


@pytest.mark.parametrize("name", sorted(SYSTEMS))
@pytest.mark.parametrize("forcing", ["explicit", "implicit", "mixed"])
def test_generated_data_satisfy_true_equations(name, forcing):
    data = generate_dataset(name, n_trajectories=1, duration=3.0, forcing=forcing, seed=3,
                            progress=False)
    trajectory = data.trajectories[0]
    assert np.ptp(trajectory.q, axis=0).min() > 0.2  # the motion is not trivial
    assert relative_residual(get_system(name), trajectory) < 1e-10


def test_relative_hinge_friction_couples_absolute_coordinates():
    system = DoublePendulum(damping1=0.2, damping2=0.05)
    friction = system.friction_matrix()
    np.testing.assert_allclose(friction, [[0.25, -0.05], [-0.05, 0.05]])
    th1d, th2d = system.coords.qd
    assert system.friction() == pytest.approx(
        {(th1d, 0): 0.25, (th2d, 0): -0.05, (th1d, 1): -0.05, (th2d, 1): 0.05}
    )
    np.testing.assert_array_equal(system.force_matrix(), [[1, -1], [0, 1]])
    # a strongly damped relative hinge: the coupling is needed for the residual to vanish
    heavy = DoublePendulum(damping2=0.5)
    data = generate_dataset(heavy, n_trajectories=1, duration=2.0, seed=0, progress=False)
    assert relative_residual(heavy, data.trajectories[0]) < 1e-10


@pytest.mark.parametrize(
    "system, truth",
    [
        (CartPole(cart_mass=1.2, pole_mass=0.4, length=0.9, cart_damping=0.2, pole_damping=0.1,
                  point_inertia=1e-10),
         lambda: cart_pole(m_cart=1.2, m_pole=0.4, length=0.9, friction=(0.2, 0.1))),
        (DoublePendulum(mass1=1.0, mass2=0.6, length1=0.8, length2=0.5, damping1=0.1,
                        damping2=0.0, point_inertia=1e-10),
         lambda: double_pendulum(m1=1.0, m2=0.6, l1=0.8, l2=0.5, friction=(0.1, 0.0))),
        (CartDoublePendulum(cart_mass=1.0, mass1=0.5, mass2=0.4, length1=0.7, length2=0.5,
                            cart_damping=0.3, damping1=0.05, damping2=0.0, point_inertia=1e-10),
         lambda: cart_double_pendulum(m_cart=1.0, m1=0.5, m2=0.4, l1=0.7, l2=0.5,
                                      friction=(0.3, 0.05, 0.0))),
        (TriplePendulum(mass1=1.0, mass2=0.8, mass3=0.6, length1=0.8, length2=0.6,
                        length3=0.5, damping1=0.0, damping2=0.0, damping3=0.0,
                        point_inertia=1e-10),
         lambda: triple_pendulum(m1=1.0, m2=0.8, m3=0.6, l1=0.8, l2=0.6, l3=0.5,
                                 friction=(0.0, 0.0, 0.0))),
    ],
    ids=["cart-pole", "double-pendulum", "cart-double-pendulum", "triple-pendulum"],
)
def test_accelerations_match_independent_mechanics(system, truth):
    # the sympy.physics.mechanics derivation runs with the test, not at collection
    truth = truth()
    data = generate_dataset(system, n_trajectories=1, duration=2.0, seed=5, sample_every=10,
                            progress=False)
    tr = data.trajectories[0]
    expected = truth.accelerations(tr.q, tr.qd, tr.tau)
    np.testing.assert_allclose(tr.qdd, expected, rtol=0, atol=1e-6 * np.abs(expected).max())


@pytest.mark.parametrize("name", sorted(SYSTEMS))
def test_bob_positions_follow_textbook_convention(name):
    """theta = 0 hanging down, bob at (x + l sin theta, -l cos theta), absolute angles."""
    system = get_system(name)
    model = system.mj_model()
    data = mujoco.MjData(model)
    rng = np.random.default_rng(0)
    q = rng.uniform(-2, 2, system.n)
    data.qpos[:] = system.from_generalized(q)[0]
    mujoco.mj_forward(model, data)
    p = system.parameters
    has_cart = system.coordinate_names[0] == "x"
    x = q[0] if has_cart else 0.0
    angles = q[1:] if has_cart else q
    links = [f"link{k}" for k in range(1, len(angles) + 1)]
    lengths = [p["length"]] if name == "cart-pole" else [p[f"length{k}"]
                                                         for k in range(1, len(angles) + 1)]
    point = np.array([x, 0.0])
    bodies = ["pole"] if name == "cart-pole" else links
    for body, angle, length in zip(bodies, angles, lengths, strict=True):
        point = point + length * np.array([np.sin(angle), -np.cos(angle)])
        b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body)
        np.testing.assert_allclose(data.xipos[b][[0, 2]], point, atol=1e-12)


@pytest.mark.parametrize("name", sorted(SYSTEMS))
def test_packaged_xml_matches_default_parameters(name):
    path = default_xml_path(name)
    assert path.read_text() == get_system(name).xml()
    mujoco.MjModel.from_xml_path(str(path))


def test_transform_round_trip():
    system = CartDoublePendulum()
    rng = np.random.default_rng(1)
    q, qd = rng.normal(size=(2, 5, 3))
    qpos, qvel = system.from_generalized(q, qd)
    np.testing.assert_allclose(qpos[:, 2], q[:, 2] - q[:, 1])
    back = system.to_generalized(qpos, qvel, qvel)
    np.testing.assert_allclose(back[0], q)
    np.testing.assert_allclose(back[1], qd)


def test_parameters_are_used_and_checked():
    system = CartPole(pole_mass=0.25, gravity=3.7)
    model = system.mj_model()
    assert model.body_mass[2] == 0.25
    assert model.opt.gravity[2] == -3.7
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
    with pytest.raises(ValueError, match="pole_mass"):
        CartPole(pole_mass=-1)
    with pytest.raises(TypeError, match="length"):
        CartPole(length="long")
    with pytest.raises(ValueError, match="unknown system"):
        get_system("quadruple-pendulum")
    assert isinstance(get_system("cart_double_pendulum"), CartDoublePendulum)


USER_PENDULUM = """
<mujoco model="user_pendulum">
  <option timestep="0.001" integrator="RK4"><flag contact="disable"/></option>
  <worldbody>
    <body name="arm">
      <joint name="swing" type="hinge" axis="0 1 0" damping="0.1"/>
      <inertial pos="0 0 -0.6" mass="0.7" diaginertia="1e-8 1e-8 1e-8"/>
      <geom type="sphere" size="0.05" pos="0 0 -0.6"/>
    </body>
  </worldbody>
  <actuator><motor joint="swing" gear="2" ctrlrange="-1 1" ctrllimited="true"/></actuator>
</mujoco>
"""


def test_user_mjcf_system(tmp_path):
    path = tmp_path / "pendulum.xml"
    path.write_text(USER_PENDULUM)
    system = get_system(str(path))
    assert isinstance(system, MJCFSystem)
    assert system.coords.names == ("swing",)
    assert system.angle_coordinates == (0,)
    assert system.actuated_joints == ("swing",)
    assert system.friction() == {(system.coords.qd[0], 0): pytest.approx(0.1)}
    tr = simulate_trajectory(system, 1.0, signals=lambda t: np.sin(3 * t)[:, None], q0=[0.3])
    # gear 2 doubles the generalized force; with axis +y, the bob moves to -x for positive angles
    np.testing.assert_allclose(tr.tau[:, 0], 2 * np.sin(3 * tr.t), atol=1e-12)
    m, l, g = 0.7, 0.6, 9.81
    expected = (tr.tau[:, 0] - 0.1 * tr.qd[:, 0] - m * g * l * np.sin(tr.q[:, 0])) / (m * l**2)
    np.testing.assert_allclose(tr.qdd[:, 0], expected, rtol=1e-6, atol=1e-9)
    with pytest.raises(NotImplementedError, match="Lagrangian"):
        system.lagrangian()


def test_get_system_reads_mjcf_text_and_any_existing_file(tmp_path):
    path = tmp_path / "pendulum.model"  # a file without the .xml suffix
    path.write_text(USER_PENDULUM)
    for source in (USER_PENDULUM, str(path)):
        system = get_system(source)
        assert isinstance(system, MJCFSystem) and system.coords.names == ("swing",)
    # registry names win over files of the same name; unknown names still fail clearly
    (tmp_path / "cart-pole").write_text(USER_PENDULUM)
    assert isinstance(get_system(str(tmp_path / "cart-pole")), MJCFSystem)
    assert isinstance(get_system("cart-pole"), CartPole)
    with pytest.raises(ValueError, match="unknown system 'no-such-system'"):
        get_system("no-such-system")


def test_mujoco_package_is_lazy_and_keeps_its_public_names():
    import subprocess
    import sys

    # names of the public API contract (shared/API.md) under pysindy_xl.mujoco
    contract = ["get_system", "MJCFSystem", "generate_dataset", "load_dataset", "Dataset",
                "Trajectory", "simulate_trajectory", "validation_trajectory", "validate_model",
                "reference_catalog", "actuator_law", "start_on_reference", "kinematic_catalog"]
    code = (
        "import sys, pysindy_xl.mujoco as m\n"
        "heavy = ('mujoco', 'sympy', 'pysindy', 'sklearn', 'scipy', 'matplotlib', 'jax')\n"
        "print(sorted(h for h in heavy if h in sys.modules))\n"
        "print(sorted(n for n in m.__all__ if getattr(m, n, None) is None))\n"
        f"print(sorted(set({contract!r}) - set(m.__all__)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split("\n")
    assert out[:3] == ["[]", "[]", "[]"]


def test_user_mjcf_errors(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        MJCFSystem(tmp_path / "missing.xml")
    bad = tmp_path / "bad.xml"
    bad.write_text("<mujoco><worldbody><body>")
    with pytest.raises(ValueError, match="cannot load"):
        MJCFSystem(bad)
    free = "<mujoco><worldbody><body><freejoint/><geom size='0.1'/></body></worldbody></mujoco>"
    with pytest.raises(ValueError, match="hinge or slide"):
        MJCFSystem(free)


def test_joints_of_a_model_with_a_full_length_keyframe(tmp_path, capsys):
    from pysindy_xl.cli import main
    from pysindy_xl.mujoco import MJCFSystem

    xml = tmp_path / "keyed.xml"
    xml.write_text("""<mujoco><option timestep="0.002"/><worldbody>
      <body name="a"><joint name="j1" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.03" mass="1"/>
        <body name="b" pos="0 0 -0.5"><joint name="j2" type="hinge" axis="0 1 0"/>
          <geom type="capsule" fromto="0 0 0 0 0 -0.4" size="0.03" mass="0.5"/></body></body>
      <body name="t" pos="2 0 0"><joint name="tx" type="slide" axis="1 0 0"/>
        <joint name="ty" type="slide" axis="0 0 1"/><geom size="0.05" mass="0.2"/></body>
    </worldbody>
    <actuator><motor joint="j1"/><motor joint="j2"/><motor joint="tx"/></actuator>
    <keyframe><key name="home" qpos="0.1 0.2 0.3 0.4" qvel="0 0 0 0" ctrl="0.5 0.6 0.7"/>
    </keyframe></mujoco>""")
    system = MJCFSystem(str(xml), joints=["j1", "j2"])
    assert system.trimmed_keyframes == ("home",)
    model = system.mj_model()
    np.testing.assert_array_equal(model.key_qpos[0], [0.1, 0.2])
    np.testing.assert_array_equal(model.key_ctrl[0], [0.5, 0.6])
    assert main(["demo", str(xml), "--joints", "j1", "j2", "--duration", "1",
                 "--trajectories", "1", "--validation-duration", "0.5", "--no-plots",
                 "--out", str(tmp_path / "out")]) == 0
    assert "keyframes cut to the identified joints: home" in capsys.readouterr().out
