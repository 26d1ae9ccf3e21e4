"""A restricted expression grammar: parse catalog terms without ``eval`` or ``sympify``.

Saved models and pysindy feature names are turned back into sympy expressions by this parser,
which only knows numbers, the symbols it is given, a whitelist of functions and the operators
``+ - * / ** ^`` (and implicit multiplication by juxtaposition, as in pysindy's ``"x y^2"``).
Nothing in a file can make it execute code.
"""

from __future__ import annotations

import math
import re

import sympy as sp
from sympy.printing.str import StrPrinter

__all__ = ["parse_expression", "format_expression", "check_real_expression", "FUNCTIONS"]

FUNCTIONS = {
    "sin": sp.sin,
    "cos": sp.cos,
    "tan": sp.tan,
    "exp": sp.exp,
    "log": sp.log,
    "sqrt": sp.sqrt,
    "sinh": sp.sinh,
    "cosh": sp.cosh,
    "tanh": sp.tanh,
    "asin": sp.asin,
    "acos": sp.acos,
    "atan": sp.atan,
    "Abs": sp.Abs,
    "abs": sp.Abs,
    "sign": sp.sign,
}
_CONSTANTS = {"pi": sp.pi, "E": sp.E}
_TOKEN = re.compile(
    r"\s*(?:(?P<num>\d+\.?\d*(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?)"
    r"|(?P<name>[A-Za-z_][A-Za-z_0-9]*)|(?P<op>\*\*|[-+*/^(),]))"
)
_MAX_LENGTH = 20_000
_MAX_DEPTH = 100
_MAX_NUMBER_DIGITS = 40
_MAX_POWER_DIGITS = 300  # a numeric power may not exceed 10**300 (no huge exact integers)


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

    Parameters
    ----------
    expr : sympy.Expr

    Returns
    -------
    str

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
            if base.is_number and exponent.is_number:
                self.check_numeric_power(base, exponent)
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
                return FUNCTIONS[token](arg)
            if token in self.symbols:
                return self.symbols[token]
            if token in _CONSTANTS:
                return _CONSTANTS[token]
            raise self.error(f"unknown symbol {token!r}")
        raise self.error(f"unexpected {token!r}")


def parse_expression(text: str, symbols: dict[str, sp.Symbol]) -> sp.Expr:
    """Parse ``text`` into a sympy expression over the given ``symbols`` only.

    Parameters
    ----------
    text : str
        Expression such as ``"x_dot**2*cos(theta)"`` or pysindy's ``"x theta_dot^2"``.
    symbols : dict of str to sympy.Symbol
        The only names allowed besides the whitelisted functions and ``pi``, ``E``.

    Returns
    -------
    sympy.Expr

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
    expr = _Parser(text, symbols).parse()
    check_real_expression(expr, "text")
    return expr


def check_real_expression(expr: sp.Expr, name: str) -> None:
    """Raise ``ValueError`` (naming ``name``) if ``expr`` holds a non-real or infinite number.

    ``x/0`` (``zoo``), ``0/0`` (``nan``), ``sqrt(-1)`` or ``log(0)`` make no sense in a catalog
    term, and NumPy would evaluate them to NaN or silently drop an imaginary part.

    Parameters
    ----------
    expr : sympy.Expr
    name : str
        Argument name used in the error message.

    Examples
    --------
    >>> import sympy as sp
    >>> x = sp.Symbol("x")
    >>> check_real_expression(sp.sqrt(-1) * x, "terms")
    Traceback (most recent call last):
    ...
    ValueError: terms: I*x contains the non-real or infinite number I
    """
    for sub in sp.preorder_traversal(expr):
        if sub.is_number and (sub.is_real is not True or sub.is_finite is False):
            raise ValueError(f"{name}: {expr} contains the non-real or infinite number {sub}")
