"""The benchmark grid: trajectories x configurations, and the ``quick`` / ``full`` presets.

A *trajectory* (what the paper ranks on) is one training dataset: system, friction level,
forcing, noise level, seed. A *configuration* is a catalog (the paper's ``mixed``,
``lagrange``, ``classical``, and ``kinematic`` from the MJCF tree) crossed with a solver
(``mixed``, ``explicit``, ``implicit``), plus the plain :class:`pysindy.SINDy` baseline. A
*task* is one configuration on one trajectory. As in the paper, the explicit solver needs
forces, the implicit one is for unforced data, the others run on every forcing mode."""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, fields, replace

__all__ = ["CATALOGS", "SOLVERS", "BASELINE", "FORCINGS", "SYSTEM_NAMES", "TrajectorySpec",
           "Task", "GridSettings", "PRESETS", "config_label", "all_configurations",
           "solver_applies"]

#: The paper's three catalogs, then the kinematic-tree catalog (the row added by issue 12).
CATALOGS = ("mixed", "lagrange", "classical", "kinematic")
SOLVERS = ("mixed", "explicit", "implicit")
#: The extra row: plain pysindy.SINDy (second order) with the classical catalog.
BASELINE = ("classical", "pysindy")
FORCINGS = ("implicit", "explicit", "mixed")
SYSTEM_NAMES = ("cart-pole", "double-pendulum", "cart-double-pendulum")


def config_label(catalog: str, solver: str) -> str:
    """Row name of a configuration in the table.

    Parameters
    ----------
    catalog : str
        The catalog.
    solver : str
        The solver, ``"pysindy"`` for the baseline.

    Returns
    -------
    str
        ``"CATALOG x SOLVER"``, or ``"pysindy.SINDy (CATALOG)"``.

    Examples
    --------
    >>> config_label("lagrange", "explicit")
    'lagrange x explicit'
    >>> config_label("classical", "pysindy")
    'pysindy.SINDy (classical)'
    """
    if (catalog, solver) == BASELINE:
        return "pysindy.SINDy (classical)"
    return f"{catalog} x {solver}"


def all_configurations(include_baseline: bool = True) -> list[tuple[str, str]]:
    """``(catalog, solver)`` pairs in table order: the paper's 9, the kinematic catalog's 3, then
    (``include_baseline``) the pysindy.SINDy baseline ``("classical", "pysindy")``.

    Parameters
    ----------
    include_baseline : bool, default=True
        Append the pysindy.SINDy baseline.

    Returns
    -------
    list of tuple of str
        ``(catalog, solver)`` pairs.

    Examples
    --------
    >>> configurations = all_configurations()
    >>> len(configurations), configurations[-2:]
    (13, [('kinematic', 'implicit'), ('classical', 'pysindy')])
    """
    out = [(c, s) for c in CATALOGS for s in SOLVERS]
    return out + [BASELINE] if include_baseline else out


def solver_applies(solver: str, forcing: str) -> bool:
    """Whether a solver runs on data of a forcing mode (module docstring).

    Parameters
    ----------
    solver : str
        The solver.
    forcing : str
        The forcing mode of the data.

    Returns
    -------
    bool
        Whether the configuration runs on that data.

    Examples
    --------
    >>> solver_applies("explicit", "implicit"), solver_applies("mixed", "implicit")
    (False, True)
    """
    if solver == "explicit":
        return forcing in ("explicit", "mixed")
    if solver == "implicit":
        return forcing == "implicit"
    return True


def _stable_hash(payload) -> str:
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"))
    return hashlib.sha1(text.encode()).hexdigest()[:10]


@dataclass(frozen=True)
class TrajectorySpec:
    """One training dataset of the grid.

    Parameters
    ----------
    system : str
        Registry name of the system.
    friction : float
        Multiplier of the default joint damping.
    forcing : {"implicit", "explicit", "mixed"}
        The forcing mode.
    noise : float
        Relative noise level.
    seed : int
        Seed of the data.
    noise_model : {"all", "positions"}, default="all"
        ``"all"``: the paper's noise on every channel, all given to the fit; ``"positions"``:
        noisy positions only, no derivative given, as from a real sensor.

    Examples
    --------
    >>> TrajectorySpec("cart-pole", 1.0, "explicit", 0.01, 0).key
    'cart-pole/friction=1/explicit/noise=0.01/seed=0'
    """

    system: str
    friction: float
    forcing: str
    noise: float
    seed: int
    noise_model: str = "all"

    @property
    def key(self) -> str:
        """Readable identifier, e.g. ``cart-pole/friction=1/explicit/noise=0.01/seed=0``."""
        model = "(positions)" if self.noise_model == "positions" else ""
        return (f"{self.system}/friction={self.friction:g}/{self.forcing}/"
                f"noise={self.noise:g}{model}/seed={self.seed}")


@dataclass(frozen=True)
class Task:
    """One configuration on one trajectory.

    Parameters
    ----------
    trajectory : TrajectorySpec
        The training data.
    catalog : str
        The catalog (``"lagrange"``, ``"classical"``, ``"mixed"``, ``"kinematic"``).
    solver : str
        The solver (``"explicit"``, ``"implicit"``, ``"mixed"``), or ``"pysindy"`` for the
        baseline.
    settings_hash : str, default=""
        Hash of the grid's data settings: records of a grid with other settings do not count
        as done.

    Examples
    --------
    >>> task = Task(TrajectorySpec("cart-pole", 1.0, "explicit", 0.0, 0), "mixed", "explicit")
    >>> task.config, task.run_id == Task(task.trajectory, "mixed", "explicit").run_id
    ('mixed x explicit', True)
    """

    trajectory: TrajectorySpec
    catalog: str
    solver: str
    settings_hash: str = ""

    @property
    def config(self) -> str:
        return config_label(self.catalog, self.solver)

    @property
    def run_id(self) -> str:
        """Unique, stable identifier of the run (used to resume)."""
        return f"{self.trajectory.key}/{self.catalog}x{self.solver}/{self.settings_hash}"

    def to_dict(self) -> dict:
        """The task as a JSON-serializable dict (the start of its record).

        Returns
        -------
        dict
            The trajectory's fields, ``catalog``, ``solver``, ``config``, ``trajectory_id`` and
            ``run_id``.
        """
        return {**asdict(self.trajectory), "catalog": self.catalog, "solver": self.solver,
                "config": self.config, "trajectory_id": self.trajectory.key,
                "run_id": self.run_id}


@dataclass(frozen=True)
class GridSettings:
    """A benchmark grid: its axes and the data / run settings shared by every task.

    Parameters
    ----------
    systems : tuple of str, default=SYSTEM_NAMES
        Systems of the grid (registry names).
    friction_levels : tuple of float, default=(1.0,)
        Multipliers of the default joint damping.
    forcings : tuple of str, default=FORCINGS
        Forcing modes.
    noise_levels : tuple of float, default=(0.0,)
        The paper's noise on every channel.
    seeds : tuple of int, default=(0,)
        Seeds of the data.
    position_noise_levels : tuple of float, default=()
        Further noise levels on the positions only.
    configurations : tuple of (catalog, solver), default=all_configurations()
        Configurations to run.
    n_trajectories : int, default=2
        Training trajectories per dataset.
    duration : float, default=10.0
        Seconds of each training trajectory.
    sample_every : int, default=2
        Every k-th MuJoCo step (1 ms) kept.
    validation_duration : float, default=10.0
        Seconds of the fresh validation trajectory.
    timeout : float, default=3600.0
        Seconds allowed to one run.
    name : str, default="custom"
        Preset name, recorded with the results.

    Raises
    ------
    ValueError
        When an axis is empty or holds an unknown or out-of-range value.

    Examples
    --------
    >>> grid = GridSettings(systems=("cart-pole",), forcings=("explicit",))
    >>> len(grid.trajectories()), len(grid.configurations), len(grid.tasks())
    (1, 13, 9)

    The four implicit-solver configurations skip forced data (:func:`solver_applies`).
    """

    systems: tuple = SYSTEM_NAMES
    friction_levels: tuple = (1.0,)
    forcings: tuple = FORCINGS
    noise_levels: tuple = (0.0,)
    seeds: tuple = (0,)
    position_noise_levels: tuple = ()
    configurations: tuple = tuple(all_configurations())
    n_trajectories: int = 2
    duration: float = 10.0
    sample_every: int = 2
    validation_duration: float = 10.0
    timeout: float = 3600.0
    name: str = "custom"

    def __post_init__(self):
        _check_axis(self.systems, "systems", str)
        _check_axis(self.forcings, "forcings", str)
        for f in self.forcings:
            if f not in FORCINGS:
                raise ValueError(f"forcings: expected values among {FORCINGS}, got {f!r}")
        _check_axis(self.friction_levels, "friction_levels", (int, float), non_negative=True)
        _check_axis(self.noise_levels, "noise_levels", (int, float), non_negative=True)
        if self.position_noise_levels:
            _check_axis(self.position_noise_levels, "position_noise_levels", (int, float),
                        non_negative=True)
        _check_axis(self.seeds, "seeds", int)
        if not self.configurations:
            raise ValueError("configurations: expected at least one (catalog, solver) pair")
        known = set(all_configurations())
        for pair in self.configurations:
            if tuple(pair) not in known:
                raise ValueError(f"configurations: unknown (catalog, solver) {pair!r}; expected "
                                 f"among {sorted(known)}")
        for name in ("n_trajectories", "sample_every"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name}: expected an integer >= 1, got {value!r}")
        for name in ("duration", "validation_duration", "timeout"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
                raise ValueError(f"{name}: expected a positive number of seconds, got {value!r}")

    def data_settings(self) -> dict:
        """The settings that change the data, hashed into every run id (not the timeout: rerunning
        with a longer one and ``retry`` reruns only the runs that timed out).

        Returns
        -------
        dict
            The axes and data settings (JSON-serializable).
        """
        return {"n_trajectories": self.n_trajectories, "duration": float(self.duration),
                "sample_every": self.sample_every,
                "validation_duration": float(self.validation_duration)}

    @property
    def settings_hash(self) -> str:
        return _stable_hash(self.data_settings())

    def trajectories(self) -> list[TrajectorySpec]:
        """Every trajectory of the grid, in a stable order.

        Returns
        -------
        list of TrajectorySpec
            The training datasets.
        """
        noises = [(float(v), "all") for v in self.noise_levels] + [
            (float(v), "positions") for v in self.position_noise_levels]
        return [
            TrajectorySpec(system, float(friction), forcing, noise, int(seed), model)
            for system in self.systems
            for friction in self.friction_levels
            for forcing in self.forcings
            for noise, model in noises
            for seed in self.seeds
        ]

    def tasks(self) -> list[Task]:
        """Every run of the grid, grouped by trajectory (consecutive runs share data).

        Returns
        -------
        list of Task
            The runs, where the configuration applies to the forcing (:func:`solver_applies`).
        """
        digest = self.settings_hash
        return [
            Task(spec, catalog, solver, digest)
            for spec in self.trajectories()
            for catalog, solver in self.configurations
            if solver_applies(solver, spec.forcing)
        ]

    def with_options(self, **changes) -> GridSettings:
        """A copy with some fields replaced (None values are ignored).

        Parameters
        ----------
        **changes
            Field values; None leaves a field as it is.

        Returns
        -------
        GridSettings
            The new settings.
        """
        changes = {k: v for k, v in changes.items() if v is not None}
        unknown = set(changes) - {f.name for f in fields(self)}
        if unknown:
            raise ValueError(f"changes: unknown grid settings {sorted(unknown)}")
        return replace(self, **changes)

    def to_dict(self) -> dict:
        """The settings as a JSON-serializable dict, with the number of runs.

        Returns
        -------
        dict
            The fields (tuples as lists) and ``n_runs``.
        """
        out = asdict(self)
        out["configurations"] = [list(c) for c in self.configurations]
        for key in ("systems", "friction_levels", "forcings", "noise_levels", "seeds",
                    "position_noise_levels"):
            out[key] = list(out[key])
        out["n_runs"] = len(self.tasks())
        out["n_trajectory_specs"] = len(self.trajectories())
        return out


def _check_axis(values, name, kind, non_negative=False):
    if isinstance(values, (str, bytes)) or not isinstance(values, (tuple, list)) or not values:
        raise ValueError(f"{name}: expected a non-empty tuple, got {values!r}")
    for v in values:
        if isinstance(v, bool) or not isinstance(v, kind):
            raise TypeError(f"{name}: unexpected entry {v!r} ({type(v).__name__})")
        if non_negative and not (v >= 0 and v == v and v != float("inf")):
            raise ValueError(f"{name}: expected non-negative finite numbers, got {v!r}")
    if len(set(values)) != len(values):
        raise ValueError(f"{name}: duplicate entries in {values!r}")


#: ``quick``: every system and forcing mode, one seed, short trajectories; ``full``: the
#: paper's scale (three friction levels, three noise levels, two seeds, 1 h per run).
PRESETS = {
    "quick": GridSettings(
        friction_levels=(1.0,), noise_levels=(0.0, 0.001), seeds=(0,),
        position_noise_levels=(0.01, 0.05),
        n_trajectories=2, duration=5.0, sample_every=5, validation_duration=5.0,
        timeout=90.0, name="quick",
    ),
    "full": GridSettings(
        friction_levels=(0.0, 1.0, 2.0), noise_levels=(0.0, 0.001, 0.01), seeds=(0, 1),
        position_noise_levels=(0.01, 0.05),
        n_trajectories=2, duration=10.0, sample_every=2, validation_duration=10.0,
        timeout=3600.0, name="full",
    ),
}
