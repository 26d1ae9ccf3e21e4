"""MJCF models written to test catalogs from the kinematic tree (off-axis centres of mass, full
inertia tensors, non-parallel axes, armature, damping, springs)."""

PLANAR_ARM = """
<mujoco model="planar_arm">
  <option gravity="0 0 -9.81" timestep="0.0005" integrator="RK4">
    <flag contact="disable"/>
  </option>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" type="hinge" axis="0 1 0" damping="0.2"/>
      <inertial pos="0.05 0.01 -0.35" mass="1.3" fullinertia="0.06 0.05 0.02 0.004 -0.003 0.002"/>
      <body name="fore" pos="0.02 0 -0.7">
        <joint name="elbow" type="hinge" axis="0 1 0" damping="0.1"/>
        <inertial pos="-0.03 0.02 -0.25" mass="0.9"
                  fullinertia="0.03 0.035 0.01 -0.002 0.001 0.003"/>
        <body name="hand" pos="0 0.01 -0.5">
          <joint name="wrist" type="hinge" axis="0 1 0" damping="0.05"/>
          <inertial pos="0.04 -0.01 -0.08" mass="0.4"
                    fullinertia="0.004 0.005 0.002 0.0003 -0.0002 0.0004"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor joint="shoulder"/><motor joint="elbow"/><motor joint="wrist"/>
  </actuator>
</mujoco>
"""

SPATIAL_ARM = """
<mujoco model="spatial_arm">
  <option gravity="0 0 -9.81" timestep="0.0005" integrator="RK4">
    <flag contact="disable"/>
  </option>
  <worldbody>
    <body name="base" pos="0 0 0.3" quat="0.99 0.05 -0.08 0.1">
      <joint name="j1" type="hinge" axis="0 0 1" armature="0.02" damping="0.3"/>
      <inertial pos="0.02 -0.01 0.1" mass="2.0" fullinertia="0.02 0.025 0.015 0.001 -0.002 0.0015"/>
      <body name="shoulder" pos="0.05 0.02 0.2" euler="0.2 -0.1 0.3">
        <joint name="j2" type="hinge" axis="0 1 0.2" pos="0.01 0 0.02"
               armature="0.015" damping="0.2"/>
        <inertial pos="0.15 0.03 0.01" mass="1.5" fullinertia="0.01 0.04 0.045 0.002 0.003 -0.001"/>
        <body name="elbow" pos="0.35 0 0.03" euler="-0.3 0.2 0.1">
          <joint name="j3" type="hinge" axis="0.3 1 0" armature="0.01" damping="0.15"/>
          <inertial pos="0.12 -0.02 0.03" mass="1.0"
                    fullinertia="0.006 0.02 0.022 -0.001 0.0015 0.0008"/>
          <body name="wrist" pos="0.3 0.01 -0.02" euler="0.4 0.1 -0.2">
            <joint name="j4" type="hinge" axis="1 0.2 -0.1" pos="0 0.01 0"
                   armature="0.005" damping="0.05"/>
            <inertial pos="0.05 0.01 -0.02" mass="0.5"
                      fullinertia="0.002 0.003 0.0025 0.0002 -0.0001 0.0003"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor joint="j1"/><motor joint="j2"/><motor joint="j3"/><motor joint="j4"/>
  </actuator>
</mujoco>
"""

CART_DOUBLE_PENDULUM = """
<mujoco model="cart_two_link">
  <option gravity="0 0 -9.81" timestep="0.0005" integrator="RK4">
    <flag contact="disable"/>
  </option>
  <worldbody>
    <body name="cart" pos="0 0 0.5">
      <joint name="rail" type="slide" axis="1 0 0.1" damping="0.4" armature="0.05"/>
      <inertial pos="0.03 0.02 -0.01" mass="1.2" fullinertia="0.02 0.03 0.04 0.001 0.002 0.003"/>
      <body name="link1" pos="0.05 0.1 0" quat="0.98 0.1 0.05 0.0">
        <joint name="hinge1" type="hinge" axis="0 1 0" pos="0 0 0.02" damping="0.05"
               stiffness="0.8" springref="0.2"/>
        <inertial pos="0.03 0.01 -0.3" mass="0.6"
                  fullinertia="0.02 0.021 0.003 0.001 -0.002 0.0015"/>
        <body name="link2" pos="0.01 0.05 -0.6" euler="0.1 0 0.2">
          <joint name="hinge2" type="hinge" axis="0.1 1 0" damping="0.03" ref="0.1"/>
          <inertial pos="-0.02 0.01 -0.2" mass="0.4"
                    fullinertia="0.008 0.009 0.002 -0.0005 0.0007 0.0003"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor joint="rail"/><motor joint="hinge1"/><motor joint="hinge2"/>
  </actuator>
</mujoco>
"""


def serial_arm(n_joints: int) -> str:
    """A spatial serial arm of ``n_joints`` hinges with alternating, tilted axes."""
    axes = ["0 0 1", "0 1 0.1", "0.1 1 0", "1 0 0.2", "0 1 0", "0.2 0 1", "1 0.1 0"]
    body = ""
    for k in reversed(range(n_joints)):
        body = f"""
<body name="l{k}" pos="{0.05 * (k % 2)} 0.02 {0.3 if k else 0.1}"
      euler="{0.1 * k} -0.05 {0.07 * k}">
  <joint name="q{k}" type="hinge" axis="{axes[k % len(axes)]}" armature="0.01" damping="0.1"/>
  <inertial pos="0.02 0.01 {0.12 + 0.01 * k}" mass="{1.5 - 0.15 * k}"
            fullinertia="0.01 0.012 0.008 0.001 -0.0005 0.0007"/>
  {body}
</body>"""
    motors = "".join(f'<motor joint="q{k}"/>' for k in range(n_joints))
    return (f'<mujoco model="arm{n_joints}"><option gravity="0 0 -9.81"><flag contact="disable"/>'
            f"</option><worldbody>{body}</worldbody><actuator>{motors}</actuator></mujoco>")


def robot_arm(n_joints: int) -> str:
    """A robot-like serial arm: axes along the link frames (yaw, pitch, pitch, roll, pitch,
    roll, ...), link offsets, off-axis centres of mass, full inertias, armature, damping."""
    axes = ["0 0 1", "0 1 0", "0 1 0", "1 0 0", "0 1 0", "1 0 0", "0 0 1"]
    offsets = ["0 0 0.2", "0 0.05 0.1", "0.35 -0.03 0", "0.3 0 0", "0.1 0 0", "0.08 0 0",
               "0.05 0 0"]
    body = ""
    for k in reversed(range(n_joints)):
        body = f"""
<body name="r{k}" pos="{offsets[k]}">
  <joint name="a{k}" type="hinge" axis="{axes[k]}" armature="0.01" damping="0.1"/>
  <inertial pos="{0.05 + 0.01 * k} 0.01 -0.02" mass="{1.5 - 0.15 * k}"
            fullinertia="0.01 0.012 0.008 0.001 -0.0005 0.0007"/>
  {body}
</body>"""
    motors = "".join(f'<motor joint="a{k}"/>' for k in range(n_joints))
    return (f'<mujoco model="robot{n_joints}"><option gravity="0 0 -9.81" timestep="0.0005" '
            f'integrator="RK4"><flag contact="disable"/></option><worldbody>{body}</worldbody>'
            f"<actuator>{motors}</actuator></mujoco>")


# Two hinges and a slide on one body (applied in order, about anchors), a body welded to the
# world, and a jointless body welded inside the chain.
MULTI_JOINT_BODY = """
<mujoco model="gimbal">
  <option gravity="0 0 -9.81"><flag contact="disable"/></option>
  <worldbody>
    <body name="mount" pos="0 0 1" euler="0.1 0.2 0">
      <inertial pos="0 0 0.1" mass="3" diaginertia="0.1 0.1 0.1"/>
      <body name="gimbal" pos="0.1 0 0" euler="0 0.3 0.2">
        <joint name="pan" type="hinge" axis="0 0 1" pos="0.02 0.01 0" armature="0.01"/>
        <joint name="tilt" type="hinge" axis="0 1 0.3" pos="0 0.03 -0.02"/>
        <joint name="extend" type="slide" axis="1 0 0.2"/>
        <inertial pos="0.1 0.02 -0.05" mass="1.2"
                  fullinertia="0.02 0.03 0.025 0.002 -0.001 0.003"/>
        <body name="bracket" pos="0.2 0 -0.1" euler="0.3 0 0">
          <inertial pos="0.03 0.01 0" mass="0.3"
                    fullinertia="0.002 0.003 0.0025 0.0002 0.0001 -0.0003"/>
          <body name="tip" pos="0.1 0 0">
            <joint name="spin" type="hinge" axis="1 0 0" ref="0.4"/>
            <inertial pos="0.02 0.01 0.01" mass="0.2"
                      fullinertia="0.001 0.002 0.0015 0.0001 0.0002 -0.0001"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
