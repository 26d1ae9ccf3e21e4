"""Payload identification: the ten inertial parameters of a load carried by a known arm.

A payload rigidly attached to body ``b`` adds its parameters ``pi_p`` (about ``b``'s frame
origin, in ``b``'s frame) to those of ``b``. With base parameters ``beta = C pi``:

.. math:: \\tau = W(q, \\dot q, \\ddot q)\\,\\beta_{arm} + F(\\dot q) + W\\,C_b\\,\\pi_p ,

``W`` the kinematic catalog's Lagrange columns, ``F`` its friction, ``C_b`` body ``b``'s
columns of ``C``. With the arm known, the residual torques of a loaded run are a linear
regression on ``W C_b``, solved under the payload's physical consistency (pseudo-inertia
positive semidefinite; :func:`~pysindy_xl.physical.consistent_least_squares`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...physical.structure import INERTIAL_PARAMETERS, PhysicalStructure

__all__ = ["Payload", "identify_payload"]


@dataclasses.dataclass
class Payload:
    """Inertial parameters of a payload identified by :func:`identify_payload`.

    Parameters
    ----------
    body : str
        The body that carries the payload (its frame is the parameters' reference).
    parameters : numpy.ndarray of shape (10,)
        ``m, mcx, mcy, mcz, Ixx, Iyy, Izz, Ixy, Ixz, Iyz`` about the body frame origin.
    mass : float
        The payload's mass (kg).
    com : numpy.ndarray of shape (3,)
        Its centre of mass in the body frame (m).
    inertia : numpy.ndarray of shape (3, 3)
        Its inertia tensor about the centre of mass, in the body frame (kg m^2).
    identifiable : int
        How many independent combinations of the ten parameters the run determines.
    residual : float
        Relative RMS of the torques (or weak-form projections) left unexplained.

    Examples
    --------
    >>> payload = Payload("hand", np.r_[2.0, 0.2, 0, 0, np.zeros(6)], 2.0,
    ...                   np.array([0.1, 0, 0]), np.zeros((3, 3)), 10, 0.0)
    >>> payload.to_dict()["com"]
    [0.1, 0.0, 0.0]
    """

    body: str
    parameters: np.ndarray
    mass: float
    com: np.ndarray
    inertia: np.ndarray
    identifiable: int
    residual: float

    def to_dict(self) -> dict:
        """JSON-serializable description (arrays as nested lists).

        Returns
        -------
        dict
            The fields, arrays as nested lists.
        """
        return {"body": self.body, "parameters": self.parameters.tolist(), "mass": self.mass,
                "com": self.com.tolist(), "inertia": self.inertia.tolist(),
                "identifiable": self.identifiable, "residual": self.residual}

    def forces(self, catalog, q, qd, qdd) -> np.ndarray:
        """Joint torques (N, n) the payload adds to the arm: ``W(q, qd, qdd) C_b pi_p``.

        Added to the arm's :meth:`~pysindy_xl.XLSINDy.predict_forces` it predicts the loaded
        arm; ``catalog`` is the one the payload was identified with, ``q, qd, qdd`` (N, n).

        Parameters
        ----------
        catalog : KinematicCatalog
            The catalog the payload was identified with.
        q, qd, qdd : array_like of shape (N, n)
            Generalized positions, velocities and accelerations.

        Returns
        -------
        numpy.ndarray of shape (N, n)
            The joint torques the payload adds.

        Examples
        --------
        >>> from pysindy_xl.mujoco import kinematic_catalog
        >>> arm = kinematic_catalog('''<mujoco><option gravity="0 0 -9.81"/><worldbody>
        ...   <body name="hand"><joint name="a" axis="0 1 0"/>
        ...   <inertial pos="0.5 0 0" mass="1" diaginertia="1 1 1"/></body>
        ...   </worldbody></mujoco>''')
        >>> payload = Payload("hand", np.r_[2.0, 1.0, np.zeros(8)], 2.0,
        ...                   np.array([0.5, 0, 0]), np.zeros((3, 3)), 10, 0.0)
        >>> zero = np.zeros((1, 1))
        >>> float(abs(payload.forces(arm, zero, zero, zero)[0, 0]).round(3))  # 2 kg at 0.5 m
        9.81
        """
        from ..._inputs import check_array
        from ...symbols import stack_variables
        library = catalog.library().fit()
        q = check_array(q, "q", n_columns=catalog.coords.n)
        qd, qdd = check_array(qd, "qd", q.shape), check_array(qdd, "qdd", q.shape)
        rows = library.transform(stack_variables(q, qd, qdd, np.zeros_like(q)))
        forces = _regressor(catalog, library, self.body, rows) @ self.parameters
        return forces.reshape(q.shape[1], -1).T


def _bodies(catalog) -> list:
    return list(dict.fromkeys(name.rsplit(".", 1)[0] for name in catalog.physical_names
                              if name.rsplit(".", 1)[1] in INERTIAL_PARAMETERS))


def _regressor(catalog, library, body, rows) -> np.ndarray:
    """``W C_b``: the catalog's Lagrange rows mapped onto the ten parameters of ``body``."""
    if body not in _bodies(catalog):
        raise ValueError(f"body: expected one of {_bodies(catalog)}, got {body!r}")
    lagrange = [j for j, c in enumerate(library.categories_) if c == "lagrange"]
    index = [list(catalog.physical_names).index(f"{body}.{p}") for p in INERTIAL_PARAMETERS]
    return rows[:, lagrange] @ catalog.combination[:, index]


def _arm_coefficients(catalog, library, arm):
    if arm is None:
        return catalog.true_coefficients()
    if hasattr(arm, "coefficients") and hasattr(arm, "get_feature_names"):
        if list(arm.get_feature_names()) != list(library.get_feature_names()):
            raise ValueError("arm: a model fitted on another catalog than catalog.library()")
        coef = np.asarray(arm.coefficients(), dtype=float)
        force = coef[library.force_columns_[0]]
        if force == 0:
            raise ValueError("arm: the model's force coefficient is zero")
        return -coef / force
    coef = np.asarray(arm, dtype=float)
    rest = library.get_feature_names()[1:]
    if coef.shape != (len(library.get_feature_names()),) or not np.all(np.isfinite(coef)):
        raise ValueError(f"arm: expected a fitted XLSINDy, None or the {len(rest) + 1} finite "
                         f"coefficients of catalog.library(), got shape {coef.shape}")
    return coef


def identify_payload(catalog, q, t, tau, qd=None, qdd=None, arm=None, body=None) -> Payload:
    """The inertial parameters of a payload from a run of the loaded arm.

    Parameters
    ----------
    catalog : KinematicCatalog
        The arm's catalog without the payload (:func:`~pysindy_xl.mujoco.kinematic_catalog`).
    q, t, tau : array, shapes (N, n), (N,), (N, n)
        Positions, sample times and joint torques of the loaded run.
    qd, qdd : array, shape (N, n), optional
        Without both, the regression is the weak form
        (:func:`~pysindy_xl.weak.weak_regression`), with ``arm``'s test functions and
        smoother when it is a fitted model.
    arm : XLSINDy, array or None, optional
        The arm without payload: a model fitted with ``catalog.library()``, its coefficient
        vector (force coefficient -1), or None for the MJCF's nominal values.
    body : str, optional
        The body carrying the payload; default the last body of the chain.

    Returns
    -------
    Payload
        The identified inertial parameters.

    Raises
    ------
    ValueError
        If the shapes differ, ``body`` is not in the catalog or ``arm`` does not match it.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> from pysindy_xl.mujoco import identify_payload, kinematic_catalog
    >>> arm = '''<mujoco><option gravity="0 0 -9.81"/><worldbody><body name="link">
    ...   <joint name="a" axis="0 1 0"/>
    ...   <inertial pos="0.3 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>
    ...   <body name="hand" pos="0.6 0 0"><joint name="b" axis="0 1 0"/>
    ...   <inertial pos="0.1 0 0" mass="0.5" diaginertia="0.01 0.01 0.01"/>
    ...   </body></body></worldbody></mujoco>'''
    >>> loaded = arm.replace('mass="0.5"', 'mass="0.8"')  # 0.3 kg more at the hand's 0.1 m
    >>> rng = np.random.default_rng(0)
    >>> q, qd, qdd = rng.uniform(-2, 2, (3, 200, 2))
    >>> truth = kinematic_catalog(loaded)  # the loaded arm's torques, from its catalog
    >>> theta = truth.library().fit().transform(px.stack_variables(q, qd, qdd))
    >>> tau = (theta[:, 1:] @ truth.true_coefficients()[1:]).reshape(2, -1).T
    >>> t = np.arange(200) * 0.01  # (unused: the derivatives are given)
    >>> payload = identify_payload(kinematic_catalog(arm), q, t, tau, qd, qdd)
    >>> payload.body, round(payload.mass, 4), (payload.com.round(4) + 0.0)[[0, 2]]
    ('hand', 0.3, array([0.1, 0. ]))
    """
    from ..._inputs import check_array
    from ...physical.sdp import consistent_least_squares
    from ...symbols import stack_variables
    from ...weak import BumpTestFunctions, WhittakerSmoother, weak_regression
    library = catalog.library().fit()
    n = catalog.coords.n
    q = check_array(q, "q", n_columns=n)
    tau = check_array(tau, "tau", q.shape)
    t = np.asarray(t, dtype=float)
    if t.shape != (len(q),) or not np.all(np.isfinite(t)):
        raise ValueError(f"t: expected {len(q)} finite sample times, got shape {t.shape}")
    bodies = _bodies(catalog)
    body = bodies[-1] if body is None else body
    if body not in bodies:
        raise ValueError(f"body: expected one of {bodies}, got {body!r}")
    coef = _arm_coefficients(catalog, library, arm)
    if qd is None or qdd is None:  # positions only: weak form, as the package's fits
        rows = weak_regression(library, [{"t": t, "x": q, "x_dot": qd, "u": tau,
                                         "mask": np.ones(len(t), dtype=bool)}],
                               getattr(arm, "test_functions", None) or BumpTestFunctions(),
                               getattr(arm, "smoother", None) or WhittakerSmoother())[0]
    else:
        rows = library.transform(stack_variables(
            q, check_array(qd, "qd", q.shape), check_array(qdd, "qdd", q.shape), tau))
    # rows (coordinate-major, strong or weak) of the catalog: F[tau] = rest @ coef[rest]
    forces = library.force_columns_
    rest = np.setdiff1d(np.arange(rows.shape[1]), forces)
    measured = rows[:, forces].sum(axis=1)
    residual = measured - rows[:, rest] @ coef[rest]
    regressor = _regressor(catalog, library, body, rows)  # (rows, 10)
    unconstrained = np.linalg.lstsq(regressor, residual, rcond=None)[0]
    structure = PhysicalStructure.from_maps([{f"payload.{p}": 1.0} for p in INERTIAL_PARAMETERS],
                                            base_columns=np.arange(10))
    parameters = consistent_least_squares(regressor, structure, unconstrained)[0]
    mass = float(parameters[0])
    com = parameters[1:4] / mass if mass > 0 else np.zeros(3)
    ixx, iyy, izz, ixy, ixz, iyz = parameters[4:]
    about_origin = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    inertia = about_origin - mass * (com @ com * np.eye(3) - np.outer(com, com))
    singular = np.linalg.svd(regressor, compute_uv=False)
    left = residual - regressor @ parameters
    return Payload(body=body, parameters=parameters, mass=mass, com=com, inertia=inertia,
                   identifiable=int(np.sum(singular > 1e-9 * singular[0])),
                   residual=float(np.linalg.norm(left) / np.linalg.norm(measured)))
