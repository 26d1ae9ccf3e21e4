"""Running the grid: one task = data, identification, validation, one record.

:func:`run_grid` sends the pending tasks to :class:`joblib.Parallel` (local processes, Dask or
Ray: :func:`backend_context`) and appends each record as its run finishes: an interrupted
grid resumes where it stopped. Each run goes to a forked child killed after ``timeout``
seconds (``isolation="process"``; without fork, ``"signal"`` uses ``signal.setitimer``), so
neither a hang in C code nor a crash takes a worker down. No local process outlives the grid
(:mod:`.lifetime`): Ctrl-C and SIGTERM stop it with the finished records kept. With runs in
parallel, BLAS gets one thread per run (``blas_threads="auto"``). A trajectory's data are
simulated once per process and cached; the clean motions' seed does not depend on the noise
level, so a grid's noise levels perturb the same motions."""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import time
import warnings

import numpy as np

from .grid import GridSettings, Task, TrajectorySpec
from .isolation import (
    RunTimeout,
    blas_thread_limit,
    resolve_blas_threads,
    resolve_isolation,
    run_in_process,
    run_with_signal,
)
from .lifetime import sigterm_as_interrupt, watch_grid
from .records import RecordStore, base_record, failed_record, finish_record, json_finite

__all__ = ["run_task", "execute_task", "run_grid", "system_for", "trajectory_data",
           "backend_context", "blas_thread_limit", "RunTimeout"]


def system_for(spec: TrajectorySpec):
    """The MuJoCo system of a trajectory, joint damping scaled by its friction level.

    Parameters
    ----------
    spec : TrajectorySpec
        The trajectory.

    Returns
    -------
    MuJoCoSystem
        The registry system with its joint damping multiplied by ``spec.friction``.
    """
    from ..mujoco import get_system
    base = get_system(spec.system)
    damping = {k: v * spec.friction for k, v in base.parameters.items() if "damping" in k}
    if not damping and spec.friction != 1.0:
        raise ValueError(f"friction: system {spec.system!r} has no damping parameter to scale")
    return get_system(spec.system, **damping)


def _seed(*parts) -> int:
    text = "/".join(map(str, parts))
    return int.from_bytes(hashlib.sha256(text.encode()).digest()[:4], "little")


@functools.lru_cache(maxsize=4)
def trajectory_data(spec: TrajectorySpec, n_trajectories: int, duration: float,
                    sample_every: int, validation_duration: float):
    """``(dataset, validation, seconds)`` of a grid trajectory, cached per process: the noisy
    training :class:`~pysindy_xl.data.Dataset`, a fresh noise-free validation trajectory with
    the same forcing, and the time spent simulating.

    Parameters
    ----------
    spec : TrajectorySpec
        The trajectory.
    n_trajectories : int
        Training trajectories.
    duration : float
        Seconds of each.
    sample_every : int
        Every k-th MuJoCo step kept.
    validation_duration : float
        Seconds of the validation trajectory.

    Returns
    -------
    dataset : pysindy_xl.data.Dataset
        The noisy training data.
    validation : pysindy_xl.data.Trajectory
        The noise-free validation trajectory.
    seconds : float
        Time spent simulating.
    """
    from ..data import Dataset, add_noise
    from ..evaluation.validation import validation_trajectory
    from ..mujoco import generate_dataset
    start = time.perf_counter()
    system = system_for(spec)
    motion_seed = _seed(spec.system, spec.friction, spec.forcing, spec.seed)
    clean = generate_dataset(system, n_trajectories=n_trajectories, duration=duration,
                             forcing=spec.forcing, noise=0.0, seed=motion_seed,
                             sample_every=sample_every, progress=False)
    if spec.noise > 0:
        rng = np.random.default_rng(_seed(motion_seed, "noise", spec.noise))
        matrix = system.force_matrix()
        positions_only = spec.noise_model == "positions"
        levels = ({"q": spec.noise} if positions_only
                  else dict.fromkeys(("q", "qd", "qdd", "tau"), spec.noise))
        noisy = [add_noise(tr, levels, rng, matrix) for tr in clean.trajectories]
        if positions_only:  # a sensor records positions: the package estimates the rest
            for trajectory in noisy:
                trajectory.qd = trajectory.qdd = None
        metadata = dict(clean.metadata, noise=levels, noise_model=spec.noise_model,
                        derivatives="none" if positions_only else "mujoco")
        clean = Dataset(noisy, clean.coordinate_names, metadata)
    validation = validation_trajectory(system, validation_duration, spec.forcing,
                                       seed=_seed(motion_seed, "validation"),
                                       sample_every=sample_every)
    return clean, validation, time.perf_counter() - start


def _optimizer(solver: str):
    import pysindy_xl as px
    return {"explicit": px.ExplicitOptimizer, "implicit": px.ImplicitOptimizer,
            "mixed": px.MixedOptimizer}[solver]()


def _identify(task: Task, system, dataset):
    """Fit one configuration; returns the model (anything with ``simulate``)."""
    import pysindy_xl as px

    from ..mujoco.catalogs.reference import reference_catalog
    forced = task.trajectory.forcing != "implicit"
    arguments = dataset.fit_arguments(forces="tau" if forced else None)
    catalog = reference_catalog(system, task.catalog)
    if task.solver == "pysindy":
        from .baseline import SINDyBaseline, baseline_terms
        catalog.fit()
        if arguments["x_dot"] is None:  # positions only: derivatives of the smoothed data
            smoothed = [px.WhittakerSmoother().smooth(t, x)
                        for x, t in zip(arguments["x"], arguments["t"], strict=True)]
            arguments = dict(arguments, x=[s[0] for s in smoothed],
                             x_dot=[s[1] for s in smoothed], x_ddot=[s[2] for s in smoothed])
        return SINDyBaseline(system.coords, baseline_terms(catalog)).fit(**arguments)
    model = px.XLSINDy(catalog, _optimizer(task.solver))
    return model.fit(**arguments)


def _model_summary(task: Task, system, model) -> dict:
    """Size of the model and, for XL-SINDy models, its error against the truth."""
    if task.solver == "pysindy":
        coef = model.coef_
        names = model.get_feature_names()
        nonzero = {f"{system.coordinate_names[i]}_ddot <- {names[k]}": float(coef[i, k])
                   for i, k in zip(*np.nonzero(coef), strict=True)}
        return {"n_features": len(names), "n_terms": len(nonzero), "coefficients": nonzero}
    coef = model.coefficients()
    names = model.get_feature_names()
    summary = {"n_features": len(names), "n_terms": int(np.count_nonzero(coef)),
               "coefficients": {names[k]: float(coef[k]) for k in np.flatnonzero(coef)},
               "dropped_features": len(getattr(model, "dropped_features_", {}) or {})}
    try:
        from ..mujoco.catalogs.reference import true_coefficients
        truth, missing = true_coefficients(system, model.feature_library_)
        # an implicit law is only defined up to a factor: compare at the best common scale
        # (1 for explicit fits, whose force coefficient is fixed to -1 like the truth's)
        factor = float(coef @ truth / (coef @ coef)) if np.any(coef) else 0.0
        summary["coefficient_error"] = float(np.abs(factor * coef - truth).max()
                                             / np.abs(truth).max())
        summary["coefficient_scale"] = factor
        summary["support_recovered"] = bool(np.array_equal(coef != 0, truth != 0))
        summary["true_model_in_catalog"] = not missing
    except Exception as error:  # a summary must never fail the run
        summary["coefficient_error_failure"] = f"{type(error).__name__}: {error}"
    return summary


def execute_task(task: Task, settings: GridSettings, deadline: float | None = None,
                 stage=None) -> dict:
    """Run one task in this process and return its record (no time limit of its own): the
    validation simulation must end by ``deadline`` (a ``time.perf_counter()`` value), ``stage``
    is called with ``"generate"``, ``"fit"``, ``"validate"``, and warnings go to the record's
    ``warnings`` list.

    Parameters
    ----------
    task : Task
        The run.
    settings : GridSettings
        The grid's settings.
    deadline : float, default=None
        ``time.perf_counter()`` value by which the validation simulation must end; None: no
        deadline.
    stage : callable, default=None
        Called with ``"generate"``, ``"fit"``, ``"validate"`` as the run goes.

    Returns
    -------
    dict
        The run's record (status, metrics, model summary, times, warnings).
    """
    stage = stage or (lambda name: None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        record = _execute(task, settings, deadline, stage)
    messages = list(dict.fromkeys(f"{w.category.__name__}: {w.message}" for w in caught))
    record["warnings"] = [m[:300] for m in messages[:5]] + (
        [f"... and {len(messages) - 5} more"] if len(messages) > 5 else [])
    return record


def _execute(task, settings, deadline, stage) -> dict:
    from ..dynamics import DynamicsError
    from ..evaluation.validation import validate_model
    record = base_record(task, settings)
    spec = task.trajectory
    stage("generate")
    dataset, validation, generate_seconds = trajectory_data(
        spec, settings.n_trajectories, float(settings.duration), settings.sample_every,
        float(settings.validation_duration))
    record["time_s"]["generate"] = generate_seconds
    system = system_for(spec)
    start = time.perf_counter()
    stage("fit")
    try:
        model = _identify(task, system, dataset)
    except RunTimeout:
        raise
    except Exception as error:
        record["time_s"]["fit"] = time.perf_counter() - start
        record["time_s"]["run"] = record["time_s"]["fit"]
        return failed_record(record, "error", error, with_traceback=True)
    fitted = time.perf_counter()
    record["time_s"]["fit"] = fitted - start
    stage("validate")
    remaining = None if deadline is None else max(deadline - time.perf_counter(), 1e-3)
    try:
        result = validate_model(model, system, trajectory=validation, timeout=remaining)
    except RunTimeout:
        raise
    except (DynamicsError, ValueError) as error:  # e.g. no acceleration in the equations
        result = None
        record["status"], record["message"] = "invalid", f"{type(error).__name__}: {error}"
    end = time.perf_counter()
    record["time_s"]["validate"] = end - fitted
    record["time_s"]["run"] = end - start
    if result is not None:
        record["metrics"] = result.to_dict()
        if result.valid:
            record["status"] = "ok"
        elif result.failure == "timeout":
            record["status"] = "timeout"
            record["message"] = (f"validation simulation stopped by the time limit "
                                 f"({settings.timeout:g} s per run)")
        else:
            record["status"] = "invalid"
            when = result.divergence_time
            record["message"] = (f"{result.failure or 'diverged'}"
                                 + ("" if when is None else f" at t={when:.3g} s"))
    stage("summary")
    record["model"] = _model_summary(task, system, model)
    return json_finite(record)


def _grid_call(task, grid_pid, **options):
    """One run of a grid in a worker: :func:`run_task` under the worker's watchdog."""
    watch_grid(grid_pid)
    return run_task(task, **options)


def _prefetch(task: Task, settings: GridSettings) -> None:
    """Simulate the trajectory's data here, so that forked runs inherit the cache."""
    try:
        trajectory_data(task.trajectory, settings.n_trajectories, float(settings.duration),
                        settings.sample_every, float(settings.validation_duration))
    except Exception:  # the run repeats the call and records the error
        pass


def run_task(task: Task, settings: GridSettings, timeout: float | None = None,
             isolation: str = "auto", function=None, blas_threads: int | None = None) -> dict:
    """Run one task under its time limit (``timeout``, default ``settings.timeout``); never raises
    for a failing run and returns the record, with ``finished_at``.

    Parameters
    ----------
    task : Task
        The run.
    settings : GridSettings
        The grid's settings.
    timeout : float, default=None
        Seconds allowed; None: ``settings.timeout``.
    isolation : {"auto", "process", "signal", "none"}, default="auto"
        Module docstring; ``auto`` picks ``process`` where fork exists.
    function : callable, optional
        ``function(task, settings, deadline, stage) -> record`` (default :func:`execute_task`).
    blas_threads : int, optional
        BLAS threads during the run (:func:`blas_thread_limit`); default: no limit.

    Returns
    -------
    dict
        The run's record, with ``finished_at``; a failing run gives a record with status
        ``error`` or ``timeout``.
    """
    with blas_thread_limit(blas_threads):
        return _run_task(task, settings, timeout, isolation, function)


def _run_task(task, settings, timeout, isolation, function):
    function = function or execute_task
    timeout = float(settings.timeout if timeout is None else timeout)
    if not timeout > 0:
        raise ValueError(f"timeout: expected a positive number of seconds, got {timeout!r}")
    mode = resolve_isolation(isolation)
    if mode == "process":
        if function is execute_task:
            _prefetch(task, settings)
        return finish_record(run_in_process(function, task, settings, timeout))
    if mode == "signal":
        return finish_record(run_with_signal(function, task, settings, timeout))
    start = time.perf_counter()
    try:
        record = function(task, settings, start + timeout, None)
    except Exception as error:
        record = failed_record(base_record(task, settings), "error", error, True)
    return finish_record(json_finite(record))


@contextlib.contextmanager
def backend_context(backend: str | None = None, address: str | None = None):
    """A :func:`joblib.parallel_config` context for ``backend``: ``None`` / ``"loky"`` /
    ``"multiprocessing"`` (local processes), ``"dask"`` (a ``dask.distributed.Client`` on the
    scheduler ``address``, a local cluster when None) or ``"ray"`` (``ray.init(address=address)``,
    ``"auto"`` joins a running cluster). Dask and Ray are imported only when asked for.

    Parameters
    ----------
    backend : {None, "loky", "multiprocessing", "dask", "ray"}, default=None
        The joblib backend.
    address : str, default=None
        The Dask scheduler or Ray cluster address.

    Yields
    ------
    None
        Inside the context, joblib runs on the backend.
    """
    import joblib
    if backend in (None, "loky", "multiprocessing"):
        with joblib.parallel_config(backend=backend or "loky"):
            yield
        return
    if backend == "dask":
        try:
            from dask.distributed import Client
        except ImportError:
            raise ImportError("backend 'dask' needs dask.distributed: pip install "
                              "'dask[distributed]'") from None
        with Client(address) if address else Client(processes=True) as client:
            with joblib.parallel_config(backend="dask"):
                yield client
        return
    if backend == "ray":
        try:
            import ray
            from ray.util.joblib import register_ray
        except ImportError:
            raise ImportError("backend 'ray' needs ray: pip install 'ray[default]'") from None
        register_ray()
        if not ray.is_initialized():
            ray.init(address=address)
        with joblib.parallel_config(backend="ray"):
            yield
        return
    raise ValueError(f"backend: expected None, 'loky', 'multiprocessing', 'dask' or 'ray', "
                     f"got {backend!r}")


def _results(tasks, call, n_jobs):
    """Yield records as runs finish (unordered), or in chunks where the backend cannot."""
    import joblib
    try:
        parallel = joblib.Parallel(n_jobs=n_jobs, return_as="generator_unordered")
    except ValueError:  # backends without generator support (multiprocessing, Ray)
        parallel = None
    if parallel is not None:
        yield from parallel(joblib.delayed(call)(task) for task in tasks)
        return
    chunk = max(2 * joblib.effective_n_jobs(n_jobs), 1)
    for k in range(0, len(tasks), chunk):
        yield from joblib.Parallel(n_jobs=n_jobs)(
            joblib.delayed(call)(task) for task in tasks[k:k + chunk])


def run_grid(settings: GridSettings, records_path, n_jobs: int = -1, backend: str | None = None,
             address: str | None = None, retry=(), isolation: str = "auto", progress=None,
             limit: int | None = None, function=None, blas_threads="auto") -> dict:
    """Run every pending task of a grid, appending one record per run to the JSONL file
    ``records_path`` (runs recorded there are skipped).

    Parameters
    ----------
    settings : GridSettings
        The grid.
    records_path : str or os.PathLike
        The JSONL file of records.
    n_jobs : int, default=-1
        Parallel processes (joblib convention: -1 = all cores).
    backend, address : str, optional
        As in :func:`backend_context`.
    retry : iterable of str, default=()
        Statuses to run again (e.g. ``("error", "timeout")``).
    isolation : {"auto", "process", "signal", "none"}, default="auto"
        As in :func:`run_task`.
    function : callable, optional
        As in :func:`run_task`.
    progress : bool, optional
        Show a tqdm progress bar (default: on a terminal).
    limit : int, optional
        Run at most this many pending tasks.
    blas_threads : "auto", int or None, default="auto"
        BLAS threads per run: ``"auto"`` is 1 when runs go in parallel, no limit otherwise.

    Returns
    -------
    dict
        ``{"total", "skipped", "ran", "statuses", "seconds"}``. Ctrl-C raises
        :class:`KeyboardInterrupt` after joblib has killed its workers; SIGTERM stops the grid
        the same way, then ends the process by SIGTERM.

    Examples
    --------
    A grid of two configurations on one trajectory, each run replaced by a stand-in that only
    writes its record (a real run simulates, fits and validates):

    >>> import os, tempfile
    >>> def fake_run(task, settings, deadline, stage):
    ...     error = 0.01 if task.solver == "mixed" else 0.02
    ...     return {**task.to_dict(), "status": "ok", "metrics": {"position_rmse": error},
    ...             "time_s": {"run": 0.0}, "message": None}
    >>> grid = GridSettings(systems=("cart-pole",), forcings=("mixed",),
    ...                     configurations=(("mixed", "mixed"), ("mixed", "explicit")))
    >>> path = os.path.join(tempfile.mkdtemp(), "records.jsonl")
    >>> first = run_grid(grid, path, n_jobs=1, isolation="none", function=fake_run,
    ...                  progress=False)
    >>> again = run_grid(grid, path, n_jobs=1, isolation="none", function=fake_run,
    ...                  progress=False)  # resumes: nothing left to run
    >>> first["ran"], first["statuses"]["ok"], again["ran"], again["skipped"]
    (2, 2, 0, 2)
    """
    from tqdm.auto import tqdm
    if not isinstance(settings, GridSettings):
        raise TypeError(f"settings: expected a GridSettings, got {type(settings).__name__}")
    if limit is not None and (isinstance(limit, bool) or not isinstance(limit, int)
                              or limit < 0):
        raise ValueError(f"limit: expected an integer >= 0, got {limit!r}")
    store = RecordStore(records_path)
    tasks = settings.tasks()
    done = store.finished_ids(retry=retry)
    pending = [t for t in tasks if t.run_id not in done]
    if limit is not None:
        pending = pending[:limit]
    call = functools.partial(_grid_call, grid_pid=os.getpid(), settings=settings,
                             isolation=isolation, function=function,
                             blas_threads=resolve_blas_threads(blas_threads, n_jobs, backend))
    statuses = dict.fromkeys(("ok", "invalid", "timeout", "error"), 0)
    start = time.perf_counter()
    bar = tqdm(total=len(pending), desc=f"benchmark {settings.name}", unit="run",
               disable=None if progress is None else not progress, smoothing=0.05)
    with sigterm_as_interrupt(), store.lock(), bar, backend_context(backend, address):
        if pending:
            # closing the generator (on an interrupt too) makes joblib kill its workers
            with contextlib.closing(_results(pending, call, n_jobs)) as results:
                for record in results:
                    store.append(record)
                    statuses[record["status"]] += 1
                    bar.set_postfix(statuses, refresh=False)
                    bar.update(1)
    return {"total": len(tasks), "skipped": sum(t.run_id in done for t in tasks),
            "ran": sum(statuses.values()), "statuses": statuses,
            "seconds": time.perf_counter() - start}
