"""Robot arms identified from noisy encoders: pysindy-xl against IDIM-LS.

Arms (MJCF written here, realistic link masses and lengths): a 6-joint arm shaped like a UR5
and two 7-joint arms shaped like a Franka Panda and a KUKA iiwa, every joint a position servo
(``kp``, ``kv``) with armature, viscous damping and limits, MuJoCo's ``implicitfast``
integrator as published arm models use. Data: :func:`pysindy_xl.mujoco.generate_dataset`
(reference trajectories of random sums of sines inside the joint limits, recorded joint
torques ``qfrc_actuator``, RK4 where the implicit step would bias the positions), two 10 s
trajectories sampled at 250 Hz, Gaussian noise of ``p`` times each joint's standard deviation
on the positions only.

Methods, on the same data and the same kinematic catalog (base parameters, viscous and
smooth-Coulomb friction per joint):

* ``pysindy-xl``: ``XLSINDy(catalog.library())`` with its defaults (weak form on smoothed
  positions; for a kinematic catalog ``PhysicalOptimizer(EnsembleOptimizer(
  ExplicitOptimizer(threshold=0.0)))``: every parameter estimated, errors in the variables
  corrected, bagged for intervals, then the least squares under rigid bodies' constraints,
  pseudo-inertias positive semidefinite, armature and friction non-negative, when the
  estimate is not physically consistent);
* ``pysindy-xl-selected``: the same constrained fit of the terms a noise-aware bagged
  selection keeps, ``PhysicalOptimizer(EnsembleOptimizer(ExplicitOptimizer()))``;
* ``pysindy-xl-unconstrained``: the selection's estimate as it is,
  ``EnsembleOptimizer(ExplicitOptimizer())``;
* ``pysindy-xl-lmi-support`` and ``pysindy-xl-lmi-all``: the constrained fit of the
  selection with ``base_parameters="support"`` (its zeros stay zero) and ``"all"``;
* ``idim-ls``: the robotics baseline of :mod:`idim` on the catalog's rigid-body columns (the
  base-parameter regressor) with its own viscous, smooth Coulomb ``tanh(qd / 0.01)`` and
  offset columns: positions and torques low-pass filtered forwards and backwards
  (4th-order Butterworth; the cutoff and the least squares' rank tolerance with the
  smallest time-blocked held-out torque error on the training runs),
  central differences, decimation, ordinary then weighted least squares;
* ``truth``: the MJCF's own parameters (no fit): smooth dry friction against MuJoCo's
  constraint friction is the only model error left.

* ``mujoco-sysid`` (not in the default ``--methods``: minutes per fit): MuJoCo's own system
  identification (:func:`mujoco_sysid`): output error of rollouts of the MJCF under the
  recorded controls against the noisy positions, Levenberg-Marquardt on every link's
  inertial parameters, the joints' armature and damping, from the MJCF's values perturbed by
  30 %. Needs ``absl-py``, ``colorama`` and ``tabulate`` (the ``benchmarks`` extra); its
  metrics come from MuJoCo on the identified MJCF (``mj_fullM``, ``qfrc_bias``,
  ``mj_inverse``), its record's ``sysid`` holds the fit's summary and the initial guess's
  errors.

Metrics: mass-matrix error (mean over 200 random joint states of ``|M_id - M|_F / |M|_F``),
gravity-torque error (``|g_id - g| / |g|`` over the same states), torque prediction on a fresh
trajectory (worst joint's relative RMS error against the recorded torques, at MuJoCo's exact
states: the model's own error, whatever differentiated its training data), whether ``M`` is
positive definite on the states, viscous friction against the MJCF's joint damping (worst
joint's relative error), the largest dry friction identified (the arms have none), fit time;
``realizable``: whether the identified base parameters are those of rigid bodies (the
semidefinite program of :func:`pysindy_xl.physical.realize` reproduces them within 1e-4
relative, about its accuracy on the boundary of the consistent set) with non-negative
friction; ``dry_friction_relative``: the largest dry friction as a share of its joint's RMS
torque on the fresh trajectory; ``dry_friction_significant``: how many joints' dry friction has
a bagged 95 % interval that excludes zero (friction the data tell from none); for the
constrained fits,
``selection_consistent``: whether the selection's own
(unconstrained) estimate was.

Usage: ``python benchmarks/robot_arms.py [--seeds 3] [--levels 0,0.01,0.05]
[--arms ur5,panda,iiwa] [--methods pysindy-xl,idim-ls] [--jobs 2]``. Results are appended to
``benchmarks/results/robot_arms.jsonl`` as each run finishes (finished cells are skipped when
run again, so an interrupted sweep resumes) and summarized in ``robot_arms.md``.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import time
import warnings

import idim
import joblib
import numpy as np

RESULTS = pathlib.Path(__file__).resolve().parent / "results"

#: Records of older data generators are not mixed with new ones: 2 = controls held at each
#: step's midpoint, forces recorded under the continuous signal, servo runs starting on
#: their reference; 3 = integration chosen from the model's stiffness, references within the
#: servos' reach, recording after the settle time; 4 = servo runs starting where the servos
#: push nothing while moving with their reference; 5 = forced runs integrated by RK4 at
#: ``h |lambda| <= RK4_HELD_BOUND`` (the control held over each step stays faithful).
DATA_VERSION = 5

#: (axis, offset of the joint from its parent, centre of mass, mass, inertia diagonal, range)
ARMS = {
    "ur5": [("0 0 1", "0 0 0.089", "0 0 0", 3.7, "0.010 0.010 0.007", 3.0),
            ("0 1 0", "0 0.136 0", "0.212 0 0", 8.4, "0.023 0.134 0.134", 2.0),
            ("0 1 0", "0.425 -0.120 0", "0.196 0 0", 2.3, "0.003 0.031 0.031", 2.5),
            ("0 1 0", "0.392 0 0", "0 0.093 0", 1.2, "0.002 0.002 0.002", 3.0),
            ("0 0 1", "0 0.093 0", "0 0 0.095", 1.2, "0.002 0.002 0.002", 3.0),
            ("0 1 0", "0 0 0.095", "0 0.068 0", 0.19, "0.0001 0.0001 0.0001", 3.0)],
    "panda": [("0 0 1", "0 0 0.333", "0 -0.03 -0.07", 4.97, "0.70 0.70 0.009", 2.8),
              ("0 1 0", "0 0 0", "0 -0.07 0.03", 0.65, "0.008 0.028 0.025", 1.7),
              ("0 0 1", "0 0 0.316", "0.04 0.02 -0.07", 3.23, "0.037 0.036 0.010", 2.8),
              ("0 -1 0", "0.083 0 0", "-0.05 0.10 0.03", 3.59, "0.026 0.019 0.028", 2.0),
              ("0 0 1", "-0.083 0 0.384", "-0.01 0.04 -0.11", 1.23, "0.036 0.029 0.008", 2.8),
              ("0 -1 0", "0 0 0", "0.06 -0.01 0.01", 1.67, "0.002 0.004 0.005", 1.6),
              ("0 0 1", "0.088 0 -0.107", "0.01 0.01 0.08", 0.74, "0.013 0.010 0.004", 2.8)],
    "iiwa": [("0 0 1", "0 0 0.157", "0 -0.03 0.12", 3.4, "0.02 0.02 0.01", 2.9),
             ("0 1 0", "0 0 0.203", "0.0003 0.059 0.042", 3.4, "0.02 0.02 0.01", 2.0),
             ("0 0 1", "0 0 0.203", "0 0.03 0.13", 2.7, "0.02 0.02 0.01", 2.9),
             ("0 -1 0", "0 0 0.213", "0 0.067 0.034", 2.7, "0.02 0.02 0.01", 2.0),
             ("0 0 1", "0 0 0.187", "0.0001 0.021 0.076", 1.7, "0.01 0.01 0.01", 2.9),
             ("0 1 0", "0 0 0.213", "0 0.0006 0.0004", 1.8, "0.01 0.01 0.01", 2.0),
             ("0 0 1", "0 0 0.081", "0 0 0.02", 0.3, "0.001 0.001 0.001", 3.0)],
}


def arm_mjcf(name: str) -> str:
    """MJCF of one arm: servo joints with armature, damping and limits, ``implicitfast``."""
    body = ""
    for k, (axis, pos, com, mass, inertia, limit) in reversed(list(enumerate(ARMS[name]))):
        body = (f'<body name="link{k}" pos="{pos}"><joint name="j{k}" type="hinge" '
                f'axis="{axis}" range="{-limit} {limit}" armature="{0.1 / (k + 1):.4f}" '
                f'damping="{0.5 / (k + 1):.4f}"/><inertial pos="{com}" mass="{mass}" '
                f'diaginertia="{inertia}"/>{body}</body>')
    servos = "".join(
        f'<position joint="j{k}" kp="{200 / (k + 1):.1f}" kv="{10 / (k + 1):.2f}" '
        f'ctrlrange="{-0.8 * spec[5]} {0.8 * spec[5]}"/>' for k, spec in enumerate(ARMS[name]))
    return (f'<mujoco model="{name}"><compiler angle="radian"/>'
            f'<option timestep="0.002" integrator="implicitfast" '
            f'gravity="0 0 -9.81"><flag contact="disable"/></option><worldbody>{body}'
            f"</worldbody><actuator>{servos}</actuator></mujoco>")


def _data(system, level, seed, duration=10.0, n_trajectories=2):
    from pysindy_xl.mujoco import generate_dataset

    return generate_dataset(system, n_trajectories=n_trajectories, duration=duration,
                            noise=level, seed=seed, sample_every=2, progress=False)


def idim_ls(library, data):
    """The honest IDIM-LS of :mod:`idim` on the catalog's rigid-body columns (its own
    viscous, smooth Coulomb ``tanh(qd / 0.01)`` and offset columns; cutoff and rank
    tolerance by time-blocked held-out torque error on the training runs; decimation; WLS),
    as a coefficient vector over the catalog (force coefficient -1; the viscous and
    smooth-Coulomb columns take IDIM's viscous and Coulomb estimates, its offsets are left
    out: the arms have none)."""
    regressor, lagrange = idim.catalog_regressor(library)
    fit = idim.choose_cutoff(regressor, [(tr.t, tr.q, tr.tau) for tr in data.trajectories])
    names = library.get_feature_names()
    coef = np.zeros(len(names))
    coef[library.force_columns_] = -1.0
    coef[lagrange] = fit.parameters[:len(lagrange)]
    friction = fit.parameters[len(lagrange):].reshape(-1, 3)
    for j, coordinate in enumerate(library.coords.names):
        for k, name in enumerate(names):
            if name == f"C_{coordinate}[{coordinate}_dot]":
                coef[k] = friction[j, 0]
            elif name.startswith(f"C_{coordinate}[tanh(") and name.endswith(
                    f"*{coordinate}_dot)]"):
                coef[k] = friction[j, 1]
    return coef, fit.cutoff


def _realizable(catalog, library, beta, coef, tolerance=1e-4):
    """Whether base parameters ``beta`` are those of rigid bodies and friction is
    non-negative (None without cvxpy)."""
    try:
        from pysindy_xl.physical import PhysicalStructure, realize
    except ImportError:
        return None
    structure = PhysicalStructure.from_combination(list(catalog.physical_names),
                                                   catalog.combination)
    try:
        _, residual = realize(structure, beta, closeness=1e-9)
    except (ImportError, RuntimeError):
        return None
    friction = library.physical_structure().friction_columns
    return bool(residual <= tolerance and np.all(coef[friction] >= 0))


# ---------------------------------------------------------------------------------------------
# MuJoCo's own system identification (mujoco.sysid): output error over rollouts of the MJCF
# ---------------------------------------------------------------------------------------------

#: Limits of one mujoco.sysid fit: Gauss-Newton iterations and seconds (the best point reached
#: when the time runs out is kept).
SYSID_MAX_ITERS = 20
SYSID_TIME_LIMIT = 600.0


def sysid_missing() -> str | None:
    """Why ``mujoco.sysid`` cannot run here, or None."""
    try:
        import absl  # noqa: F401
        import colorama  # noqa: F401
        import tabulate  # noqa: F401
        from mujoco import sysid
    except ImportError as error:
        return (f"mujoco.sysid unavailable ({error}); pip install 'mujoco>=4.0' absl-py "
                "colorama tabulate (the 'benchmarks' extra)")
    if not hasattr(sysid, "optimize"):
        return "mujoco.sysid unavailable (its optional dependencies failed to import)"
    return None


def _perturbed_spec(xml, rng, scale=0.3):
    """The MJCF with every inertial parameter, armature and damping off by up to ``scale``.

    Mass, armature, damping and the second moments of each link's mass distribution
    (``Sigma = tr(I)/2 - I`` on the principal axes: any positive values are a physical body)
    are multiplied by ``1 + scale * u``, ``u ~ U(-1, 1)``; the centre of mass moves by up to
    ``scale`` times its distance from the joint frame along each axis."""
    import mujoco

    def factor(size=None):
        return 1 + scale * rng.uniform(-1, 1, size)

    spec = mujoco.MjSpec.from_string(xml)
    for body in spec.bodies[1:]:
        inertia = np.asarray(body.inertia, dtype=float)
        sigma = (inertia.sum() / 2 - inertia) * factor(3)
        com = np.asarray(body.ipos, dtype=float)
        body.ipos = com + scale * np.linalg.norm(com) * rng.uniform(-1, 1, 3)
        body.mass = body.mass * factor()
        body.inertia = sigma.sum() - sigma
    for joint in spec.joints:
        joint.armature = joint.armature * factor()
        joint.damping = joint.damping * factor()
    return spec


def mujoco_sysid(system, data, seed, max_iters=SYSID_MAX_ITERS, time_limit=SYSID_TIME_LIMIT,
                 log=None):
    """Identify the arm with ``mujoco.sysid``: the identified MjModel, a summary dict (with
    95 % confidence half-widths of the damping, relative) and the initial guess's MjModel.

    Output-error fit (MuJoCo's Levenberg-Marquardt over finite-difference Jacobians of
    rollouts) of every link's 10 inertial parameters (mass, centre of mass, full inertia, in
    sysid's pseudo-inertia parametrization, physical by construction), every joint's armature
    and viscous damping, starting from the MJCF's values perturbed by 30 % (seeded; see
    :func:`_perturbed_spec`). Data:
    each training trajectory's reference controls (``info["signals"]`` held at each step's
    midpoint, as the data were simulated) and its noisy joint positions, observed as the
    rollouts' ``qpos``; the rollouts use the data's own integrator (RK4) and start on the servos'
    reference at t = 0, as the data do (computed from the controls). The servo gains are
    fixed at their MJCF values: from positions and controls alone a common scale of the
    inertias, damping and gains is not identifiable (the others read it from the torques).
    No parameter scaling (``x_scale="jac"`` stalls: the columns of the unidentifiable
    parameters, e.g. the base link's inertia across its axis, are zero). At most ``max_iters``
    iterations and ``time_limit`` seconds (then the best point reached is kept). The
    optimizer's iteration log goes to ``log`` (default stderr).
    """
    import sys

    import mujoco
    from mujoco import sysid
    from mujoco.sysid._src import model_modifier

    from pysindy_xl.mujoco import SumOfSinusoids, start_on_reference

    xml = system.metadata()["model_xml"]
    rng = np.random.default_rng([seed, 30])
    spec = _perturbed_spec(xml, rng)
    spec.option.integrator = getattr(mujoco.mjtIntegrator,
                                     f"mjINT_{data.metadata['integrator'].upper()}")
    joints = [spec.joints[k].name for k in range(len(spec.joints))]
    # the positions are observed as the rollout's states (qpos at each state's own time):
    # jointpos sensors would lag a step, a rollout's sensordata being computed before the step
    observed = [(f"{name}_qpos", sysid.SignalType.MjStateQPos) for name in joints]
    guess = spec.compile()
    dt = guess.opt.timestep

    initial_states, controls, sensors = [], [], []
    for trajectory in data.trajectories:
        signals = SumOfSinusoids.from_dict(trajectory.info["signals"])
        q0, qd0 = start_on_reference(system, signals, trajectory.q[0],
                                     np.zeros(system.n))
        initial_states.append(sysid.create_initial_state(guess, q0, qd0))
        times = np.arange(int(round(trajectory.t[-1] / dt)) + 1) * dt
        controls.append(sysid.TimeSeries(times, np.asarray(signals(times + dt / 2))))
        sensors.append(sysid.TimeSeries.from_names(trajectory.t, trajectory.q, guess,
                                                   names=observed))
    sequences = sysid.ModelSequences(system.name, spec, [f"run{k}" for k in range(
        len(controls))], initial_states, controls, sensors, allow_missing_sensors=True)

    params = sysid.ParameterDict()
    for body in spec.bodies[1:]:
        def modifier(s, p, name=body.name):
            model_modifier.apply_body_theta_inertia(s, name, p.value)
            s.body(name).iquat = [1, 0, 0, 0]  # mujoco 4.0.0: NaN iquat does not compile
        params.add(sysid.body_inertia_param(
            spec, guess, body.name, sysid.InertiaType.Pseudo, modifier=modifier,
            mass_bound_mult=np.array([0.2, 5.0]), stretch_bound_mult=np.array([0.25, 4.0])))
    for name in joints:
        joint = spec.joint(name)
        for attribute in ("armature", "damping"):
            value = np.atleast_1d(getattr(joint, attribute))  # damping: [linear, ...]
            params.add(sysid.Parameter(
                f"{name}_{attribute}", value[0], 0.0, 5 * value[0],
                modifier=lambda s, p, n=name, a=attribute, v=value: setattr(
                    s.joint(n), a, np.r_[p.value[0], v[1:]] if v.size > 1 else p.value[0])))

    residual_fn = sysid.build_residual_fn(models_sequences=[sequences])
    start = time.perf_counter()
    best = {"objective": np.inf, "x": params.as_vector(), "evaluations": 0}

    class _OutOfTime(Exception):
        pass

    def bounded(x, p, **kwargs):
        if time.perf_counter() - start > time_limit:
            raise _OutOfTime
        result = residual_fn(x, p, **kwargs)
        best["evaluations"] += 1
        if x.ndim == 1 or x.shape[1] == 1:  # a trial point, not a finite-difference batch
            objective = 0.5 * float(np.sum(np.concatenate(result[0]) ** 2))
            if objective < best["objective"]:
                best.update(objective=objective, x=np.ravel(x).copy())
        return result

    log = sys.stderr if log is None else log

    def progress(trace):
        print(f"mujoco-sysid: iteration {len(trace)}, objective {trace[-1].objective:.4g}, "
              f"{time.perf_counter() - start:.0f} s", file=log, flush=True)

    summary = {"parameters": int(params.as_vector().size), "max_iters": max_iters,
               "time_limit_s": time_limit}
    try:
        # the backend's own log (full: it ends on the Jacobian at the optimum, which gives
        # the confidence intervals) is printed to ``log``
        identified, result = sysid.optimize(params, bounded, optimizer="mujoco",
                                            verbose=False, max_iters=max_iters,
                                            iter_callback=progress, output=log)
        summary["stopped"] = "converged or max_iters"
        x = identified.as_vector()
        _, intervals = sysid.calculate_intervals(residual_fn(x, identified.copy())[0],
                                                 result.jac)
        names = [n for n in identified.keys() for _ in range(identified[n].size)]
        summary["damping_ci"] = [float(w / abs(v)) for n, v, w in zip(
            names, x, intervals, strict=True) if n.endswith("_damping")]
    except _OutOfTime:
        identified = params.copy()
        identified.update_from_vector(best["x"])
        summary["stopped"] = "time limit"
    summary.update(objective=best["objective"], evaluations=best["evaluations"])
    model = model_modifier.apply_param_modifiers(identified, spec)
    return model, summary, guess


def _mjcf_metrics(model, truth, fresh, limits, rng_seed=0):
    """The benchmark's metrics of an MJCF model against the true one (MuJoCo's own
    dynamics: ``mj_fullM``, ``qfrc_bias`` at rest, ``mj_inverse``)."""
    import mujoco

    def mass_and_gravity(m, states):
        d = mujoco.MjData(m)
        mass = np.empty((len(states), m.nv, m.nv))
        gravity = np.empty((len(states), m.nv))
        for k, q in enumerate(states):
            d.qpos[:], d.qvel[:] = q, 0
            mujoco.mj_forward(m, d)
            mujoco.mj_fullM(m, d, mass[k])
            gravity[k] = d.qfrc_bias
        return mass, gravity

    rng = np.random.default_rng(rng_seed)
    q = rng.uniform(limits[:, 0], limits[:, 1], size=(200, model.nv))
    (mass, gravity), (mass_id, gravity_id) = mass_and_gravity(truth, q), mass_and_gravity(
        model, q)
    d = mujoco.MjData(model)
    predicted = np.empty_like(fresh.tau)
    for k in range(len(fresh.t)):  # inverse dynamics at MuJoCo's exact states
        d.qpos[:], d.qvel[:], d.qacc[:] = fresh.q[k], fresh.qd[k], fresh.qdd[k]
        mujoco.mj_inverse(model, d)
        predicted[k] = d.qfrc_inverse  # M qdd + bias + damping qd: the actuator torques
    joint_errors = (np.sqrt(np.mean((predicted - fresh.tau) ** 2, axis=0))
                    / np.sqrt(np.mean(fresh.tau**2, axis=0)))
    return dict(
        mass_error=float(np.mean(np.linalg.norm(mass_id - mass, axis=(1, 2))
                                 / np.linalg.norm(mass, axis=(1, 2)))),
        gravity_error=float(np.linalg.norm(gravity_id - gravity) / np.linalg.norm(gravity)),
        torque_error=float(np.max(joint_errors)),
        torque_errors=joint_errors.tolist(),  # per joint
        positive_definite=bool(np.all(np.linalg.eigvalsh(mass_id)[:, 0] > 0)),
        damping_error=float(np.max(np.abs(model.dof_damping - truth.dof_damping)
                                   / truth.dof_damping)),
        dry_friction=float(np.max(np.abs(model.dof_frictionloss), initial=0.0)),
        damping=model.dof_damping.tolist())


def run(arm, level, seed, method):
    import pysindy_xl as px
    from pysindy_xl.fitted.equations import physical_parameters
    from pysindy_xl.mujoco import MJCFSystem, kinematic_catalog

    system = MJCFSystem(arm_mjcf(arm))
    data = _data(system, level, seed)
    fresh = _data(system, 0.0, seed + 1000, duration=5.0, n_trajectories=1).trajectories[0]
    record = {"arm": arm, "level": level, "seed": seed, "method": method,
              "integrator": data.metadata["integrator"], "data": DATA_VERSION}
    if method == "mujoco-sysid":  # an MJCF identified: MuJoCo's own dynamics give the metrics
        truth = system.mj_model()
        start = time.perf_counter()
        identified, summary, guess = mujoco_sysid(system, data, seed)
        record["fit_s"] = time.perf_counter() - start
        metrics = _mjcf_metrics(identified, truth, fresh, truth.jnt_range)
        summary.update(torque_errors=metrics.pop("torque_errors"),
                       damping=metrics.pop("damping"), true_damping=truth.dof_damping.tolist())
        record.update(metrics)
        initial = _mjcf_metrics(guess, truth, fresh, truth.jnt_range)
        record["sysid"] = summary | {"initial_" + key: initial[key] for key in (
            "mass_error", "gravity_error", "torque_error", "damping_error")}
        return record
    catalog = kinematic_catalog(system)
    start = time.perf_counter()
    library = catalog.library().fit()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if method.startswith("pysindy-xl"):
            bagged = px.EnsembleOptimizer(px.ExplicitOptimizer())
            optimizer = {"pysindy-xl": None, "pysindy-xl-unconstrained": bagged,
                         "pysindy-xl-selected": px.PhysicalOptimizer(bagged)}.get(
                method, px.PhysicalOptimizer(bagged, base_parameters=method.split("-lmi-")[-1]))
            model = px.XLSINDy(library, optimizer).fit(**data.fit_arguments(forces="tau"))
            coef = model.coefficients()
            coef = -coef / coef[library.force_columns_[0]]  # force coefficient -1
            if model.coef_interval_ is not None:  # dry friction the data tell from zero
                scale = -model.coef_[library.force_columns_[0]]
                low, high = model.coef_interval_[:, _dry_columns(library)] / scale
                record["dry_friction_significant"] = int(np.sum((low > 0) | (high < 0)))
            if getattr(model, "physical_consistency_", None) is not None:
                record["selection_consistent"] = model.physical_consistency_["consistent"]
                record["constraint_cost"] = model.physical_consistency_["cost"]
        elif method == "idim-ls":
            coef, record["idim_cutoff_hz"] = idim_ls(library, data)
        else:  # the MJCF's own parameters: the floor of the torque metric
            coef = catalog.true_coefficients()
    record["fit_s"] = time.perf_counter() - start
    beta = coef[[j for j, c in enumerate(library.categories_) if c == "lagrange"]]
    friction = physical_parameters(coef, library)["friction"]
    damping = system.mj_model().dof_damping
    record["damping_error"] = float(max(
        abs(friction[name]["viscous"] - d) / d
        for name, d in zip(system.coordinate_names, damping, strict=True)))
    record["dry_friction"] = float(max(abs(f["dry"]) for f in friction.values()))
    record["realizable"] = _realizable(catalog, library, beta, coef)
    # torque prediction on the fresh trajectory's exact states (MuJoCo's): the model's own
    # error in torque space, the same for every method whatever differentiates its data
    theta = library.transform(px.stack_variables(fresh.q, fresh.qd, fresh.qdd)).reshape(
        system.n, len(fresh.t), -1)
    rest = np.setdiff1d(np.arange(theta.shape[-1]), library.force_columns_)
    predicted = (theta[:, :, rest] @ coef[rest]).T
    torque_scale = np.sqrt(np.mean(fresh.tau**2, axis=0))  # each joint's RMS torque
    torque_error = float(np.max(np.sqrt(np.mean((predicted - fresh.tau) ** 2, axis=0))
                                / torque_scale))
    record["dry_friction_relative"] = float(max(
        abs(friction[name]["dry"]) / scale
        for name, scale in zip(system.coordinate_names, torque_scale, strict=True)))
    rng = np.random.default_rng(0)
    limits = system.mj_model().jnt_range
    q = rng.uniform(limits[:, 0], limits[:, 1], size=(200, system.n))
    mass, mass_id = catalog.mass_matrix(q), catalog.mass_matrix(q, beta)
    gravity, gravity_id = catalog.gravity_torque(q), catalog.gravity_torque(q, beta)
    record.update(
        mass_error=float(np.mean(np.linalg.norm(mass_id - mass, axis=(1, 2))
                                 / np.linalg.norm(mass, axis=(1, 2)))),
        gravity_error=float(np.linalg.norm(gravity_id - gravity) / np.linalg.norm(gravity)),
        torque_error=float(torque_error),
        positive_definite=bool(np.all(np.linalg.eigvalsh((mass_id + np.swapaxes(
            mass_id, 1, 2)) / 2)[:, 0] > 0)))
    return record


def _dry_columns(library) -> list:
    """The catalog's dry-friction columns (``tanh`` of a velocity)."""
    return [j for j, name in enumerate(library.get_feature_names())
            if name.startswith("C_") and "tanh(" in name]


def summarize(records) -> str:
    cells = {}
    for r in records:
        cells.setdefault((r["arm"], r["level"], r["method"]), []).append(r)
    lines = ["| arm | noise | method | seeds | mass-matrix error (median / worst) | gravity error "
             "(median / worst) | torque prediction (median / worst) | damping error "
             "(median / worst) | largest dry friction (share of its joint's RMS torque) "
             "| M positive definite | realizable "
             "| fit (s) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for (arm, level, method), rs in sorted(cells.items()):
        def median(key, rs=rs):
            return np.median([r[key] for r in rs])

        def worst(key, rs=rs):
            return np.max([r[key] for r in rs])
        lines.append(f"| {arm} | {level:.0%} | {method} | {len(rs)} | "
                     f"{median('mass_error'):.2%} / {worst('mass_error'):.2%} | "
                     f"{median('gravity_error'):.2%} / {worst('gravity_error'):.2%} | "
                     f"{median('torque_error'):.2%} / {worst('torque_error'):.2%} | "
                     f"{median('damping_error'):.1%} / {worst('damping_error'):.1%} | "
                     f"{worst('dry_friction'):.3g}{_share(rs, 'dry_friction_relative')} | "
                     f"{sum(r['positive_definite'] for r in rs)}/{len(rs)} | "
                     f"{_count(rs, 'realizable')} | {median('fit_s'):.1f} |")
    return (f"{len(records)} runs; medians and worst cases over seeds (see robot_arms.py for "
            "the setup; fit times are wall clock on a shared 2-core machine, measured in "
            "different sessions for different methods)\n\n" + "\n".join(lines) + "\n")


def _share(records, key) -> str:
    """`` (x %)``, the largest ``key`` of the records that have it; empty when none has."""
    said = [r[key] for r in records if r.get(key) is not None]
    return f" ({max(said):.2%})" if said else ""


def _count(records, key) -> str:
    """``k/n`` of the records that say ``key`` is true, ``-`` when none says."""
    said = [r[key] for r in records if r.get(key) is not None]
    return f"{sum(said)}/{len(said)}" if said else "-"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--levels", default="0,0.01,0.05")
    parser.add_argument("--arms", default=",".join(ARMS))
    parser.add_argument("--methods", default="pysindy-xl,idim-ls,truth")
    parser.add_argument("--out", default=str(RESULTS))
    parser.add_argument("--jobs", type=int, default=1,
                        help="cells run at once (joblib processes)")
    args = parser.parse_args()
    methods = args.methods.split(",")
    if "mujoco-sysid" in methods and (reason := sysid_missing()):
        print(f"skipping mujoco-sysid: {reason}", flush=True)
        methods.remove("mujoco-sysid")
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "robot_arms.jsonl"
    records = [json.loads(line) for line in path.read_text().splitlines()] \
        if path.exists() else []
    records = [r for r in records if r.get("data") == DATA_VERSION]
    done = {(r["arm"], r["level"], r["seed"], r["method"]) for r in records}
    cells = [(arm, level, seed, method) for arm in args.arms.split(",")
             for level in map(float, args.levels.split(",")) for seed in range(args.seeds)
             for method in methods if (arm, level, seed, method) not in done]
    runs = joblib.Parallel(n_jobs=args.jobs, return_as="generator_unordered")(
        joblib.delayed(run)(*cell) for cell in cells)
    for record in runs:
        print(json.dumps(record), flush=True)
        with path.open("a") as handle:  # each finished run kept at once
            handle.write(json.dumps(record) + "\n")
        records.append(record)
    (out / "robot_arms.md").write_text(summarize(records))
    print(summarize(records))


if __name__ == "__main__":
    main()

