"""ExternalForces category: the known right-hand side of the equations of motion."""

from __future__ import annotations

import numpy as np
import sympy as sp

from .._validation import Collection, InstanceOf
from ..symbols import Coordinates
from ._base import SymbolicLibrary

__all__ = ["ExternalForces"]


def _interlink_matrix(interlink, n: int) -> np.ndarray:
    """Normalize ``interlink`` to a matrix ``B`` (n, n): generalized force = ``B @ u``."""
    if interlink is None:
        return np.eye(n)
    try:
        matrix = np.asarray(interlink, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("interlink: expected a numeric matrix of shape (n, n); for lists of "
                         "signed input indices use ExternalForces.from_signed_indices") from None
    if matrix.shape != (n, n):
        raise ValueError(f"interlink: expected a matrix of shape (n, n) = {(n, n)} (generalized "
                         f"force = interlink @ u), got shape {matrix.shape}")
    if not np.all(np.isfinite(matrix)):
        raise ValueError("interlink: contains NaN or inf")
    if not matrix.any():
        raise ValueError("interlink: is all zero, so no input acts on any coordinate; expected "
                         "a matrix with at least one nonzero entry (generalized force = "
                         "interlink @ u)")
    return matrix


def _exact(value: float) -> sp.Expr:
    """``value`` as the exact number it stands for (an integer directly: ``nsimplify`` is slow)."""
    return sp.Integer(int(value)) if value == int(value) else sp.nsimplify(value)


def signed_indices_to_interlink(indices, n: int) -> np.ndarray:
    """Interlink matrix from per-coordinate lists of signed 1-based input indices.

    ``[[1], [-1, 2]]`` gives coordinate 0 ``u_1`` and coordinate 1 ``u_2 - u_1`` (xlsindy's
    convention).

    Parameters
    ----------
    indices : sequence of sequence of int
        Per coordinate, the signed 1-based indices of the inputs acting on it.
    n : int
        Number of coordinates (and inputs).

    Returns
    -------
    ndarray, shape (n, n)
        ``interlink[c, k] = sign`` for each signed index ``k + 1`` of coordinate ``c``.

    Examples
    --------
    >>> signed_indices_to_interlink([[1], [-1, 2]], 2)
    array([[ 1.,  0.],
           [-1.,  1.]])
    """
    if not isinstance(indices, (list, tuple)) or len(indices) != n:
        raise ValueError(f"indices: expected one list of signed input indices per coordinate ({n})")
    matrix = np.zeros((n, n))
    for c, row in enumerate(indices):
        for k in row:
            if not isinstance(k, (int, np.integer)) or k == 0 or abs(k) > n:
                raise ValueError(f"indices: entry {k!r} for coordinate {c} is not a signed 1-based "
                                 f"input index in [-{n}, -1] or [1, {n}]")
            matrix[c, abs(k) - 1] += np.sign(k)
    return matrix


class ExternalForces(SymbolicLibrary):
    """Known generalized forces: one column whose entry in equation ``c`` is the force on ``c``.

    In explicit regression its coefficient is fixed to ``-1`` (the paper's convention), so the
    identified equations read ``EL(L) + classical terms = force``.

    Parameters
    ----------
    coords : Coordinates
        The generalized coordinates.
    interlink : array, shape (n, n), optional
        Generalized force ``= interlink @ u`` for the measured inputs ``u`` (several signed
        inputs may act on one coordinate, e.g. a motor between two links). Default: identity.
        See :meth:`from_signed_indices`.

    Attributes
    ----------
    interlink_ : ndarray, shape (n, n)
        The interlink matrix used.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> c = px.Coordinates(["theta1", "theta2"])
    >>> px.ExternalForces(c, interlink=[[1, -1], [0, 1]]).symbolic_matrix()
    Matrix([
    [tau_theta1 - tau_theta2],
    [             tau_theta2]])
    """

    category = "forces"
    column_rank = 0
    spec_type = "ExternalForces"
    _parameter_constraints = {
        "coords": [InstanceOf(Coordinates, "a pysindy_xl.Coordinates")],
        "interlink": [None, Collection("an array of shape (n, n)")],
    }

    def __init__(self, coords: Coordinates, interlink=None):
        self.coords = coords
        self.interlink = interlink

    @classmethod
    def from_signed_indices(cls, coords: Coordinates, indices) -> ExternalForces:
        """Build from per-coordinate lists of signed 1-based input indices (xlsindy's convention).

        ``[[1], [-1, 2]]`` gives coordinate 0 the force ``u_1`` and coordinate 1 ``u_2 - u_1``
        (:func:`signed_indices_to_interlink`).

        Parameters
        ----------
        coords : Coordinates
            The generalized coordinates.
        indices : sequence of sequence of int
            Per coordinate, the signed 1-based indices of the inputs acting on it.

        Returns
        -------
        ExternalForces
            The library with the corresponding ``interlink``.

        Examples
        --------
        >>> import pysindy_xl as px
        >>> c = px.Coordinates(["a", "b"])
        >>> px.ExternalForces.from_signed_indices(c, [[1, -2], [2]]).interlink
        array([[ 1., -1.],
               [ 0.,  1.]])
        """
        return cls(coords, interlink=signed_indices_to_interlink(indices, coords.n))

    def _build_symbolic(self):
        matrix = _interlink_matrix(self.interlink, self.coords.n)
        self.interlink_ = matrix
        tau = self.coords.tau
        return ["F[tau]"], sp.Matrix([sum(_exact(matrix[c, k]) * tau[k] for k in range(len(tau))
                                          if matrix[c, k]) for c in range(len(tau))])

    def to_spec(self) -> dict:
        """JSON-serializable description of this library, read back by :meth:`from_spec`.

        Returns
        -------
        dict
            ``{"type": spec_type, ...}``: the parameters as plain JSON values, terms in the
            restricted grammar (:func:`~pysindy_xl.expressions.format_expression`).
        """
        return {"type": self.spec_type,
                "interlink": _interlink_matrix(self.interlink, self.coords.n).tolist()}

    @classmethod
    def from_spec(cls, spec, reader):
        """The library a specification describes (the inverse of :meth:`to_spec`).

        Parameters
        ----------
        spec : dict
            The description; untrusted (from a file).
        reader : SpecReader
            Parses its parts within the loader's budget
            (:class:`~pysindy_xl.feature_library.SpecReader`).

        Returns
        -------
        ExternalForces
            The library, not fitted.
        """
        n = reader.coords.n
        return cls(reader.coords,
                   interlink=reader.matrix(spec, "interlink", (n, n), shape_name="(n, n)"))
