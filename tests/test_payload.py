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
