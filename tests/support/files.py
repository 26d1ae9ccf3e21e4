"""Model files of ``tests/models`` and exact pendulum data written as a user's CSV files."""

import pathlib

import numpy as np

#: folder of the MJCF and URDF models used by the tests
MODELS = pathlib.Path(__file__).resolve().parents[1] / "models"

#: CSV header of :func:`two_trajectories` (time, coordinate, its derivatives, force, run id)
HEADER = ["t", "theta", "theta_dot", "theta_ddot", "tau_theta", "trajectory"]


def pendulum(n=101, phase=0.0):
    """Exact damped pendulum data: 0.5 qdd + 0.2 qd + 4.9 sin q = tau."""
    t = np.linspace(0.0, 2.0, n)
    q = np.sin(1.3 * t + phase) + 0.3 * np.sin(3.1 * t)
    qd = 1.3 * np.cos(1.3 * t + phase) + 0.93 * np.cos(3.1 * t)
    qdd = -1.69 * np.sin(1.3 * t + phase) - 0.3 * 3.1**2 * np.sin(3.1 * t)
    tau = 0.5 * qdd + 0.2 * qd + 4.9 * np.sin(q)
    return t, q, qd, qdd, tau


def write_csv(path, header, columns, delimiter=","):
    """Write ``columns`` under ``header`` to ``path`` (exact float reprs); return ``path``."""
    rows = [delimiter.join(header)]
    rows += [delimiter.join(repr(float(v)) for v in row) for row in zip(*columns, strict=True)]
    path.write_text("\n".join(rows) + "\n")
    return path


def two_trajectories():
    """Two exact pendulum runs of 201 samples stacked, with a trajectory-id column last."""
    a, b = pendulum(201), pendulum(201, phase=0.7)
    columns = [np.r_[x, y] for x, y in zip(a, b, strict=True)]
    return columns + [np.r_[np.full(201, 1.0), np.full(201, 2.0)]]


#: A two-link URDF arm (continuous joints about y, joint damping) for URDF and ROS-bag tests.
TWO_LINK_URDF = """<robot name="arm">
  <link name="base"/>
  <link name="upper"><inertial><origin xyz="0 0 -0.25"/><mass value="1.0"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="fore"><inertial><origin xyz="0 0 -0.2"/><mass value="0.6"/>
    <inertia ixx="0.005" iyy="0.005" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="shoulder" type="continuous"><parent link="base"/><child link="upper"/>
    <axis xyz="0 1 0"/><dynamics damping="0.05"/></joint>
  <joint name="elbow" type="continuous"><parent link="upper"/><child link="fore"/>
    <origin xyz="0 0 -0.5"/><axis xyz="0 1 0"/><dynamics damping="0.03"/></joint>
</robot>
"""
