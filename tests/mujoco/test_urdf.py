"""URDF robot descriptions: MJCFSystem and the kinematic catalog read them with their inertials.

Ground truth: Pinocchio (``crba``, ``computeGeneralizedGravity``) on the same URDF, and MuJoCo's
``mj_fullM`` / ``qfrc_bias`` on the compiled model.
"""

from __future__ import annotations

import importlib.metadata
import pathlib
import pickle
import re
import warnings

import numpy as np
import pytest
from support.files import MODELS

mujoco = pytest.importorskip("mujoco")

from pysindy_xl.mujoco import MJCFSystem, get_system, kinematic_catalog  # noqa: E402
from pysindy_xl.mujoco.systems.registry import system_from_metadata  # noqa: E402

KINOVA = MODELS / "kinova_gen3.urdf"

# a revolute shoulder, a tool fixed to the upper arm (fused into it), a revolute elbow with
# damping, a prismatic slide; meshes that do not exist
SMALL = """<?xml version="1.0"?>
<robot name="small">
  <link name="world"/>
  <link name="upper">
    <inertial><origin xyz="0.05 0.01 -0.3" rpy="0.2 0 0.1"/><mass value="2.0"/>
      <inertia ixx="0.05" iyy="0.04" izz="0.02" ixy="0.001" ixz="-0.002" iyz="0.003"/></inertial>
    <visual><geometry><mesh filename="package://small/meshes/upper.dae"/></geometry></visual>
    <collision><geometry><mesh filename="package://small/meshes/upper.stl"/></geometry>
    </collision>
  </link>
  <link name="tool">
    <inertial><origin xyz="0.02 0 0.05"/><mass value="0.7"/>
      <inertia ixx="0.003" iyy="0.002" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="meshes/tool.stl"/></geometry></visual>
  </link>
  <link name="fore">
    <inertial><origin xyz="0 0.02 -0.25"/><mass value="1.2"/>
      <inertia ixx="0.02" iyy="0.025" izz="0.01" ixy="0" ixz="0.001" iyz="0"/></inertial>
  </link>
  <link name="slider">
    <inertial><origin xyz="0.01 0 0"/><mass value="0.4"/>
      <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="world"/><child link="upper"/><origin xyz="0 0 1" rpy="0 0.3 0"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="50" velocity="3"/>
  </joint>
  <joint name="mount" type="fixed">
    <parent link="upper"/><child link="tool"/><origin xyz="0.1 0 -0.2" rpy="0 0 0.5"/>
  </joint>
  <joint name="elbow" type="continuous">
    <parent link="upper"/><child link="fore"/><origin xyz="0 0 -0.6" rpy="0.1 0 0"/>
    <axis xyz="1 0 0"/><dynamics damping="0.3" friction="0.1"/>
  </joint>
  <joint name="extend" type="prismatic">
    <parent link="fore"/><child link="slider"/><origin xyz="0 0 -0.5"/>
    <axis xyz="0 0 1"/><limit lower="-0.1" upper="0.1" effort="20" velocity="1"/>
  </joint>
</robot>
"""


def _robot_data_path(relative):
    """A URDF of the ``example-robot-data`` package, None without it."""
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    path = dist.locate_file(f"cmeel.prefix/share/example-robot-data/robots/{relative}")
    return pathlib.Path(path) if pathlib.Path(path).is_file() else None


def _ur5_path():
    return _robot_data_path("ur_description/urdf/ur5_robot.urdf")


def _balanced(text: str) -> str:
    """The URDF with each impossible inertia tensor made isotropic with the mean principal
    moment (MuJoCo's balanceinertia), written independently of the package."""
    def fix(match):
        values = {k: float(v) for k, v in re.findall(r'(i[xyz]{2})="\s*([^"]+)"',
                                                     match.group(0))}
        tensor = np.array([[values["ixx"], values["ixy"], values["ixz"]],
                           [values["ixy"], values["iyy"], values["iyz"]],
                           [values["ixz"], values["iyz"], values["izz"]]])
        moments = np.sort(np.linalg.eigvalsh(tensor))
        if moments[0] + moments[1] >= moments[2]:
            return match.group(0)
        mean = float(moments.mean())
        return (f'<inertia ixx="{mean!r}" iyy="{mean!r}" izz="{mean!r}" ixy="0" ixz="0" '
                'iyz="0"/>')
    return re.sub(r"<inertia [^>]*/>", fix, text)


def _pinocchio_dynamics(text: str, q: np.ndarray, joint_names):
    """Pinocchio's mass matrix and gravity at ``q`` (MuJoCo joint order and angles)."""
    pin = pytest.importorskip("pinocchio")
    model = pin.buildModelFromXML(text)
    data = model.createData()
    order = [model.getJointId(name) for name in joint_names]
    assert all(0 < j < model.njoints for j in order)
    masses, gravities = [], []
    for sample in q:
        configuration = pin.neutral(model)
        for value, j in zip(sample, order, strict=True):
            joint = model.joints[j]
            if joint.nq == 2:  # continuous joint: (cos, sin)
                configuration[joint.idx_q:joint.idx_q + 2] = np.cos(value), np.sin(value)
            else:
                configuration[joint.idx_q] = value
        mass = pin.crba(model, data, configuration)
        mass = np.triu(mass) + np.triu(mass, 1).T
        velocity_index = [model.joints[j].idx_v for j in order]
        masses.append(mass[np.ix_(velocity_index, velocity_index)])
        gravities.append(pin.computeGeneralizedGravity(model, data, configuration)[velocity_index])
    return np.array(masses), np.array(gravities)


def _mujoco_dynamics(system, q):
    model = system.mj_model()
    data = mujoco.MjData(model)
    masses, bias = [], []
    for sample in q:
        data.qpos[:] = sample
        data.qvel[:] = 0.0
        mujoco.mj_forward(model, data)
        full = np.zeros((model.nv, model.nv))
        try:
            mujoco.mj_fullM(model, data, full)  # MuJoCo >= 3.4
        except TypeError:
            mujoco.mj_fullM(model, full, data.qM)
        masses.append(full)
        bias.append(data.qfrc_bias.copy())
    return np.array(masses), np.array(bias)


def _random_q(system, n=6, seed=0):
    rng = np.random.default_rng(seed)
    return np.array([system.random_initial_state(rng)[0] for _ in range(n)])


def _relative(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


def test_small_urdf_loads_without_its_meshes_with_motors_and_fused_fixed_joint(tmp_path):
    path = tmp_path / "small.urdf"
    path.write_text(SMALL)
    system = MJCFSystem(path)
    model = system.mj_model()
    assert system.coordinate_names == ("shoulder", "elbow", "extend")
    assert system.actuated_joints == ("shoulder", "elbow", "extend")
    assert model.nu == 3 and model.ngeom == 0
    # the fixed tool is fused into the upper arm: its mass loads the parent body
    assert model.nbody == 4
    assert np.isclose(model.body_mass[model.body("upper").id], 2.7)
    np.testing.assert_allclose(system.joint_damping, [0.0, 0.3, 0.0])
    np.testing.assert_allclose(system.frictionloss, [0.0, 0.1, 0.0])
    assert 0 in system.angle_coordinates and 2 not in system.angle_coordinates
    # registry, text and metadata round trips give the same model
    assert get_system(str(path)).coordinate_names == system.coordinate_names
    assert MJCFSystem(SMALL).xml() == system.xml()
    meta = system.metadata()
    assert meta["model_path"] == str(path.resolve())
    for recorded in (meta, {**meta, "model_path": str(tmp_path / "gone.urdf")}):
        rebuilt = system_from_metadata({"system": "mjcf", **recorded})
        assert rebuilt.mj_model().nu == 3
    locked = MJCFSystem(path, joints=["shoulder", "elbow"])
    assert locked.excluded_joints == ("extend",) and locked.mj_model().nu == 2


def test_small_urdf_catalog_matches_pinocchio_and_mujoco(tmp_path):
    path = tmp_path / "small.urdf"
    path.write_text(SMALL)
    system = MJCFSystem(path)
    catalog = kinematic_catalog(system)
    q = _random_q(system)
    mass, gravity = catalog.mass_matrix(q), catalog.gravity_torque(q)
    mj_mass, mj_bias = _mujoco_dynamics(system, q)
    assert _relative(mass, mj_mass) < 1e-8 and _relative(gravity, mj_bias) < 1e-8
    pin_mass, pin_gravity = _pinocchio_dynamics(SMALL, q, system.joint_names)
    assert _relative(mass, pin_mass) < 1e-9 and _relative(gravity, pin_gravity) < 1e-9
    # the path itself, and a pickled system, give the same catalog
    same = kinematic_catalog(str(path))
    assert same.lagrange_terms == catalog.lagrange_terms
    np.testing.assert_allclose(same.mass_matrix(q), mass, rtol=1e-12)
    assert pickle.loads(pickle.dumps(system)).xml() == system.xml()


def test_fusestatic_false_keeps_the_fixed_link_with_the_same_dynamics(tmp_path):
    text = SMALL.replace('<robot name="small">', '<robot name="small"><mujoco><compiler '
                         'fusestatic="false" discardvisual="true"/></mujoco>')
    fused, kept = MJCFSystem(SMALL), MJCFSystem(text)
    assert kept.mj_model().nbody == fused.mj_model().nbody + 1
    q = _random_q(fused, 3)
    for a, b in zip(_mujoco_dynamics(kept, q), _mujoco_dynamics(fused, q), strict=True):
        assert _relative(a, b) < 1e-12


def test_kinova_gen3_balances_its_impossible_inertias_and_matches_pinocchio():
    with pytest.warns(UserWarning, match="shoulder_link.*spherical_wrist_1_link"):
        system = MJCFSystem(KINOVA)
    assert system.n == 7 and system.mj_model().nu == 7
    q = _random_q(system, 8)
    mj_mass, mj_bias = _mujoco_dynamics(system, q)
    pin_mass, pin_gravity = _pinocchio_dynamics(_balanced(KINOVA.read_text()), q,
                                                system.joint_names)
    assert _relative(mj_mass, pin_mass) < 1e-5 and _relative(mj_bias, pin_gravity) < 1e-5
    # the balancing is what stands between the two: the URDF's own values differ
    raw_mass, _ = _pinocchio_dynamics(KINOVA.read_text(), q, system.joint_names)
    assert _relative(mj_mass, raw_mass) > 1e-3


def test_ur5_from_example_robot_data_matches_pinocchio():
    path = _ur5_path()
    if path is None:
        pytest.skip("example-robot-data is not installed")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # consistent inertias: nothing balanced
        system = MJCFSystem(path)
    assert system.n == 6 and system.mj_model().nu == 6
    q = _random_q(system, 8)
    mj_mass, mj_bias = _mujoco_dynamics(system, q)
    pin_mass, pin_gravity = _pinocchio_dynamics(path.read_text(), q, system.joint_names)
    assert _relative(mj_mass, pin_mass) < 1e-6 and _relative(mj_bias, pin_gravity) < 1e-6


@pytest.mark.slow
@pytest.mark.parametrize("robot", ["kinova", "ur5"])
def test_robot_catalog_matches_pinocchio(robot):
    if robot == "kinova":
        with pytest.warns(UserWarning):
            system = MJCFSystem(KINOVA)
        text = _balanced(KINOVA.read_text())
    else:
        path = _ur5_path()
        if path is None:
            pytest.skip("example-robot-data is not installed")
        system, text = MJCFSystem(path), path.read_text()
    catalog = kinematic_catalog(system)
    q = _random_q(system, 8)
    pin_mass, pin_gravity = _pinocchio_dynamics(text, q, system.joint_names)
    assert _relative(catalog.mass_matrix(q), pin_mass) < 1e-5
    assert _relative(catalog.gravity_torque(q), pin_gravity) < 1e-5


def test_a_broken_urdf_is_refused_with_the_argument_named(tmp_path):
    with pytest.raises(ValueError, match="source"):
        MJCFSystem('<robot name="r"><link name="a"/><joint name="j" type="revolute">'
                   '<parent link="a"/><child link="missing"/></joint></robot>')
    path = tmp_path / "bad.urdf"
    path.write_text("<robot><link")
    with pytest.raises(ValueError, match="bad.urdf"):
        MJCFSystem(path)
    with pytest.raises(ValueError, match="does not exist"):
        MJCFSystem(tmp_path / "absent.urdf")


def test_identify_locks_the_joints_a_log_does_not_record(tmp_path, capsys):
    """A 7-joint arm's log with a URDF that also has its gripper (two fingers, the second a
    mimic joint): ``identify`` locks the fingers at their reference pose, and the arm's mass
    matrix is the full model's block of the arm's joints there (MuJoCo's ``mj_fullM``)."""
    from pysindy_xl.cli import build_parser
    from pysindy_xl.cli.commands import _identify_inputs

    urdf = _robot_data_path("panda_description/urdf/panda.urdf")
    if urdf is None:
        pytest.skip("example-robot-data is not installed")
    names = [f"panda_joint{k}" for k in range(1, 8)]
    t = np.arange(0.0, 1.0, 0.002)
    q = 0.4 * np.sin(np.outer(t, 0.5 + np.arange(7) * 0.3))
    data = tmp_path / "log.csv"
    np.savetxt(data, np.column_stack([t, q]), delimiter=",", comments="",
               header=",".join(["t", *names]))
    dataset, system = _identify_inputs(build_parser().parse_args(
        ["identify", str(data), "--system", str(urdf)]))
    assert "locked at their reference pose: panda_finger_joint1, panda_finger_joint2" in (
        capsys.readouterr().err)
    assert system.coordinate_names == tuple(names) and dataset.n == 7
    full = MJCFSystem(str(urdf)).mj_model()
    locked = system.mj_model()
    for m in (full, locked):
        data_m = mujoco.MjData(m)
        data_m.qpos[:7] = q[100]
        mujoco.mj_forward(m, data_m)
        matrix = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, data_m, matrix)
        if m is full:
            expected = matrix[:7, :7]
    np.testing.assert_allclose(matrix, expected, rtol=1e-10, atol=1e-12)
