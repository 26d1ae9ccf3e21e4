"""MuJoCo steps under a sequence of controls, taken in C (``mujoco.rollout``) as ``mj_step`` would.

:func:`step_controls` advances an ``MjData`` by one ``mj_step`` per row of a control array,
``data.ctrl`` set to the row before its step: the loop a simulation runs between two recorded
samples. MuJoCo's ``rollout`` takes the steps without returning to Python, from the data's full
physics state (``mjSTATE_FULLPHYSICS``: time, positions, velocities, actuator states...), its
warm start (``qacc_warmstart``) and its user inputs (``mjSTATE_USER``: the applied forces,
mocap poses, active equalities, user data held, the controls row by row), so that the data
end where ``mj_step`` in a Python loop leaves them, to the bit (``tests/simulation/
test_stepping.py``), and that the warning counters go on counting. ``rollout`` stops at the
first MuJoCo warning; such a block is taken again, from its start, one ``mj_step`` at a time,
so that a run that leaves the physics (``mjWARN_BADQACC``, MuJoCo's reset) goes on exactly as
the loop would. Short blocks (under :data:`ROLLOUT_MIN_STEPS`) and a MuJoCo without
``mujoco.rollout.Rollout`` take the plain loop: the same steps.
"""

from __future__ import annotations

import importlib

import numpy as np

from .._optional import import_mujoco

__all__ = ["step_controls", "ROLLOUT_MIN_STEPS"]

#: Blocks of fewer steps are taken one ``mj_step`` at a time from Python: a call of
#: ``rollout`` (reading and setting the state, the warning counters) costs as much as a few
#: steps of a small model.
ROLLOUT_MIN_STEPS = 16


def step_controls(model, data, controls, runner=None) -> None:
    """Advance ``data`` by one ``mj_step`` per row of ``controls``, in C.

    Step ``k`` sets ``data.ctrl = controls[k]`` and calls ``mj_step(model, data)``; every other
    input (applied forces, mocap poses, active equalities) is held at its value in ``data``.
    The data end bit-identical to that loop in Python, warning counters included
    (module docstring).

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.
    data : mujoco.MjData
        Its data, advanced in place.
    controls : array of shape (n_steps, nu)
        The control of each step.
    runner : mujoco.rollout.Rollout, optional
        A single-threaded ``Rollout`` (``nthread=0``) to reuse over many calls (default: one
        made for this call). None where MuJoCo has no ``Rollout``.

    Returns
    -------
    None
        ``data`` holds the state after the last step.

    Raises
    ------
    ValueError
        If ``controls`` is not of shape (n_steps, nu).

    Examples
    --------
    A hinge under a motor, 20 steps in C and 20 in a Python loop:

    >>> mujoco = import_mujoco()
    >>> model = mujoco.MjModel.from_xml_string('''<mujoco><worldbody><body>
    ...   <joint name="j" axis="0 1 0" damping="0.1"/><geom size="0.1" pos="0 0 -0.5"/>
    ...   </body></worldbody><actuator><motor joint="j"/></actuator></mujoco>''')
    >>> controls = np.sin(np.arange(20.0))[:, None]
    >>> fast, slow = mujoco.MjData(model), mujoco.MjData(model)
    >>> step_controls(model, fast, controls)
    >>> for row in controls:
    ...     slow.ctrl[:] = row
    ...     mujoco.mj_step(model, slow)
    >>> bool(np.array_equal(fast.qpos, slow.qpos) and np.array_equal(fast.qvel, slow.qvel))
    True
    """
    mujoco = import_mujoco()
    controls = np.asarray(controls, dtype=float)
    if controls.ndim != 2 or controls.shape[1] != model.nu:
        raise ValueError(f"controls: expected an array of shape (n_steps, nu={model.nu}), got "
                         f"shape {controls.shape}")
    n_steps = len(controls)
    if runner is None and n_steps >= ROLLOUT_MIN_STEPS:
        runner = new_runner()
    if runner is None or n_steps < ROLLOUT_MIN_STEPS:
        _python_steps(mujoco, model, data, controls)
        return
    states = mujoco.mjtState
    full = int(states.mjSTATE_FULLPHYSICS)
    start = np.empty((1, mujoco.mj_stateSize(model, full)))
    mujoco.mj_getState(model, data, start[0], full)
    warm = data.qacc_warmstart.copy()[None]
    user = int(states.mjSTATE_USER)  # the controls come first in it
    inputs = np.empty((n_steps, mujoco.mj_stateSize(model, user)))
    mujoco.mj_getState(model, data, inputs[0], user)
    inputs[1:] = inputs[0]
    inputs[:, :model.nu] = controls
    counters = data.warning.number  # a view; rollout clears the counters and stops at a warning
    before = counters.copy()
    runner.rollout([model], [data], start, inputs[None], control_spec=user, skip_checks=True,
                   nstep=n_steps, initial_warmstart=warm)
    if counters.any():  # stopped at a warning: the same steps in Python, from the start
        mujoco.mj_setState(model, data, start[0], full)
        data.qacc_warmstart[:] = warm[0]
        counters[:] = before
        _python_steps(mujoco, model, data, controls)
    else:
        counters[:] = before


def new_runner():
    """A single-threaded ``mujoco.rollout.Rollout`` for :func:`step_controls`, or None.

    Returns
    -------
    mujoco.rollout.Rollout or None
        None where the installed MuJoCo has no ``Rollout`` (then the steps are taken in a
        Python loop).

    Examples
    --------
    >>> runner = new_runner()
    >>> runner is None or runner.nthread == 0
    True
    """
    import_mujoco()
    maker = getattr(importlib.import_module("mujoco.rollout"), "Rollout", None)
    return None if maker is None else maker(nthread=0)


def _python_steps(mujoco, model, data, controls) -> None:
    """One ``mj_step`` per row of ``controls``, ``data.ctrl`` set to it first."""
    for row in controls:
        data.ctrl[:] = row
        mujoco.mj_step(model, data)
