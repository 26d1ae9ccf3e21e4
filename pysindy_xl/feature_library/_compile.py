"""Numeric evaluation of many symbolic entries at once, sharing every common product.

Entries are decomposed once into :class:`Terms` (atoms: data variables and functions of them
such as ``sin(q)``; per entry, ``(coefficient, monomial)`` pairs), then evaluated by a plan
(:mod:`._plans`): each distinct monomial built degree by degree, the entries as sparse
products, nested angle by angle for a robot arm's polynomials. ``lambdify`` of a whole arm's
catalog costs more to build than to run, and its sum overflows Python's compiler. Samples are
processed in blocks shared among :data:`THREADS` threads (the sparse products release the
GIL). :func:`scalar_function` evaluates the same terms at one state, for simulators.
"""

from __future__ import annotations

import functools
import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import sympy as sp

from ._monomials import unique_rows
from ._plans import monomial_tuples, stored_plan

__all__ = ["compile_entries", "Terms", "decompose", "compile_terms", "scalar_function"]

_BLOCK = 16_384
_BLOCK_VALUES = 1 << 21  # values built at once (16 MiB of floats: blocks stay in the cache)

Monomial = tuple  # sorted tuple of (atom index, integer power)

#: Threads that evaluate blocks of samples side by side (at most the CPUs).
THREADS = max(1, min(os.cpu_count() or 1, 4))
_POOL: list = []  # the executor, made on first use (and dropped in a forked child)
os.register_at_fork(after_in_child=_POOL.clear)


def _blocks_map(function, starts) -> None:
    """``function(start)`` for every block start, in threads when there are several blocks,
    under the caller's floating-point error handling."""
    if THREADS == 1 or len(starts) < 2:
        for start in starts:
            function(start)
        return
    if not _POOL:
        _POOL.append(ThreadPoolExecutor(THREADS, thread_name_prefix="pysindy_xl"))
    errors = np.geterr()  # thread-local: the workers take the caller's

    def run(start):
        with np.errstate(**errors):
            function(start)

    for _ in _POOL[0].map(run, starts):
        pass


class Terms:
    """Entries as polynomials in atoms.

    Held as lists of ``(coefficient, monomial)`` or as arrays (one row per term, see
    :meth:`from_arrays`), each form built from the other on first use: catalogs derived as
    arrays (trigonometric polynomials) are merged, reordered and compiled without building a
    Python tuple per term.

    Attributes
    ----------
    atoms : list of sympy.Expr
        Data variables and functions of them.
    entries : list of list of (float, Monomial)
        Per entry, its terms: a coefficient and a monomial, a sorted tuple of
        ``(atom index, power)`` (the empty tuple for a constant).
    """

    def __init__(self, atoms, entries):
        self.atoms = list(atoms)
        self._entries = entries
        self._arrays = None
        # what derives from these terms, computed once (evaluators compiled for some
        # variables, reorderings): closures and caches, never pickled
        self._memo: dict = {}

    @classmethod
    def from_arrays(cls, atoms, powers, coefficients, owners, n_entries) -> Terms:
        """Terms given as one row per term, the rows of an entry together and in entry order.

        Parameters
        ----------
        atoms : list of sympy.Expr
        powers : ndarray of int, shape (T, len(atoms))
            Each term's power of each atom.
        coefficients : ndarray of float, shape (T,)
        owners : ndarray of int, shape (T,)
            Each term's entry, non-decreasing.
        n_entries : int
        """
        terms = cls(atoms, None)
        terms._arrays = (np.asarray(powers, dtype=np.int16).reshape(-1, len(terms.atoms)),
                         np.asarray(coefficients, dtype=float).reshape(-1),
                         np.asarray(owners, dtype=np.intp).reshape(-1), int(n_entries))
        return terms

    @property
    def entries(self) -> list:
        if self._entries is None:
            self._entries = _entries_of(*self._arrays)
        return self._entries

    def arrays(self) -> tuple:
        """``(powers, coefficients, owners, n_entries)`` (see :meth:`from_arrays`)."""
        if self._arrays is None:
            self._arrays = _arrays_of(self.entries, len(self.atoms))
        return self._arrays

    def take(self, order) -> Terms:
        """The terms of the entries ``order`` (indices), in that order."""
        order = np.asarray(order, dtype=np.intp).reshape(-1)
        if self._entries is not None:
            return Terms(self.atoms, [self._entries[k] for k in order.tolist()])
        powers, coefficients, owners, n_entries = self._arrays
        starts = np.searchsorted(owners, np.arange(n_entries + 1))
        sizes = (starts[1:] - starts[:-1])[order]
        rows = np.repeat(starts[order] - np.cumsum(sizes) + sizes, sizes) + np.arange(
            int(sizes.sum()))
        return Terms.from_arrays(self.atoms, powers[rows], coefficients[rows],
                                 np.repeat(np.arange(len(order)), sizes), len(order))

    def __len__(self):
        return len(self._entries) if self._entries is not None else self._arrays[3]

    def __eq__(self, other):
        if not isinstance(other, Terms):
            return NotImplemented
        return self.atoms == other.atoms and self.entries == other.entries

    __hash__ = None

    def __repr__(self):
        return f"Terms(atoms={self.atoms!r}, entries={self.entries!r})"

    def __getstate__(self):
        return {"atoms": self.atoms, "_entries": self._entries, "_arrays": self._arrays,
                "_memo": {}}

    def __setstate__(self, state):  # states of either form, or of the tuple form only
        self.__dict__.update({"_entries": None, "_arrays": None, "_memo": {}, **state})


def _entries_of(powers, coefficients, owners, n_entries) -> list:
    """The lists of ``(coefficient, monomial)`` of terms held as arrays."""
    keys, which = _keys(powers)
    terms = list(zip(coefficients.tolist(), [keys[m] for m in which.tolist()], strict=True))
    cuts = np.searchsorted(owners, np.arange(n_entries + 1)).tolist()
    return [terms[cuts[k]:cuts[k + 1]] for k in range(n_entries)]


def _arrays_of(entries, n_atoms) -> tuple:
    """The arrays (see :meth:`Terms.from_arrays`) of lists of ``(coefficient, monomial)``."""
    sizes = [len(entry) for entry in entries]
    coefficients = np.array([coef for entry in entries for coef, _ in entry], dtype=float)
    powers = np.zeros((len(coefficients), n_atoms), dtype=np.int16)
    pairs = [(r, a, p) for r, (_, key) in enumerate(term for entry in entries for term in entry)
             for a, p in key]
    if pairs:
        rows, atoms, values = np.array(pairs, dtype=np.intp).T
        np.add.at(powers, (rows, atoms), values)
    return powers, coefficients, np.repeat(np.arange(len(entries)), sizes), len(entries)


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
        ``f(Z, targets=None, stacked=False)`` for a data array ``Z`` of shape
        ``(N, len(variables))``. Without ``targets`` it returns a list of ``len(exprs)``
        arrays of shape ``(N,)`` (with ``stacked``, one array of shape ``(len(exprs), N)``);
        with ``targets`` (one writable array of shape ``(N,)`` per entry, or ``None`` to skip
        an entry) it writes the entries there and returns ``None``.

    Examples
    --------
    >>> import numpy as np, sympy as sp
    >>> a, b = sp.symbols("a b")
    >>> f = compile_entries([a, b], [a * b + sp.sin(a) ** 2, sp.Integer(2)])
    >>> [v.round(4) for v in f(np.array([[1.0, 3.0]]))]
    [array([3.7081]), array([2.])]
    """
    return compile_terms(variables, decompose(exprs))


def _angle_groups(atom_list, variables) -> list:
    """Masks of the atoms that are functions of the angles only (the variables found inside
    a sine or a cosine: the atoms of a mechanical catalog's coefficient functions), one mask
    per set of angles, the sets of later variables first (the distal joints of a chain)."""
    angles = set()
    for atom in atom_list:
        for trig in atom.atoms(sp.sin, sp.cos):
            angles |= trig.free_symbols
    position = {v: k for k, v in enumerate(variables)}
    owners = [frozenset(a.free_symbols) if a.free_symbols and a.free_symbols <= angles
              else None for a in atom_list]
    groups = sorted({owner for owner in owners if owner is not None},
                    key=lambda owner: sorted((position[v] for v in owner), reverse=True),
                    reverse=True)
    return [np.array([owner == group for owner in owners], dtype=bool) for group in groups]


def _keys(powers) -> tuple[list, np.ndarray]:
    """The distinct rows of ``powers`` as monomials (sorted tuples of ``(atom, power)``), and
    each row's position among them."""
    first, inverse = unique_rows(powers)
    return monomial_tuples(powers[first]), inverse


def compile_terms(variables, terms: Terms):
    """The vectorized evaluator of :class:`Terms` (see :func:`compile_entries`).

    With ``V`` the values of every monomial and ``C`` the sparse matrix of term coefficients
    (entries x monomials), the entries are ``C @ V``. Entries of mechanical catalogs are
    polynomials in a few velocities (or forces) whose coefficients are long trigonometric
    polynomials of the angles: when it saves operations (:func:`._plans.best_plan`) they
    are evaluated as ``sum_u u * p_u``, each distinct polynomial ``p_u`` of the angles once,
    and the same factoring is applied to those polynomials one angle after the other (the
    distal joint first). The plans of large catalogs are kept on disk
    (:func:`._plans.stored_plan`).

    >>> import numpy as np, sympy as sp
    >>> a, b, v = sp.symbols("a b v")
    >>> expr = sp.expand(v * (1 + sp.sin(a) + sp.cos(a) * sp.sin(b)) ** 2)
    >>> f = compile_terms([a, b, v], decompose([expr]))
    >>> z = np.array([[0.3, -1.2, 2.0]])
    >>> bool(np.isclose(f(z)[0][0], sp.lambdify([a, b, v], expr)(*z[0])))
    True
    """
    variables = tuple(variables)
    key = ("compiled", variables)
    evaluate = terms._memo.get(key)
    if evaluate is None:  # shared by every library that holds the same terms
        evaluate = terms._memo[key] = _compile_terms(variables, terms)
    return evaluate


def _compile_terms(variables: tuple, terms: Terms):
    position = {v: k for k, v in enumerate(variables)}
    atom_list = terms.atoms
    unknown = set().union(*(a.free_symbols for a in atom_list)) - set(variables)
    if unknown:
        raise ValueError(f"exprs: unknown symbols {sorted(map(str, unknown))}")
    atom_functions = [_atom_function(a, position, variables) for a in atom_list]
    groups = _angle_groups(atom_list, variables)
    angles = np.any(groups, axis=0) if groups else np.zeros(len(atom_list), dtype=bool)
    plan = stored_plan(terms.arrays(), np.ones(len(atom_list), dtype=bool),
                       [~angles, *groups])
    n_entries = len(terms)
    # blocks of samples keep the values built at once (values x block) near _BLOCK_VALUES
    block = int(np.clip(_BLOCK_VALUES // max(plan.size, 1), 64, _BLOCK))

    def atom_values(columns, n_rows):
        rows = np.empty((len(atom_functions), n_rows))
        for k, f in enumerate(atom_functions):
            rows[k] = columns[f] if isinstance(f, int) else f(*columns)
        return rows

    def evaluate(z: np.ndarray, targets=None, stacked=False):
        z = np.asarray(z, dtype=float)
        n_samples = z.shape[0]
        atom_rows = atom_values(z.T, n_samples)
        outputs = np.empty((n_entries, n_samples)) if targets is None else None

        def evaluate_block(start):  # blocks write to their own samples only
            stop = min(start + block, n_samples)
            values = plan(atom_rows[:, start:stop])
            if outputs is not None:
                outputs[:, start:stop] = values
                return
            for k, target in enumerate(targets):
                if target is not None:
                    target[start:stop] = values[k]

        _blocks_map(evaluate_block, range(0, n_samples, block))
        if targets is not None:
            return None
        return outputs if stacked else list(outputs)

    return evaluate


_UNARY = {sp.sin: np.sin, sp.cos: np.cos}  # what lambdify makes of them, without lambdify


def _atom_function(atom, position, variables):
    """A data column's index, or the function of the columns that evaluates ``atom``."""
    if atom in position:
        return position[atom]
    function = _UNARY.get(type(atom))
    if function is not None and atom.args[0] in position:  # sin(q), cos(q): most atoms
        index = position[atom.args[0]]
        return lambda *columns: function(columns[index])
    return _lambdified(atom, variables)


@functools.lru_cache(maxsize=1024)
def _lambdified(atom, variables: tuple):
    """``lambdify`` of an atom: the same atoms recur in a catalog's columns, weak entries and
    dynamics, and printing them is most of a compile read from disk."""
    return sp.lambdify(variables, atom, modules="numpy")


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
