"""How much of each joint's torque is inertial: why a heavily damped arm identifies worse.

For each stripped Menagerie arm, one default training run (4 s, noise-free) of
:func:`~pysindy_xl.mujoco.generate_dataset`; per joint, the RMS of the inertial forces
``M(q) qdd`` (MuJoCo's ``mj_fullM``), of the joint damping forces ``d qd`` and of the
actuator torques. Where damping dominates (inertial share of a few percent), the inertia is
read off a small part of the torque: position noise, through the velocity estimate times a
large ``d``, swamps it. Prints the table; writes ``benchmarks/results/inertial_share.md``.

Usage::

    python benchmarks/inertial_share.py [ARM ...]
"""

import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def main(arms):
    import mujoco

    from pysindy_xl.mujoco import MJCFSystem, generate_dataset

    lines = ["| arm | joint damping | RMS M qdd / RMS torque per joint | RMS d qd / RMS torque |",
             "|---|---|---|---|"]
    for arm in arms:
        system = MJCFSystem(os.path.join(HERE, "models", "menagerie", f"{arm}.xml"))
        data = generate_dataset(system, n_trajectories=1, duration=4.0, seed=0,
                                sample_every=2, progress=False)
        trajectory = data.trajectories[0]
        model = system.mj_model()
        mjdata = mujoco.MjData(model)
        mass = np.zeros((model.nv, model.nv))
        inertial = np.empty_like(trajectory.q)
        for k, (q, qdd) in enumerate(zip(trajectory.q, trajectory.qdd, strict=True)):
            mjdata.qpos[:] = q  # MuJoCo evaluates one state per call
            mujoco.mj_forward(model, mjdata)
            mujoco.mj_fullM(model, mjdata, mass)
            inertial[k] = mass @ qdd
        rms = lambda x: np.sqrt(np.mean(x**2, axis=0))  # noqa: E731
        torque = rms(trajectory.tau)
        share = rms(inertial) / torque
        damped = rms(trajectory.qd * model.dof_damping) / torque
        lines.append(f"| {arm} | {' '.join(f'{d:g}' for d in model.dof_damping)} | "
                     f"{' '.join(f'{s:.2f}' for s in share)} | "
                     f"{' '.join(f'{s:.2f}' for s in damped)} |")
        print(lines[-1], flush=True)
    os.makedirs(os.path.join(HERE, "results"), exist_ok=True)
    with open(os.path.join(HERE, "results", "inertial_share.md"), "w", encoding="utf-8") as f:
        f.write("# Inertial share of the joint torques (default excitation, 4 s, seed 0)\n\n"
                + "\n".join(lines) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:] or ["ur10e", "m1013", "fr3", "xarm7", "sawyer", "lite6", "piper"])
