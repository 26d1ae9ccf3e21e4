"""Numeric evaluation of many symbolic entries at once, sharing every common product.

Catalog entries are sums of ``coefficient * product of powers of atoms``, where the atoms are
the data variables and a few functions of them (``sin(q)``, ``cos(q)``, ...). Instead of
generating code for whole expressions (``lambdify`` costs more to build than to run on large
catalogs, and the sum of a robot arm's thousands of terms overflows Python's compiler), the
entries are decomposed once into :class:`Terms`: an atom list and, per entry, a list of
``(coefficient, monomial)``. Evaluation computes each distinct atom once, each distinct
monomial once (as a smaller monomial times one atom power, so products are shared across all
entries), and writes each entry straight into its output column; samples are processed in
blocks, so intermediate arrays stay small whatever the number of samples.
:func:`scalar_function` evaluates the same terms at one state with Python floats, from flat
generated code (one short statement per monomial and term), for simulators.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import sympy as sp

__all__ = ["compile_entries", "Terms", "decompose", "compile_terms", "scalar_function"]

_BLOCK = 16_384

Monomial = tuple  # sorted tuple of (atom index, integer power)


@dataclasses.dataclass
class Terms:
    """Entries as polynomials in atoms.

    Attributes
    ----------
    atoms : list of sympy.Expr
        Data variables and functions of them.
    entries : list of list of (float, Monomial)
        Per entry, its terms: a coefficient and a monomial, a sorted tuple of
        ``(atom index, power)`` (the empty tuple for a constant).
    """

    atoms: list
    entries: list


def _decompose(expr: sp.Expr, atoms: dict) -> list[tuple[float, Monomial]]:
    """``expr`` as ``[(coefficient, monomial), ...]``, registering atoms in ``atoms``."""
    terms = []
    for term in sp.Add.make_args(sp.sympify(expr)):
        coef, rest = term.as_coeff_Mul()
        coef = float(coef)
        powers: dict[int, int] = {}
        for factor in sp.Mul.make_args(rest):
            if factor.is_number:
                coef *= float(factor)
                continue
            base, exp = factor.as_base_exp()
            if not (exp.is_Integer and exp > 0):
                base, exp = factor, sp.Integer(1)
            index = atoms.setdefault(base, len(atoms))
            powers[index] = powers.get(index, 0) + int(exp)
        terms.append((coef, tuple(sorted(powers.items()))))
    return terms


def decompose(exprs) -> Terms:
    """The :class:`Terms` of sympy expressions (sums are not expanded: a factor that is a sum
    is an atom of its own)."""
    atoms: dict[sp.Expr, int] = {}
    entries = [_decompose(e, atoms) for e in exprs]
    return Terms(sorted(atoms, key=atoms.get), entries)


def compile_entries(variables, exprs):
    """Compile sympy expressions into one vectorized evaluator over the data columns.

    Parameters
    ----------
    variables : sequence of sympy.Symbol
        Symbols, in the order of the columns of the data array.
    exprs : sequence of sympy.Expr
        Entries to evaluate.

    Returns
    -------
    callable
        ``f(Z, targets=None)`` for a data array ``Z`` of shape ``(N, len(variables))``. Without
        ``targets`` it returns a list of ``len(exprs)`` arrays of shape ``(N,)``; with
        ``targets`` (one writable array of shape ``(N,)`` per entry, or ``None`` to skip an
        entry) it writes the entries there and returns ``None``.

    Examples
    --------
    >>> import numpy as np, sympy as sp
    >>> a, b = sp.symbols("a b")
    >>> f = compile_entries([a, b], [a * b + sp.sin(a) ** 2, sp.Integer(2)])
    >>> [v.round(4) for v in f(np.array([[1.0, 3.0]]))]
    [array([3.7081]), array([2.])]
    """
    return compile_terms(variables, decompose(exprs))


def compile_terms(variables, terms: Terms):
    """The vectorized evaluator of :class:`Terms` (see :func:`compile_entries`)."""
    variables = tuple(variables)
    position = {v: k for k, v in enumerate(variables)}
    atom_list, entries = terms.atoms, terms.entries
    unknown = set().union(*(a.free_symbols for a in atom_list)) - set(variables)
    if unknown:
        raise ValueError(f"exprs: unknown symbols {sorted(map(str, unknown))}")
    atom_functions = [
        position[a] if a in position else sp.lambdify(variables, a, modules="numpy")
        for a in atom_list
    ]

    def evaluate_block(columns, n_rows, write):
        atom_values = [
            columns[f] if isinstance(f, int) else np.broadcast_to(f(*columns), (n_rows,))
            for f in atom_functions
        ]
        memo: dict[Monomial, np.ndarray] = {}

        def monomial(key: Monomial) -> np.ndarray:
            value = memo.get(key)
            if value is None:
                if len(key) == 1:
                    # by squaring: log2(power) products deep, whatever the power
                    index, power = key[0]
                    if power == 1:
                        value = atom_values[index]
                    else:
                        half = monomial(((index, power // 2),))
                        value = half * half
                        if power % 2:
                            value = value * atom_values[index]
                else:
                    value = monomial(key[:-1]) * monomial(key[-1:])
                memo[key] = value
            return value

        for k, terms in enumerate(entries):
            write(k, terms, monomial)

    def evaluate(z: np.ndarray, targets=None):
        z = np.asarray(z, dtype=float)
        n_samples = z.shape[0]
        outputs = targets
        if outputs is None:
            outputs = [np.empty(n_samples) for _ in entries]

        for start in range(0, max(n_samples, 1), _BLOCK):
            stop = min(start + _BLOCK, n_samples)
            columns = z[start:stop].T

            def write(k, terms, monomial, start=start, stop=stop):
                target = outputs[k]
                if target is None:
                    return
                out = target[start:stop]
                first = True
                for coef, key in terms:
                    if not key:
                        if first:
                            out[...] = coef
                        else:
                            out += coef
                    elif first:
                        np.multiply(monomial(key), coef, out=out)
                    else:
                        out += coef * monomial(key)
                    first = False
                if first:
                    out[...] = 0.0

            evaluate_block(columns, stop - start, write)
        return None if targets is not None else outputs

    return evaluate


def scalar_function(variables, terms: Terms, modules=("math",)):
    """The entries of ``terms`` at one state, as Python floats, from flat generated code.

    Parameters
    ----------
    variables : sequence of sympy.Symbol
        The function's arguments, in order.
    terms : Terms
    modules : sequence
        Namespaces of the atoms' functions (as for ``sympy.lambdify``).

    Returns
    -------
    callable
        ``f(*values) -> list of float``, one value per entry.

    Examples
    --------
    >>> a, b = sp.symbols("a b")
    >>> f = scalar_function([a, b], decompose([a * b + 3 * sp.sin(a) ** 2, sp.Integer(2)]))
    >>> [round(v, 4) for v in f(1.0, 3.0)]
    [5.1242, 2.0]
    """
    variables = tuple(variables)
    names = [f"v{k}" for k in range(len(variables))]
    position = {v: k for k, v in enumerate(variables)}
    namespace, lines = {}, []
    atom_names = []
    for index, atom in enumerate(terms.atoms):
        if atom in position:
            atom_names.append(names[position[atom]])
            continue
        namespace[f"_atom{index}"] = sp.lambdify(variables, atom, modules=list(modules))
        lines.append(f"a{index} = _atom{index}({', '.join(names)})")
        atom_names.append(f"a{index}")
    monomials: dict[Monomial, str] = {}

    def monomial(key: Monomial) -> str:
        name = monomials.get(key)
        if name is None:  # a smaller monomial times one atom power: products shared
            index, power = key[-1]
            factor = atom_names[index] if power == 1 else f"{atom_names[index]}**{power}"
            value = f"{monomial(key[:-1])} * {factor}" if len(key) > 1 else factor
            name = monomials[key] = f"m{len(monomials)}"
            lines.append(f"{name} = {value}")
        return name

    for k, entry in enumerate(terms.entries):
        lines.append(f"e{k} = 0.0")
        for coef, key in entry:  # one statement a term: no deep expression to compile
            value = repr(float(coef))
            lines.append(f"e{k} += {value} * {monomial(key)}" if key else f"e{k} += {value}")
    lines.append(f"return [{', '.join(f'e{k}' for k in range(len(terms.entries)))}]")
    source = f"def _entries({', '.join(names)}):\n" + "\n".join("    " + line for line in lines)
    exec(compile(source, "<pysindy_xl.scalar_function>", "exec"), namespace)  # noqa: S102
    return namespace["_entries"]
