"""Payload identification on MuJoCo data of an arm carrying a known load on its last body."""

import numpy as np
import pytest
from kinematic_models import robot_arm

from pysindy_xl.mujoco import MJCFSystem, generate_dataset, identify_payload, kinematic_catalog
from pysindy_xl.physical import pseudo_inertia_matrix

pytest.importorskip("cvxpy")

MASS, POSITION, COM, INERTIA = 0.7, np.array([0.06, 0.02, -0.01]), np.array([0.0, 0.01, 0.03]), \
    np.array([0.002, 0.003, 0.0015])


@pytest.fixture(scope="module")
def loaded_run():
    arm = robot_arm(3)
    load = (f'<body name="load" pos="{" ".join(map(str, POSITION))}"><inertial '
            f'pos="{" ".join(map(str, COM))}" mass="{MASS}" '
            f'diaginertia="{" ".join(map(str, INERTIA))}"/></body></body>')
    loaded = arm.replace("</body>", load, 1)  # inside the innermost (last) body
    run = generate_dataset(MJCFSystem(loaded), n_trajectories=1, duration=2.0, seed=0,
                           sample_every=4, progress=False).trajectories[0]
    return kinematic_catalog(MJCFSystem(arm)), run, arm, loaded


def test_the_payload_from_noisy_positions_and_an_identified_arm(loaded_run):
    import pysindy_xl as px

    catalog, _, arm, loaded = loaded_run
    options = dict(n_trajectories=1, duration=4.0, sample_every=4, noise=0.002, progress=False)
    unloaded = generate_dataset(MJCFSystem(arm), seed=1, **options)
    model = px.XLSINDy(catalog.library()).fit(**unloaded.fit_arguments(forces="tau"))
    run = generate_dataset(MJCFSystem(loaded), seed=2, **options).trajectories[0]
    assert run.qd is None  # positions only: the model's smoother estimates the derivatives
    payload = identify_payload(catalog, run.q, run.t, run.tau, arm=model)
    assert payload.mass == pytest.approx(MASS, rel=0.05)
    np.testing.assert_allclose(payload.com, POSITION + COM, atol=0.01)
    assert np.linalg.eigvalsh(pseudo_inertia_matrix(payload.parameters))[0] > -1e-9


def test_the_payload_of_a_loaded_run_is_found(loaded_run):
    catalog, run, _, _ = loaded_run
    payload = identify_payload(catalog, run.q, run.t, run.tau, run.qd, run.qdd)
    assert payload.body == "r2"
    assert payload.mass == pytest.approx(MASS, rel=1e-4)
    np.testing.assert_allclose(payload.com, POSITION + COM, atol=1e-4)
    assert payload.residual < 1e-4  # the loaded torques explained (the SDP's tolerance)
    assert np.linalg.eigvalsh(pseudo_inertia_matrix(payload.parameters))[0] > -1e-9
    # the inertia about the centre of mass, in the directions the run determines
    if payload.identifiable == 10:
        np.testing.assert_allclose(payload.inertia, np.diag(INERTIA), atol=1e-4)
    # the same with the arm given as its coefficients (None: the MJCF's nominal ones)
    again = identify_payload(catalog, run.q, run.t, run.tau, run.qd, run.qdd,
                             arm=catalog.true_coefficients())
    np.testing.assert_allclose(again.parameters, payload.parameters, rtol=1e-6, atol=1e-9)


def test_bad_payload_inputs_are_named(loaded_run):
    catalog, run, _, _ = loaded_run
    with pytest.raises(ValueError, match="body"):
        identify_payload(catalog, run.q, run.t, run.tau, run.qd, run.qdd, body="nowhere")
    with pytest.raises(ValueError, match="tau"):
        identify_payload(catalog, run.q, run.t, run.tau[:, :2], run.qd, run.qdd)
    with pytest.raises(ValueError, match="t:"):
        identify_payload(catalog, run.q, run.t[1:], run.tau)
    with pytest.raises(ValueError, match="arm"):
        identify_payload(catalog, run.q, run.t, run.tau, run.qd, run.qdd, arm=np.zeros(3))


def test_the_payload_forces_are_mujocos_loaded_minus_unloaded_inverse_dynamics(loaded_run):
    import mujoco

    from pysindy_xl.mujoco import Payload

    catalog, run, arm, loaded = loaded_run
    com = POSITION + COM  # in the last body's frame (the load body is not rotated)
    about_origin = np.diag(INERTIA) + MASS * (com @ com * np.eye(3) - np.outer(com, com))
    parameters = np.r_[MASS, MASS * com, np.diag(about_origin), about_origin[0, 1],
                       about_origin[0, 2], about_origin[1, 2]]
    payload = Payload("r2", parameters, MASS, com, np.diag(INERTIA), 10, 0.0)
    rng = np.random.default_rng(3)
    q, qd, qdd = rng.uniform(-2, 2, (3, 50, run.q.shape[1]))
    inverse = []
    for xml in (loaded, arm):
        model = mujoco.MjModel.from_xml_string(xml)
        data = mujoco.MjData(model)
        rows = []
        for k in range(len(q)):  # a test's reference, not library code
            data.qpos[:], data.qvel[:], data.qacc[:] = q[k], qd[k], qdd[k]
            mujoco.mj_inverse(model, data)
            rows.append(data.qfrc_inverse.copy())
        inverse.append(np.array(rows))
    expected = inverse[0] - inverse[1]
    assert np.abs(expected).max() > 0.1  # the load matters at these states
    np.testing.assert_allclose(payload.forces(catalog, q, qd, qdd), expected, rtol=1e-6,
                               atol=1e-8 * np.abs(expected).max())
    with pytest.raises(ValueError, match="qdd"):
        payload.forces(catalog, q, qd, qdd[:, :1])
