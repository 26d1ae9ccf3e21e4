"""Reading library specifications from untrusted files, within a budget.

:class:`SpecReader` looks each ``{"type": ...}`` object up in
:data:`~pysindy_xl.feature_library.LIBRARY_TYPES` (a file never makes Python import anything)
and hands it to the class's ``from_spec`` with itself, so every library parses its terms and
matrices the same bounded way.
"""

from __future__ import annotations

import numpy as np

from ..expressions import expression_size, parse_expression
from ..symbols import Coordinates
from ._base import LIBRARY_TYPES

__all__ = ["SpecError", "SpecReader"]

#: Largest exponent of a polynomial term read from a file.
_MAX_POWER = 64


class SpecError(ValueError):
    """A library specification that cannot be read (the message says which part).

    A ``ValueError``; :meth:`XLSINDy.load <pysindy_xl.XLSINDy.load>` reports it as an invalid
    model file.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> SpecReader(px.Coordinates(["x"])).terms({"type": "lagrange", "terms": []})
    Traceback (most recent call last):
    ...
    pysindy_xl.feature_library.spec.SpecError: lagrange.terms must be a non-empty list of strings
    """


class SpecReader:
    """Parses library specifications for the coordinates of one model file.

    Parameters
    ----------
    coords : Coordinates
        The coordinates of the model file.
    max_terms : int, default 5000
        Catalog terms in all the specification.
    max_size : int, default 20000
        Sum of the terms' expanded sizes (:func:`~pysindy_xl.expressions.expression_size`).
    max_depth : int, default 4
        Nesting of libraries.
    max_monomials : int, default 500000
        Monomials of the polynomial terms in all.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> spec = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2]).to_spec()
    >>> SpecReader(c).library(spec).fit().get_feature_names()
    ['L[x_dot**2]', 'L[x**2]']
    >>> SpecReader(c).library({"type": "os.system"})
    Traceback (most recent call last):
    ...
    pysindy_xl.feature_library.spec.SpecError: unknown library type 'os.system'
    """

    def __init__(self, coords: Coordinates, max_terms: int = 5_000, max_size: int = 20_000,
                 max_depth: int = 4, max_monomials: int = 500_000):
        self.coords = coords
        self.max_terms = max_terms
        self.max_size = max_size
        self.max_depth = max_depth
        self.max_monomials = max_monomials
        self._symbols = {str(s): s for s in coords.variables}
        self._terms = self._size = self._depth = self._monomials = 0

    @staticmethod
    def expect(condition: bool, what: str) -> None:
        """Raise :class:`SpecError` saying ``what`` unless ``condition``.

        Parameters
        ----------
        condition : bool
            What must hold.
        what : str
            The message otherwise.
        """
        if not condition:
            raise SpecError(what)

    def library(self, spec):
        """The library ``spec`` describes (nested ones through this same reader).

        Parameters
        ----------
        spec : dict
            ``{"type": spec_type, ...}``, the type one of
            :data:`~pysindy_xl.feature_library.LIBRARY_TYPES`.

        Returns
        -------
        SymbolicLibrary
            The library, not fitted.

        Raises
        ------
        SpecError
            For an unknown type, libraries nested too deep or a part that cannot be read.
        """
        self.expect(isinstance(spec, dict) and isinstance(spec.get("type"), str),
                    "library spec must be an object with a 'type'")
        cls = LIBRARY_TYPES.get(spec["type"])
        self.expect(cls is not None, f"unknown library type {spec['type']!r}")
        self.expect(self._depth < self.max_depth,
                    f"libraries nested deeper than {self.max_depth} levels")
        self._depth += 1
        try:
            return cls.from_spec(spec, self)
        finally:
            self._depth -= 1

    def terms(self, spec, key: str = "terms") -> list:
        """``spec[key]``: a non-empty list of terms in the restricted grammar, parsed.

        Parameters
        ----------
        spec : dict
            The library's description.
        key : str, default "terms"
            The entry holding the terms.

        Returns
        -------
        list of sympy.Expr
            The terms, taken from the budget.

        Examples
        --------
        >>> import pysindy_xl as px
        >>> reader = SpecReader(px.Coordinates(["x"]))
        >>> reader.terms({"terms": ["x_dot**2", "cos(x)"]})
        [x_dot**2, cos(x)]
        """
        raw = spec.get(key)
        where = f"{spec.get('type')}.{key}"
        self.expect(isinstance(raw, list) and raw and all(isinstance(t, str) for t in raw),
                    f"{where} must be a non-empty list of strings")
        self.count_terms(len(raw))
        return [self.term(text) for text in raw]

    def count_terms(self, count: int) -> None:
        """Take ``count`` catalog terms from the budget.

        Parameters
        ----------
        count : int
            Terms read.

        Raises
        ------
        SpecError
            When the specification holds more than ``max_terms`` terms in all.
        """
        self.expect(count <= self.max_terms - self._terms,
                    f"more than {self.max_terms} catalog terms")
        self._terms += count

    def term(self, text: str):
        """One term in the restricted grammar, its expanded size taken from the budget.

        Parameters
        ----------
        text : str
            The term.

        Returns
        -------
        sympy.Expr
            The parsed term (:func:`~pysindy_xl.expressions.parse_expression`).
        """
        try:
            expr = parse_expression(text, self._symbols)
        except (TypeError, ValueError) as err:
            raise SpecError(str(err)) from None
        self._size += expression_size(expr)["terms"]
        self.expect(self._size <= self.max_size,
                    f"the catalog is too large (more than {self.max_size} expanded terms)")
        return expr

    def polynomial(self, item, width: int, where: str) -> tuple[np.ndarray, np.ndarray]:
        """A polynomial term: integer exponent rows and their coefficients, checked.

        Parameters
        ----------
        item : dict
            ``{"exponents": (T, width) integers in [0, 64], "coefficients": (T,) finite numbers}``.
        width : int
            Exponents per row.
        where : str
            The part of the specification, named in error messages.

        Returns
        -------
        exponents : ndarray of int, shape (T, width)
        coefficients : ndarray, shape (T,)
            ``T`` is taken from the monomial budget.
        """
        self.expect(isinstance(item, dict) and set(item) == {"exponents", "coefficients"},
                    f"{where} must be an object with exponents and coefficients")
        coefficients, exponents = item["coefficients"], item["exponents"]
        self.expect(isinstance(coefficients, list) and isinstance(exponents, list)
                    and len(coefficients) == len(exponents),
                    f"{where}: one exponent row per coefficient")
        self._monomials += len(coefficients)
        self.expect(self._monomials <= self.max_monomials,
                    f"the catalog is too large (more than {self.max_monomials} monomials)")
        self.expect(all(isinstance(c, (int, float)) and not isinstance(c, bool)
                        and np.isfinite(c) for c in coefficients)
                    and all(isinstance(row, list) and len(row) == width
                            and all(isinstance(e, int) and not isinstance(e, bool)
                                    and 0 <= e <= _MAX_POWER for e in row)
                            for row in exponents),
                    f"{where}: exponents must be rows of {width} integers in [0, {_MAX_POWER}]"
                    " and coefficients finite numbers")
        return (np.asarray(exponents, dtype=int).reshape(-1, width),
                np.asarray(coefficients, dtype=float))

    def matrix(self, spec, key: str, shape: tuple, binary: bool = False,
               shape_name: str | None = None) -> np.ndarray:
        """``spec[key]``: a finite numeric matrix of a given shape.

        Parameters
        ----------
        spec : dict
            The library's description.
        key : str
            The entry holding the matrix.
        shape : tuple of int
            The expected shape.
        binary : bool, default False
            Only 0 and 1 allowed (a mask).
        shape_name : str, optional
            The shape as written in error messages, e.g. ``"(n, n)"``; default None: ``shape``.

        Returns
        -------
        ndarray
            The matrix, of dtype bool when ``binary``, float otherwise.

        Examples
        --------
        >>> import pysindy_xl as px
        >>> reader = SpecReader(px.Coordinates(["x"]))
        >>> reader.matrix({"interlink": [[2.0]]}, "interlink", (1, 1))
        array([[2.]])
        """
        where = f"{spec.get('type')}.{key}"
        label = f"{shape_name} = {tuple(shape)}" if shape_name else str(tuple(shape))
        raw = spec.get(key)
        refused = (str,) if binary else (str, bool)
        try:
            numeric = isinstance(raw, list) and not any(
                isinstance(v, refused) for v in np.ravel(np.asarray(raw, dtype=object)))
            matrix = np.asarray(raw, dtype=float) if numeric else None
        except (TypeError, ValueError):  # ragged nested lists, non-numbers
            numeric, matrix = False, None
        if binary:
            self.expect(numeric and matrix.shape == tuple(shape)
                        and bool(np.isin(matrix, (0, 1)).all()),
                        f"{where} must be a 0/1 matrix {label}")
            return matrix.astype(bool)
        self.expect(numeric, f"{where} must be a numeric matrix {label}")
        self.expect(matrix.shape == tuple(shape) and bool(np.all(np.isfinite(matrix))),
                    f"{where} must be a finite {shape_name or ''} matrix of shape {tuple(shape)}"
                    .replace("  ", " "))
        return matrix
