"""A restricted expression grammar: parse catalog terms without ``eval`` or ``sympify``.

It knows numbers, the symbols it is given, the functions of :data:`FUNCTIONS` and ``+ - * /
** ^`` (juxtaposition multiplies, as in pysindy's ``"x y^2"``): a file cannot make it run code.
"""

from __future__ import annotations

import math
import numbers
import re

import numpy as np
import sympy as sp
from sympy.printing.str import StrPrinter

__all__ = ["parse_expression", "format_expression", "FUNCTIONS"]

FUNCTIONS = {
    "sin": sp.sin, "cos": sp.cos, "tan": sp.tan, "exp": sp.exp, "log": sp.log, "sqrt": sp.sqrt,
    "sinh": sp.sinh, "cosh": sp.cosh, "tanh": sp.tanh, "asin": sp.asin, "acos": sp.acos,
    "atan": sp.atan, "Abs": sp.Abs, "abs": sp.Abs, "sign": sp.sign,
}
_CONSTANTS = {"pi": sp.pi, "E": sp.E}
_TOKEN = re.compile(r"\s*(?:(?P<num>\d+\.?\d*(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?)"
                    r"|(?P<name>[A-Za-z_][A-Za-z_0-9]*)|(?P<op>\*\*|[-+*/^(),]))")
_MAX_LENGTH = 20_000
_MAX_DEPTH = 100
_MAX_NUMBER_DIGITS = 40
_MAX_POWER_DIGITS = 300  # a numeric power may not exceed 10**300 (no huge exact integers)
# bounds on the work a parsed term may cause (derivatives and expansion of the catalog)
_MAX_EXPANDED_TERMS = 1_000
_MAX_FUNCTION_DEPTH = 8
_MAX_OPERATIONS = 2_000


def _tokenize(text: str) -> list[tuple[str, str]]:
    tokens, pos = [], 0
    text = text.rstrip()
    while pos < len(text):
        match = _TOKEN.match(text, pos)
        if match is None or match.end() == pos:
            raise ValueError(f"cannot parse expression {text!r}: unexpected {text[pos:]!r}")
        kind = match.lastgroup
        tokens.append((kind, match.group(kind)))
        pos = match.end()
    return tokens


class _FullPrecisionPrinter(StrPrinter):
    """sympy's str printer, but floats keep every bit (``repr`` of the double)."""

    def _print_Float(self, expr):
        return repr(float(expr))


def format_expression(expr: sp.Expr) -> str:
    """Text of ``expr`` that :func:`parse_expression` turns back into the same expression.

    Floats are written with all their digits (17 significant), so that a saved model reads
    back bit for bit.

    Parameters
    ----------
    expr : sympy.Expr
        An expression of the restricted grammar.

    Returns
    -------
    str
        The expression as text.

    Examples
    --------
    >>> import sympy as sp
    >>> x = sp.Symbol("x")
    >>> format_expression(sp.Float(1 / 3) * sp.cos(x))
    '0.3333333333333333*cos(x)'
    """
    return _FullPrecisionPrinter().doprint(expr)


class _Parser:
    def __init__(self, text: str, symbols: dict[str, sp.Symbol]):
        self.text = text
        self.tokens = _tokenize(text)
        self.pos = 0
        self.depth = 0
        self.symbols = symbols

    def error(self, what: str):
        return ValueError(f"cannot parse expression {self.text!r}: {what}")

    def peek(self):
        return self.tokens[self.pos] if self.pos < len(self.tokens) else (None, None)

    def take(self, value=None):
        kind, token = self.peek()
        if kind is None or (value is not None and token != value):
            raise self.error(f"expected {value or 'more input'}")
        self.pos += 1
        return kind, token

    def parse(self) -> sp.Expr:
        expr = self.sum()
        if self.pos != len(self.tokens):
            raise self.error(f"unexpected {self.peek()[1]!r}")
        return expr

    def sum(self):
        expr = self.product()
        while self.peek()[1] in ("+", "-"):
            _, op = self.take()
            rhs = self.product()
            expr = expr + rhs if op == "+" else expr - rhs
        return expr

    def starts_implicit_factor(self):
        # pysindy writes "x y^2": juxtaposition multiplies names and parentheses, never a
        # number on the right ("3 2" or "1.2.3" are malformed, not products)
        kind, token = self.peek()
        return kind == "name" or token == "("

    def nested(self, parse):
        self.depth += 1
        if self.depth > _MAX_DEPTH:
            raise self.error(f"nested deeper than {_MAX_DEPTH} levels")
        try:
            return parse()
        finally:
            self.depth -= 1

    def product(self):
        expr = self.unary()
        while True:
            kind, token = self.peek()
            if token in ("*", "/"):
                self.take()
                rhs = self.unary()
                expr = expr * rhs if token == "*" else expr / rhs
            elif self.starts_implicit_factor():
                expr = expr * self.unary()
            else:
                return expr

    def unary(self):
        if self.peek()[1] in ("-", "+"):
            _, op = self.take()
            operand = self.nested(self.unary)
            return -operand if op == "-" else operand
        return self.power()

    def power(self):
        base = self.atom()
        if self.peek()[1] in ("**", "^"):
            self.take()
            exponent = self.nested(self.unary)
            if not exponent.is_number:
                raise self.error(f"the exponent {exponent} is not a number (symbolic powers "
                                 "such as power towers are not catalog terms)")
            if base.is_number:
                self.check_numeric_power(base, exponent)
            elif exponent.is_real is not True or exponent.is_finite is not True:
                raise self.error(f"the exponent {exponent} is not a finite real number")
            elif abs(float(exponent)) > 1000:
                raise self.error(f"the exponent {exponent} is too large")
            return base**exponent
        return base

    def check_numeric_power(self, base, exponent):
        # sympy evaluates numeric powers exactly: 9**9**9 would never finish
        try:
            size = abs(float(exponent)) * math.log10(max(abs(complex(base)), 1e-300))
        except (TypeError, ValueError, OverflowError):
            raise self.error("unsupported numeric power") from None
        if abs(float(exponent)) > 1000 or size > _MAX_POWER_DIGITS:
            raise self.error(f"numeric power {base}**{exponent} is too large")

    def check_numeric_value(self, value):
        # a number such as exp(exp(100)) would overflow (or hang) wherever it is evaluated
        try:
            number = complex(sp.N(value, 17))
        except (TypeError, ValueError, OverflowError, RecursionError):
            raise self.error(f"cannot evaluate the number {str(value)[:40]}") from None
        if not (math.isfinite(number.real) and math.isfinite(number.imag)) or abs(number) > 1e300:
            raise self.error(f"the number {str(value)[:40]} is too large")

    def atom(self):
        kind, token = self.take()
        if kind == "num":
            if len(token) > _MAX_NUMBER_DIGITS:
                raise self.error(f"number {token[:20]}... is too long")
            if re.fullmatch(r"\d+", token):
                return sp.Integer(token)
            return sp.Float(float(token))
        if token == "(":
            expr = self.nested(self.sum)
            self.take(")")
            return expr
        if kind == "name":
            if self.peek()[1] == "(":
                if token not in FUNCTIONS:
                    raise self.error(f"unknown function {token!r}")
                self.take("(")
                arg = self.nested(self.sum)
                self.take(")")
                value = FUNCTIONS[token](arg)
                if value.is_number:
                    self.check_numeric_value(value)
                return value
            if token in self.symbols:
                return self.symbols[token]
            if token in _CONSTANTS:
                return _CONSTANTS[token]
            raise self.error(f"unknown symbol {token!r}")
        raise self.error(f"unexpected {token!r}")


def parse_expression(text: str, symbols: dict[str, sp.Symbol]) -> sp.Expr:
    """Parse ``text`` into a sympy expression over the given ``symbols`` only.

    A restricted grammar, safe on untrusted text (``sympify`` would ``eval`` it): numbers, the
    given symbols, ``pi``, ``E``, ``+ - * / ** ^``, implicit products (``"2 x"``) and the
    functions of :data:`FUNCTIONS`. The size of the result is bounded (nesting of functions,
    terms once expanded, operations).

    Parameters
    ----------
    text : str
        Expression such as ``"x_dot**2*cos(theta)"`` or pysindy's ``"x theta_dot^2"``.
    symbols : dict of str to sympy.Symbol
        The only names allowed besides the whitelisted functions and ``pi``, ``E``
        (:meth:`Coordinates.symbol_table <pysindy_xl.Coordinates.symbol_table>`).

    Returns
    -------
    sympy.Expr
        The parsed expression, real and evaluable.

    Raises
    ------
    TypeError
        When ``text`` is not a str.
    ValueError
        When ``text`` is empty, outside the grammar, too large or not real.

    Examples
    --------
    >>> import sympy as sp
    >>> x = sp.Symbol("x")
    >>> parse_expression("2 x^2*sin(x)", {"x": x})
    2*x**2*sin(x)
    """
    if not isinstance(text, str):
        raise TypeError(f"text: expected str, got {type(text).__name__}")
    if len(text) > _MAX_LENGTH:
        raise ValueError(f"text: expression longer than {_MAX_LENGTH} characters")
    if not text.strip():
        raise ValueError("text: empty expression")
    try:
        expr = _Parser(text, symbols).parse()
    except (RecursionError, OverflowError, MemoryError):
        raise ValueError(f"text: expression {text[:60]!r} is too complex to parse") from None
    size = expression_size(expr)
    if size["depth"] > _MAX_FUNCTION_DEPTH:
        raise ValueError(f"text: {text[:60]!r} nests functions {size['depth']} deep (at most "
                         f"{_MAX_FUNCTION_DEPTH})")
    if size["terms"] > _MAX_EXPANDED_TERMS or size["operations"] > _MAX_OPERATIONS:
        raise ValueError(f"text: {text[:60]!r} is too large for a catalog term (about "
                         f"{size['terms']:.3g} terms once expanded, {size['operations']} "
                         f"operations; at most {_MAX_EXPANDED_TERMS} and {_MAX_OPERATIONS})")
    check_real_expression(expr, "text")
    check_term(expr, "text")
    return expr


def expression_size(expr: sp.Expr) -> dict:
    """Cheap upper bounds on the work an expression causes, computed without expanding it.

    Parameters
    ----------
    expr : sympy.Expr
        The expression.

    Returns
    -------
    dict
        ``terms``: bound on the terms of ``sympy.expand(expr)`` (``(a + b + ...)**n`` of ``k``
        terms counts ``C(n + k - 1, k - 1)``, a call the size of its argument); ``depth``:
        nesting of function calls; ``operations``: nodes of the tree.

    Examples
    --------
    >>> import sympy as sp
    >>> a, b = sp.symbols("a b")
    >>> expression_size((a + b) ** 3 * sp.sin(sp.cos(a)))
    {'terms': 4, 'depth': 2, 'operations': 9}
    """
    memo: dict = {}

    def visit(e):
        if e in memo:
            return memo[e]
        if e.is_Atom:
            out = (1, 0, 1)
        else:
            parts = [visit(a) for a in e.args]
            ops = 1 + sum(p[2] for p in parts)
            depth = max(p[1] for p in parts)
            if isinstance(e, sp.Add):
                terms = sum(p[0] for p in parts)
            elif isinstance(e, sp.Mul):
                terms = math.prod(p[0] for p in parts)
            elif isinstance(e, sp.Pow):
                k, exponent = parts[0][0], e.exp
                if exponent.is_Integer and exponent > 0:
                    n = int(exponent)
                    terms = math.comb(n + k - 1, k - 1) if k > 1 else 1
                else:
                    terms = k
            else:  # a function call: one atom, whose derivatives repeat its argument
                terms, depth = parts[0][0] if parts else 1, depth + 1
            out = (min(terms, 10**18), depth, ops)
        memo[e] = out
        return out

    if not isinstance(expr, sp.Basic):
        raise TypeError(f"expr: expected a sympy expression, got {type(expr).__name__}")
    terms, depth, ops = visit(expr)
    return {"terms": int(terms), "depth": int(depth), "operations": int(ops)}


def check_term(expr, name: str) -> None:
    """Raise (naming ``name``) if ``expr`` is not an evaluable catalog term.

    A catalog term holds numbers, symbols, ``+ - * / **`` and :data:`FUNCTIONS` only:
    derivatives, undefined functions, relations cannot be evaluated on data nor saved.

    Parameters
    ----------
    expr : sympy.Expr
        The term.
    name : str
        The argument named in the error message.

    Raises
    ------
    TypeError
        When ``expr`` is not a sympy expression.
    ValueError
        When it holds anything else outside the grammar.
    """
    if not isinstance(expr, sp.Expr):
        raise TypeError(f"{name}: expected a sympy expression, got {type(expr).__name__}")
    allowed = tuple({f for f in FUNCTIONS.values() if isinstance(f, type)})
    for sub in sp.preorder_traversal(expr):
        if sub.is_Atom or isinstance(sub, (sp.Add, sp.Mul, sp.Pow)):
            if isinstance(sub, sp.Atom) and not (sub.is_Symbol or sub.is_number):
                raise ValueError(f"{name}: {expr} contains {sub}, which is not a number nor a "
                                 "symbol")
            continue
        if isinstance(sub, allowed):
            continue
        raise ValueError(
            f"{name}: {expr} contains {type(sub).__name__}, which a catalog term cannot hold "
            f"(only numbers, symbols, + - * / ** and the functions {sorted(FUNCTIONS)}); "
            "a term must be differentiable twice and evaluable on data")


def check_real_expression(expr: sp.Expr, name: str) -> None:
    """Raise ``ValueError`` (naming ``name``) if ``expr`` holds a non-real or infinite number.

    ``zoo``, ``nan``, ``I``: NumPy would turn them into NaN or silently drop them.

    Parameters
    ----------
    expr : sympy.Expr
        The expression.
    name : str
        The argument named in the error message.

    Examples
    --------
    >>> import sympy as sp
    >>> x = sp.Symbol("x")
    >>> check_real_expression(sp.sqrt(-1) * x, "terms")
    Traceback (most recent call last):
    ...
    ValueError: terms: I*x contains the non-real or infinite number I
    """
    try:
        for sub in sp.preorder_traversal(expr):
            if sub.is_number and (sub.is_real is not True or sub.is_finite is False):
                raise ValueError(f"{name}: {expr} contains the non-real or infinite number {sub}")
    except (OverflowError, RecursionError):
        raise ValueError(f"{name}: a number in the expression is too large to evaluate") \
            from None


def as_expression(value, symbols: dict[str, sp.Symbol], name: str) -> sp.Expr:
    """A sympy expression from a sympy expression, a real number or a string.

    Strings are parsed by the restricted grammar (:func:`parse_expression`), never by
    ``sympify``.

    Parameters
    ----------
    value : sympy.Expr, int, float or str
        The expression.
    symbols : dict of str to sympy.Symbol
        The names a string may use.
    name : str
        The argument named in error messages.

    Returns
    -------
    sympy.Expr
        The expression, checked to be real.

    Examples
    --------
    >>> import sympy as sp
    >>> as_expression("__import__('os')", {"x": sp.Symbol("x")}, "lagrangian")
    Traceback (most recent call last):
    ...
    ValueError: lagrangian: cannot parse expression "__import__('os')": unexpected "'os')"
    """
    if isinstance(value, str):
        try:
            return parse_expression(value, symbols)
        except ValueError as err:
            raise ValueError(f"{name}: {str(err).removeprefix('text: ')}") from None
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name}: expected a sympy expression or a string, got a bool")
    if isinstance(value, numbers.Real):
        return sp.Float(float(value)) if not isinstance(value, numbers.Integral) else \
            sp.Integer(int(value))
    if isinstance(value, sp.Expr):
        return value
    raise TypeError(f"{name}: expected a sympy expression or a string, got {type(value).__name__}")
