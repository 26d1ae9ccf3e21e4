"""Classical (Newtonian) category: state functions added to chosen coordinate equations."""

from __future__ import annotations

import copy

import numpy as np
import sympy as sp
from pysindy.feature_library.base import BaseFeatureLibrary

from .._validation import Collection, InstanceOf
from ..expressions import format_expression, parse_expression
from ..symbols import Coordinates, as_expr_list
from ._base import SymbolicLibrary, compile_entries

__all__ = ["ClassicalLibrary", "pysindy_library_terms"]


def pysindy_library_terms(library: BaseFeatureLibrary, coords: Coordinates) -> list[sp.Expr]:
    """Symbolic form of a pysindy feature library evaluated on the state ``(q, qd)``.

    The feature names are parsed by the restricted grammar of :mod:`pysindy_xl.expressions`,
    then checked numerically against ``library.transform`` on random states, so a library whose
    names do not describe its features (a ``CustomLibrary``) is refused, not mistranslated.

    Parameters
    ----------
    library : pysindy.BaseFeatureLibrary
        The pysindy library, fitted on the inputs ``[q, qd]`` here.
    coords : Coordinates
        The generalized coordinates.

    Returns
    -------
    list of sympy.Expr
        One expression per output feature of ``library``.

    Raises
    ------
    ValueError
        When a feature name cannot be parsed or does not match its feature's values.

    Examples
    --------
    >>> import pysindy as ps, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> pysindy_library_terms(ps.PolynomialLibrary(degree=2, include_bias=False), c)
    [x, x_dot, x**2, x*x_dot, x_dot**2]
    """
    state = coords.state
    names = [str(s) for s in state]
    sample = np.random.default_rng(0).uniform(-1.5, 1.5, size=(64, len(state)))
    # deepcopy, not sklearn.clone: some pysindy libraries (CustomLibrary) are not clonable
    fitted = copy.deepcopy(library).fit(sample)
    feature_names = fitted.get_feature_names(input_features=names)
    table = {str(s): s for s in state}
    terms = []
    for name in feature_names:
        try:
            terms.append(parse_expression(name, table) if name != "1" else sp.Integer(1))
        except ValueError as err:
            raise ValueError(f"terms: cannot translate feature {name!r} of "
                             f"{type(library).__name__} into a symbolic term ({err}); pass sympy "
                             "expressions instead") from None
    expected = np.asarray(fitted.transform(sample), dtype=float)
    evaluate = compile_entries(state, terms)
    got = np.column_stack([np.broadcast_to(v, (len(sample),)) for v in evaluate(sample)])
    if expected.shape != got.shape or not np.allclose(expected, got, rtol=1e-9, atol=1e-12):
        raise ValueError(
            f"terms: the feature names of {type(library).__name__} do not describe its "
            "features; pass sympy expressions instead")
    return terms


class ClassicalLibrary(SymbolicLibrary):
    """Newtonian terms entering the equations of chosen coordinates.

    Each (term ``k``, coordinate ``c``) with ``mask[k, c]`` true is one feature: the term in the
    equation of ``c``, zero elsewhere (viscous friction: ``qd_i`` in the equation of ``i``).

    Parameters
    ----------
    coords : Coordinates
        The generalized coordinates.
    terms : sequence of sympy.Expr or pysindy.BaseFeatureLibrary
        Terms in ``coords.variables``; a pysindy library is evaluated on ``(q, qd)``
        (:func:`pysindy_library_terms`).
    mask : array of bool, shape (n_terms, n), optional
        Which equations each term enters. Default: every equation.

    Attributes
    ----------
    terms_ : list of sympy.Expr
        The terms, checked (a pysindy library translated).
    mask_ : ndarray of bool, shape (n_terms, n)
        The equations each term enters.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x", "theta"])
    >>> friction = px.ClassicalLibrary(c, c.qd, mask=np.eye(2, dtype=bool))
    >>> friction.fit().get_feature_names()
    ['C_x[x_dot]', 'C_theta[theta_dot]']
    """

    category = "classical"
    column_rank = 2
    spec_type = "ClassicalLibrary"
    _parameter_constraints = {
        "coords": [InstanceOf(Coordinates, "a pysindy_xl.Coordinates")],
        "terms": [InstanceOf(sp.Basic, "a sympy expression"),
                  InstanceOf(BaseFeatureLibrary, "a pysindy feature library"),
                  Collection("a sequence of sympy expressions")],
        "mask": [None, Collection("an array of bool of shape (n_terms, n)")],
    }

    def __init__(self, coords: Coordinates, terms, mask=None):
        self.coords = coords
        self.terms = terms
        self.mask = mask

    def _resolved_terms(self) -> list[sp.Expr]:
        if isinstance(self.terms, BaseFeatureLibrary):
            return pysindy_library_terms(self.terms, self.coords)
        terms = as_expr_list(self.terms, "terms")
        allowed = set(self.coords.variables)
        for term in terms:
            extra = term.free_symbols - allowed
            if extra:
                raise ValueError(
                    f"terms: classical term {term} uses unknown symbols {sorted(map(str, extra))}")
        return terms

    def _resolved_mask(self, n_terms: int) -> np.ndarray:
        if self.mask is None:
            return np.ones((n_terms, self.coords.n), dtype=bool)
        mask = np.asarray(self.mask)
        if mask.shape != (n_terms, self.coords.n):
            raise ValueError(
                f"mask: expected shape (n_terms, n) = {(n_terms, self.coords.n)}, got {mask.shape}")
        if mask.dtype != bool and not np.isin(mask, (0, 1)).all():
            raise ValueError("mask: expected booleans (or 0/1)")
        if not mask.any():
            raise ValueError("mask: selects no equation for any term; expected at least one "
                             "True entry (leave the library out to have no classical terms)")
        return mask.astype(bool)

    def _build_symbolic(self):
        terms = self._resolved_terms()
        if not terms:
            raise ValueError("terms: expected at least one classical term")
        mask = self._resolved_mask(len(terms))
        self.terms_, self.mask_ = terms, mask
        columns = [(c, term) for k, term in enumerate(terms) for c in range(self.coords.n)
                   if mask[k, c]]
        names = [f"C_{self.coords.names[c]}[{term}]" for c, term in columns]
        return names, sp.Matrix(self.coords.n, len(columns),
                                lambda i, j: columns[j][1] if columns[j][0] == i else 0)

    def _feature_terms(self):
        return [term for term, row in zip(self.terms_, self.mask_, strict=True)
                for used in row if used]

    def to_spec(self) -> dict:
        """JSON-serializable description of this library, read back by :meth:`from_spec`.

        Returns
        -------
        dict
            ``{"type": spec_type, ...}``: the parameters as plain JSON values, terms in the
            restricted grammar (:func:`~pysindy_xl.expressions.format_expression`).
        """
        if not hasattr(self, "terms_"):
            self.fit()
        return {"type": self.spec_type, "terms": [format_expression(t) for t in self.terms_],
                "mask": self.mask_.astype(int).tolist()}

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
        ClassicalLibrary
            The library, not fitted.
        """
        terms = reader.terms(spec)
        mask = reader.matrix(spec, "mask", (len(terms), reader.coords.n), binary=True,
                             shape_name="(n_terms, n)")
        return cls(reader.coords, terms, mask=mask)
