"""One validation layer per kind of input: options (:func:`check_option`) and numeric arrays
(:func:`check_numeric_array`), answering a mistake with a ``ValueError`` or ``TypeError`` that
names the argument and what was expected; and the warnings about what was identified.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

__all__ = ["IdentificationWarning", "UnexplainedCoordinateWarning", "check_option",
           "check_numeric_array", "check_instance", "check_indices", "check_times",
           "argument_type", "Interval", "Options", "Boolean", "HasMethods", "InstanceOf",
           "Collection", "check_parameter", "validate_params"]

_KINDS = ("bool", "int", "real", "choice")


class IdentificationWarning(UserWarning):
    """The identified model looks wrong on its own training data.

    For instance, an identified mass matrix that is not positive definite on the training
    states: the model will not simulate faithfully there. Turn it into an error with
    ``warnings.simplefilter("error", px.IdentificationWarning)``.

    Examples
    --------
    On a single sine ``x'' = -x``: the columns of ``x''`` and ``x`` are proportional, the fit
    cannot tell the mass from the stiffness and warns.

    >>> import warnings
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
    >>> t = np.linspace(0, 5, 501)
    >>> x, xd, xdd = np.sin(t)[:, None], np.cos(t)[:, None], -np.sin(t)[:, None]
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     model = px.XLSINDy(lib).fit(x, t, x_dot=xd, x_ddot=xdd, u=xdd + 3 * x)
    >>> any(issubclass(w.category, px.IdentificationWarning) for w in caught)
    True
    """


class UnexplainedCoordinateWarning(IdentificationWarning):
    """No identified term (besides the forces) enters some coordinate's equation.

    The model cannot predict that coordinate. :class:`~pysindy_xl.MixedOptimizer` expects it of
    its explicit part (it then solves those coordinates implicitly) and silences it there.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> issubclass(px.UnexplainedCoordinateWarning, px.IdentificationWarning)
    True
    """


def _describe_range(low, high, low_open, high_open) -> str:
    if low is not None and high is not None:
        return f" in {'(' if low_open else '['}{low}, {high}{')' if high_open else ']'}"
    if low is not None:
        return f" {'>' if low_open else '>='} {low}"
    if high is not None:
        return f" {'<' if high_open else '<='} {high}"
    return ""


def check_option(name: str, value, kind: str, *, choices=(), low=None, high=None,
                 low_open=False, high_open=False, allow_none=False, allow_inf=False):
    """Validate one scalar option ``name`` and return it as the Python type of ``kind``.

    ``kind``: ``"bool"`` (no strings or numbers), ``"int"`` (no bools or floats), ``"real"``
    (NaN refused, inf only with ``allow_inf``) within ``low``/``high`` (excluded with
    ``low_open``/``high_open``), or ``"choice"`` among ``choices``. A wrong type raises
    ``TypeError``, a value out of range ``ValueError``.

    >>> check_option("timeout", -1.0, "real", low=0, low_open=True, allow_none=True)
    Traceback (most recent call last):
    ...
    ValueError: timeout: expected a real number > 0 or None, got -1.0
    """
    if kind not in _KINDS:
        raise ValueError(f"kind: expected one of {_KINDS}, got {kind!r}")
    if value is None and allow_none:
        return None
    or_none = " or None" if allow_none else ""
    if kind == "choice":
        if isinstance(value, (str, numbers.Number, type(None))) and value in choices:
            return value
        raise (ValueError if isinstance(value, str) else TypeError)(
            f"{name}: expected one of {tuple(choices)}{or_none}, got {value!r}")
    if kind == "bool":
        if isinstance(value, (bool, np.bool_)):
            return bool(value)
        raise TypeError(f"{name}: expected True or False{or_none}, got the "
                        f"{type(value).__name__} {value!r}")
    expected = ("an integer" if kind == "int" else "a real number") + _describe_range(
        low, high, low_open, high_open) + or_none
    if isinstance(value, type):
        raise TypeError(f"{name}: expected {expected}, got the class {value.__name__}")
    integral = isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_))
    real = isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))
    if kind == "int" and real and not integral:  # a number, but not a whole one
        raise ValueError(f"{name}: expected {expected}, got {value!r}")
    if (kind == "int" and not integral) or (kind == "real" and not real):
        raise TypeError(f"{name}: expected {expected}, got the {type(value).__name__} {value!r}")
    value = int(value) if kind == "int" else float(value)
    if kind == "real" and (math.isnan(value) or (math.isinf(value) and not allow_inf)):
        raise ValueError(f"{name}: expected {expected}, got {value!r}")
    if low is not None and (value < low or (low_open and value == low)):
        raise ValueError(f"{name}: expected {expected}, got {value!r}")
    if high is not None and (value > high or (high_open and value == high)):
        raise ValueError(f"{name}: expected {expected}, got {value!r}")
    return value


def check_instance(name: str, value, what: str, method: str | None = None):
    """Return ``value``, refusing a class where an instance (``what``, e.g. ``"a smoother"``)
    is due and an object without the needed ``method``."""
    if isinstance(value, type):
        raise TypeError(f"{name}: expected an instance ({what}), got the class "
                        f"{value.__name__}; write {value.__name__}()")
    if method is not None and not callable(getattr(value, method, None)):
        raise TypeError(f"{name}: expected {what} with a {method} method, got "
                        f"{type(value).__name__}")
    return value


def check_numeric_array(a, name: str, *, ndim=None, min_samples: int = 1,
                        finite: bool = True, max_abs: float | None = None) -> np.ndarray:
    """``a`` as a float array, refusing what NumPy would cast silently (complex, str, bool,
    datetimes, objects), fewer than ``min_samples`` rows, dimensions not in ``ndim``, with
    ``finite`` NaN or inf, and values beyond ``max_abs`` (products must not overflow).

    >>> check_numeric_array([1 + 2j], "x")
    Traceback (most recent call last):
    ...
    TypeError: x: expected real numbers, got complex values
    """
    if a is None:
        raise ValueError(f"{name}: expected an array of real numbers, got None")
    if isinstance(a, (str, bytes)):
        raise TypeError(f"{name}: expected an array of real numbers, got a {type(a).__name__}")
    if isinstance(a, type):
        raise TypeError(f"{name}: expected an array of real numbers, got the class {a.__name__}")
    if hasattr(a, "tocsr") and hasattr(a, "nnz"):  # scipy.sparse, without importing it
        raise TypeError(f"{name}: sparse input is not supported; pass a dense array "
                        "(e.g. X.toarray())")
    try:
        raw = np.asarray(a)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{name}: expected a rectangular array of real numbers ({err})") from None
    kind = raw.dtype.kind
    if kind == "c":
        raise TypeError(f"{name}: expected real numbers, got complex values")
    if kind == "b":
        raise TypeError(f"{name}: expected real numbers, got booleans")
    if kind in "US":
        raise TypeError(f"{name}: expected real numbers, got an array of str ({raw.dtype})")
    if kind in "mM":
        raise TypeError(f"{name}: expected real numbers (seconds), got {raw.dtype} values; "
                        "convert them to seconds first")
    if kind == "O":
        for item in raw.reshape(-1)[:1000]:
            if not (isinstance(item, numbers.Real) and not isinstance(item, (bool, np.bool_))):
                raise TypeError(f"{name}: expected real numbers, got an element of type "
                                f"{type(item).__name__}")
    if kind not in "iufO":
        raise TypeError(f"{name}: expected real numbers, got {raw.dtype} values")
    try:
        out = raw.astype(float)
    except (TypeError, ValueError, OverflowError) as err:
        raise ValueError(f"{name}: expected real numbers ({err})") from None
    if ndim is not None:
        accepted = (ndim,) if isinstance(ndim, int) else tuple(ndim)
        if out.ndim not in accepted:
            raise ValueError(f"{name}: expected a {' or '.join(f'{d}-D' for d in accepted)} "
                             f"array, got shape {out.shape}")
    if out.ndim == 0 and min_samples > 0:
        raise ValueError(f"{name}: expected an array, got a scalar")
    if out.ndim > 0 and out.shape[0] < min_samples:
        raise ValueError(f"{name}: expected at least {min_samples} sample"
                         f"{'s' if min_samples > 1 else ''}, got shape {out.shape}")
    if finite and not np.all(np.isfinite(out)):
        raise ValueError(f"{name}: contains NaN or inf")
    if max_abs is not None and out.size:
        with np.errstate(invalid="ignore"):
            largest = np.nanmax(np.abs(np.where(np.isfinite(out), out, 0.0)))
        if largest > max_abs:
            raise ValueError(f"{name}: values up to {largest:.3g} in magnitude are too large "
                             f"(at most {max_abs:.0e}); rescale the data (other units)")
    return out


def check_indices(value, name: str, size: int) -> np.ndarray:
    """``value`` (None: none) as a 1-D int array of indices in ``[0, size)``; fractional
    numbers, booleans and strings refused."""
    raw = np.asarray([] if value is None else value, dtype=object).reshape(-1)
    for item in raw:
        if not isinstance(item, numbers.Integral) or isinstance(item, (bool, np.bool_)):
            raise TypeError(f"{name}: expected integer indices, got {item!r}")
    out = raw.astype(int)
    if np.any((out < 0) | (out >= size)):
        raise ValueError(f"{name}: indices must lie in [0, {size}), got {out.tolist()}")
    return out


def check_times(t, name: str) -> np.ndarray:
    """``t`` as a 1-D float array of at least two finite, strictly increasing times."""
    t = check_numeric_array(t, name, finite=False, min_samples=0)
    if t.ndim != 1 or len(t) < 2:
        raise ValueError(f"{name}: expected a 1-D array of at least 2 times, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ValueError(f"{name}: contains NaN or inf")
    steps = np.diff(t)
    if np.any(steps <= 0):
        bad = np.flatnonzero(steps <= 0)
        what = "repeated" if steps[bad[0]] == 0 else "decreasing"
        raise ValueError(
            f"{name}: times must be strictly increasing; {bad.size} step(s) are not, the first "
            f"{what} at samples {bad[0]} and {bad[0] + 1} ({t[bad[0]]:.9g}, {t[bad[0] + 1]:.9g}): "
            "merge the samples of a repeated stamp (keep one, or their mean) and sort the rest")
    return t


def argument_type(kind: str, **bounds):
    """An ``argparse`` type: the text as an ``"int"`` or ``"real"`` number checked by
    :func:`check_option` with ``bounds``, refused with ``argparse.ArgumentTypeError``.

    >>> fraction = argument_type("real", low=0, low_open=True, high=1)
    >>> fraction("0.5")
    0.5
    >>> fraction("2")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: expected a real number in (0, 1], got 2.0
    """
    import argparse
    parse = int if kind == "int" else float

    def convert(text):
        try:
            value = parse(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected {'an integer' if kind == 'int' else 'a number'}, got {text!r}"
            ) from None
        try:
            return check_option("value", value, kind, **bounds)
        except (TypeError, ValueError) as error:
            raise argparse.ArgumentTypeError(str(error).removeprefix("value: ")) from None

    convert.__name__ = f"{kind}_argument"
    return convert


# -- declarative parameter constraints --------------------------------------------------------
# An estimator states what each of its parameters accepts in a class attribute
# ``_parameter_constraints = {name: [constraint, ...]}`` (as scikit-learn's estimators do) and
# its fit calls :func:`validate_params`. A constraint is ``None`` (the value None), a literal
# (``"auto"``, ``False``: that very value), or one of the classes below.


class Interval:
    """A number of ``kind`` ``"int"`` or ``"real"`` within bounds, as :func:`check_option` checks
    it (NaN refused, inf only with ``allow_inf``).

    >>> Interval("real", 0, 1, high_open=True).describe()
    'a real number in [0, 1)'
    """

    def __init__(self, kind, low=None, high=None, *, low_open=False, high_open=False,
                 allow_inf=False):
        if kind not in ("int", "real"):
            raise ValueError(f"kind: expected 'int' or 'real', got {kind!r}")
        self.kind, self.low, self.high = kind, low, high
        self.low_open, self.high_open, self.allow_inf = low_open, high_open, allow_inf

    def describe(self) -> str:
        """What the constraint accepts, in words."""
        return (("an integer" if self.kind == "int" else "a real number")
                + _describe_range(self.low, self.high, self.low_open, self.high_open))

    def check(self, name: str, value, allow_none: bool = False):
        """Raise the ``TypeError``/``ValueError`` of :func:`check_option` for a bad ``value``."""
        return check_option(name, value, self.kind, low=self.low, high=self.high,
                            low_open=self.low_open, high_open=self.high_open,
                            allow_none=allow_none, allow_inf=self.allow_inf)

    def claims(self, value) -> bool:
        """Whether a refused ``value`` is this constraint's to explain (any non-string)."""
        return not isinstance(value, str)


class Options:
    """One of the strings ``choices``.

    >>> Options(("lasso", "threshold")).describe()
    "one of ('lasso', 'threshold')"
    """

    def __init__(self, choices):
        self.choices = tuple(choices)

    def describe(self) -> str:
        """What the constraint accepts, in words."""
        return f"one of {self.choices}"

    def check(self, name: str, value, allow_none: bool = False):
        """Raise the ``ValueError`` (a string) or ``TypeError`` of :func:`check_option`."""
        return check_option(name, value, "choice", choices=self.choices, allow_none=allow_none)

    def claims(self, value) -> bool:
        """Whether a refused ``value`` is this constraint's to explain (a string)."""
        return isinstance(value, str)


class Boolean:
    """``True`` or ``False`` (NumPy's booleans too, no numbers or strings)."""

    def describe(self) -> str:
        """What the constraint accepts, in words."""
        return "True, False"

    def check(self, name: str, value, allow_none: bool = False):
        """Raise the ``TypeError`` of :func:`check_option` for a non-boolean ``value``."""
        return check_option(name, value, "bool", allow_none=allow_none)

    def claims(self, value) -> bool:
        """Whether a refused ``value`` is this constraint's to explain (never: its words are
        part of the combined message)."""
        return False


class HasMethods:
    """An instance (not a class, not a string) with the callable ``method``, described as
    ``what``.

    >>> HasMethods("a smoother", "smooth").describe()
    'a smoother with a smooth method'
    """

    def __init__(self, what: str, method: str | None = None):
        self.what, self.method = what, method

    def describe(self) -> str:
        """What the constraint accepts, in words."""
        return self.what + (f" with a {self.method} method" if self.method else "")

    def check(self, name: str, value, allow_none: bool = False):
        """Raise the ``TypeError`` of :func:`check_instance` for a bad ``value``."""
        if value is None and allow_none:
            return None
        if isinstance(value, str):
            raise TypeError(f"{name}: expected {self.describe()}, got the str {value!r}")
        return check_instance(name, value, self.what, self.method)

    def claims(self, value) -> bool:
        """Whether a refused ``value`` is this constraint's to explain (a class or an object
        that is neither a string nor a number)."""
        return isinstance(value, type) or not isinstance(value, (str, numbers.Number))


class InstanceOf:
    """An instance of ``types``, described as ``what``.

    >>> InstanceOf(str, "a cvxpy solver name").describe()
    'a cvxpy solver name'
    """

    def __init__(self, types, what: str):
        self.types, self.what = types, what

    def describe(self) -> str:
        """What the constraint accepts, in words."""
        return self.what

    def accepts(self, value) -> bool:
        """Whether ``value`` is an instance of ``types`` (no message built, no ``repr``)."""
        return isinstance(value, self.types)

    def check(self, name: str, value, allow_none: bool = False):
        """Raise a ``TypeError`` naming ``name`` for a ``value`` of another type."""
        if (value is None and allow_none) or isinstance(value, self.types):
            return value
        raise TypeError(f"{name}: expected {self.what}{' or None' if allow_none else ''}, got "
                        f"{value!r}")

    def claims(self, value) -> bool:
        """Whether a refused ``value`` is this constraint's to explain (never: its words are
        part of the combined message)."""
        return False


class Collection:
    """An iterable instance that is not a string (a list, tuple, array, mapping or sequence
    object), described as ``what``; its entries are checked where they are used.

    >>> Collection("a sequence of joint names").describe()
    'a sequence of joint names'
    >>> Collection("a sequence of joint names").check("joints", "hinge")
    Traceback (most recent call last):
    ...
    TypeError: joints: expected a sequence of joint names, got the str 'hinge'
    """

    def __init__(self, what: str):
        self.what = what

    def describe(self) -> str:
        """What the constraint accepts, in words."""
        return self.what

    def accepts(self, value) -> bool:
        """Whether ``value`` is an iterable instance other than a string (no message built)."""
        return not isinstance(value, (str, bytes, type)) and callable(
            getattr(value, "__iter__", None))

    def check(self, name: str, value, allow_none: bool = False):
        """Raise a ``TypeError`` naming ``name`` for a string, a class or a non-iterable."""
        if value is None and allow_none:
            return value
        if not self.accepts(value):
            kind = "class" if isinstance(value, type) else type(value).__name__
            shown = value.__name__ if isinstance(value, type) else repr(value)
            raise TypeError(f"{name}: expected {self.what}{' or None' if allow_none else ''}, "
                            f"got the {kind} {shown}")
        return value

    def claims(self, value) -> bool:
        """Whether a refused ``value`` is this constraint's to explain (never: its words are
        part of the combined message)."""
        return False


def _accepts(rule, name, value) -> bool:
    quick = getattr(rule, "accepts", None)  # a test that formats no message (no repr)
    if quick is not None:
        return quick(value)
    try:
        rule.check(name, value)
    except (TypeError, ValueError):
        return False
    return True


def _is_literal(value, literal) -> bool:
    return type(value) is type(literal) and value == literal


def check_parameter(name: str, value, constraints):
    """Check the parameter ``name`` against its list of ``constraints``.

    The value is accepted when it is None and ``None`` is listed, when it is one of the listed
    literals (``"auto"``, ``False``) or when a constraint object accepts it. A refused value is
    explained by the one constraint object listed alone, else by the first that claims it (its
    own message), else by a ``TypeError`` listing what is accepted (a ``ValueError`` for a
    string where an :class:`Options` is listed).

    Parameters
    ----------
    name : str
        The parameter's name, which the error names.
    value : object
        Its value.
    constraints : list
        ``None``, literals and constraint objects (:class:`Interval`, :class:`Options`,
        :class:`Boolean`, :class:`HasMethods`, :class:`InstanceOf`, :class:`Collection`).

    Returns
    -------
    object
        ``value``, unchanged.

    Examples
    --------
    >>> check_parameter("threshold", "auto", ["auto", Interval("real", 0, 1, high_open=True)])
    'auto'
    >>> check_parameter("threshold", 1.5, ["auto", Interval("real", 0, 1, high_open=True)])
    Traceback (most recent call last):
    ...
    ValueError: threshold: expected a real number in [0, 1), got 1.5
    >>> check_parameter("residual_covariance", "yes", ["auto", Boolean()])
    Traceback (most recent call last):
    ...
    TypeError: residual_covariance: expected True, False or 'auto', got the str 'yes'
    """
    allow_none = any(c is None for c in constraints)
    literals = [c for c in constraints if c is not None and isinstance(c, (str, bool, int))]
    rules = [c for c in constraints if c is not None and not isinstance(c, (str, bool, int))]
    if (value is None and allow_none) or any(_is_literal(value, lit) for lit in literals):
        return value
    if any(_accepts(rule, name, value) for rule in rules):
        return value
    if len(rules) == 1 and not literals:
        rules[0].check(name, value, allow_none)
    for rule in rules:
        if rule.claims(value):
            rule.check(name, value)
    words = [rule.describe() for rule in rules] + [repr(lit) for lit in literals]
    words += ["None"] if allow_none else []
    expected = words[0] if len(words) == 1 else ", ".join(words[:-1]) + " or " + words[-1]
    misspelled = isinstance(value, str) and any(isinstance(r, Options) for r in rules)
    raise (ValueError if misspelled else TypeError)(
        f"{name}: expected {expected}, got the {type(value).__name__} {value!r}")


def validate_params(estimator):
    """Check every parameter of ``estimator`` against the class attribute
    ``_parameter_constraints`` (``{name: [constraint, ...]}``) with :func:`check_parameter`;
    called at the start of ``fit``.

    Parameters
    ----------
    estimator : object
        An estimator whose class declares ``_parameter_constraints``.

    Returns
    -------
    None

    Examples
    --------
    >>> class Smoother:
    ...     _parameter_constraints = {"lam": [Interval("real", 0, low_open=True)]}
    ...     def __init__(self, lam=1.0):
    ...         self.lam = lam
    >>> validate_params(Smoother(lam=-1.0))
    Traceback (most recent call last):
    ...
    ValueError: lam: expected a real number > 0, got -1.0
    """
    for name, constraints in type(estimator)._parameter_constraints.items():
        check_parameter(name, getattr(estimator, name), constraints)
