"""A restricted expression grammar: parse catalog terms without ``eval`` or ``sympify``.

Saved models and pysindy feature names are turned back into sympy expressions by this parser,
which only knows numbers, the symbols it is given, a whitelist of functions and the operators
``+ - * / ** ^`` (and implicit multiplication by juxtaposition, as in pysindy's ``"x y^2"``).
Nothing in a file can make it execute code.
"""

from __future__ import annotations

import re

import sympy as sp

__all__ = ["parse_expression", "FUNCTIONS"]

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


class _Parser:
    def __init__(self, text: str, symbols: dict[str, sp.Symbol]):
        self.text = text
        self.tokens = _tokenize(text)
        self.pos = 0
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

    def starts_atom(self):
        kind, token = self.peek()
        return kind in ("num", "name") or token == "("

    def product(self):
        expr = self.unary()
        while True:
            kind, token = self.peek()
            if token in ("*", "/"):
                self.take()
                rhs = self.unary()
                expr = expr * rhs if token == "*" else expr / rhs
            elif self.starts_atom():
                expr = expr * self.unary()
            else:
                return expr

    def unary(self):
        if self.peek()[1] in ("-", "+"):
            _, op = self.take()
            operand = self.unary()
            return -operand if op == "-" else operand
        return self.power()

    def power(self):
        base = self.atom()
        if self.peek()[1] in ("**", "^"):
            self.take()
            return base ** self.unary()
        return base

    def atom(self):
        kind, token = self.take()
        if kind == "num":
            if re.fullmatch(r"\d+", token):
                return sp.Integer(token)
            return sp.Float(token)
        if token == "(":
            expr = self.sum()
            self.take(")")
            return expr
        if kind == "name":
            if self.peek()[1] == "(":
                if token not in FUNCTIONS:
                    raise self.error(f"unknown function {token!r}")
                self.take("(")
                arg = self.sum()
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
    return _Parser(text, symbols).parse()
