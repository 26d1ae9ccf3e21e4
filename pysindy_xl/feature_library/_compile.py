"""Numeric evaluation of many symbolic entries at once, sharing every common product.

Catalog entries are sums of ``coefficient * product of powers of atoms``, where the atoms are
the data variables and a few functions of them (``sin(q)``, ``cos(q)``, ...). Instead of
generating code for whole expressions (``lambdify`` costs more to build than to run on large
catalogs, and the sum of a robot arm's thousands of terms overflows Python's compiler), the
entries are decomposed once into :class:`Terms`: an atom list and, per entry, a list of
``(coefficient, monomial)``. Evaluation computes each distinct atom once, then every distinct
monomial degree by degree (a monomial is a monomial one degree lower times one atom: one gather
and one product per degree, shared across all entries), and the entries as one sparse product
of the coefficient matrix with the monomial values; samples are processed in blocks, so
intermediate arrays stay small whatever the number of samples; the blocks are shared among
:data:`THREADS` threads (the sparse products and array operations release the GIL; each
block's arithmetic is the same in any thread).
:func:`scalar_function` evaluates the same terms at one state with Python floats, from flat
generated code (one short statement per monomial and term), for simulators.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import scipy.sparse
import sympy as sp

from ._monomials import _unique_rows

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


def _monomial_schedule(wanted) -> tuple[list, np.ndarray, np.ndarray, dict]:
    """The monomials ``wanted`` and the sub-monomials that build them, ordered by degree.

    Each monomial of degree ``d > 1`` is its *parent* (one power less of its last atom, degree
    ``d - 1``) times one atom, so a whole degree is one gather and one product.

    Parameters
    ----------
    wanted : set of Monomial

    Returns
    -------
    monomials : list of Monomial
        Ordered by degree, and by atom within a degree (a run of one atom is one product);
        the constant monomial (if any) first.
    parents, atoms : ndarray of int, shape (len(monomials),)
        Position of the parent in ``monomials`` (-1 for the constant and the atoms themselves)
        and the atom multiplied in (-1 for the constant).
    position : dict
        Monomial -> its position in ``monomials``.
    """
    closure = set()
    for key in wanted:
        while key and key not in closure:
            closure.add(key)
            index, power = key[-1]
            key = key[:-1] + (((index, power - 1),) if power > 1 else ())
    if () in wanted:
        closure.add(())
    monomials = sorted(closure, key=lambda key: (sum(p for _, p in key),
                                                 key[-1][0] if key else -1))
    position = {key: k for k, key in enumerate(monomials)}
    parents = np.full(len(monomials), -1)
    atoms = np.full(len(monomials), -1)
    for k, key in enumerate(monomials):
        if not key:
            continue
        index, power = key[-1]
        parent = key[:-1] + (((index, power - 1),) if power > 1 else ())
        atoms[k] = index
        parents[k] = position[parent] if parent else -1
    return monomials, parents, atoms, position


class _MonomialValues:
    """Evaluates a set of monomials degree by degree, each as its parent times one atom."""

    def __init__(self, wanted):
        monomials, parents, atoms, self.position = _monomial_schedule(wanted)
        self.size = len(monomials)
        degrees = np.array([sum(p for _, p in key) for key in monomials], dtype=int)
        self.constant = bool(degrees.size and degrees[0] == 0)
        first = slice(int(np.searchsorted(degrees, 1)), int(np.searchsorted(degrees, 1, "right")))
        self.first = (first, atoms[first])
        # per degree: the gather of the parents, then one in-place product per run of
        # monomials that share their last atom (no gathered copy of the atom rows)
        self.levels = []
        for d in range(2, int(degrees.max(initial=1)) + 1):
            start, stop = (int(np.searchsorted(degrees, d)),
                           int(np.searchsorted(degrees, d, "right")))
            cuts = np.flatnonzero(np.diff(atoms[start:stop])) + 1
            bounds = np.concatenate([[0], cuts, [stop - start]]) + start
            runs = [(int(a), int(b), int(atoms[a])) for a, b in zip(bounds[:-1], bounds[1:],
                                                                     strict=True)]
            self.levels.append((start, stop, parents[start:stop], runs))

    def __call__(self, atom_rows: np.ndarray) -> np.ndarray:
        values = np.empty((self.size, atom_rows.shape[1]))
        if self.constant:
            values[0] = 1.0
        first, atoms = self.first
        values[first] = atom_rows[atoms]
        for start, stop, parents, runs in self.levels:
            np.take(values, parents, axis=0, out=values[start:stop])
            for a, b, atom in runs:
                values[a:b] *= atom_rows[atom]
        return values


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


def _best_plan(terms: Terms, inner, peel) -> _Plan:
    """The cheaper of the flat plan of ``terms`` and the plan that factors the atoms
    ``peel[0]`` out of the ``inner`` ones (and so on, recursively, with ``peel[1:]``).

    The coefficient functions of an arm's catalog are polynomials in the sines and cosines of
    all its joints; written as polynomials in the last joint's whose coefficients are
    polynomials in the others (each distinct one once), and so on down the chain, they take
    fewer operations than as sums of products of all the joints' atoms."""
    powers = terms.arrays()[0]
    present = inner & powers.any(axis=0)
    peel = [group for group in peel if (present & group).any() and (present & ~group).any()]
    if not peel:
        return _Plan(terms, np.zeros(len(inner), dtype=bool))
    factored = _Plan(terms, inner & ~peel[0], peel[1:])
    # the flat plan's cost when it shares no polynomial (the entries of a factored plan's
    # polynomials are distinct): a product per monomial, one per term
    if factored.cost < len(powers) or factored.cost < len(powers) + len(
            _unique_rows(powers)[0]):
        return factored
    flat = _Plan(terms, np.zeros(len(inner), dtype=bool))
    return factored if factored.cost < flat.cost else flat


def _keys(powers) -> tuple[list, np.ndarray]:
    """The distinct rows of ``powers`` as monomials (sorted tuples of ``(atom, power)``), and
    each row's position among them."""
    first, inverse = _unique_rows(powers)
    return _monomials(powers[first]), inverse


def _monomials(powers) -> list:
    """The rows of ``powers`` as monomials (sorted tuples of ``(atom, power)``)."""
    rows, atoms = np.nonzero(powers)
    pairs = list(zip(atoms.tolist(), powers[rows, atoms].tolist(), strict=True))
    bounds = np.searchsorted(rows, np.arange(len(powers) + 1)).tolist()
    return [tuple(pairs[bounds[m]:bounds[m + 1]]) for m in range(len(powers))]


def _distinct_runs(bounds, *columns) -> np.ndarray:
    """For each run ``bounds[m]:bounds[m + 1]`` of the rows of ``columns`` (integer arrays),
    the number of the first run equal to it, counted in order of first appearance.

    Runs are grouped by a hash of their rows, and each group is checked row by row against
    its first run (a collision, never seen, falls back to comparing the runs one by one)."""
    sizes = np.diff(bounds)
    offsets = np.arange(int(bounds[-1])) - np.repeat(bounds[:-1], sizes)
    mixed = offsets.astype(np.uint64) * np.uint64(0x9E3779B97F4A7C15)
    for k, column in enumerate(columns):
        mixed ^= column.astype(np.int64).view(np.uint64) * np.uint64(0xBF58476D1CE4E5B9 + 2 * k)
        mixed ^= mixed >> np.uint64(31)
        mixed *= np.uint64(0x94D049BB133111EB)
    hashes = np.zeros(len(sizes), dtype=np.uint64)
    starts = bounds[:-1][sizes > 0]
    if starts.size:
        hashes[sizes > 0] = np.add.reduceat(mixed, starts)
    keys = np.rec.fromarrays([sizes, hashes])
    _, first, group = np.unique(keys, return_index=True, return_inverse=True)
    group = group.ravel()
    representative = first[group]
    rows = np.repeat(bounds[representative] - bounds[:-1], sizes) + np.arange(int(bounds[-1]))
    if not all(np.array_equal(column, column[rows]) for column in columns):
        found: dict = {}
        return np.array([found.setdefault(tuple(column[a:b].tobytes() for column in columns),
                                          len(found))
                         for a, b in zip(bounds[:-1], bounds[1:], strict=True)], dtype=np.intp)
    rank = np.empty(len(first), dtype=np.intp)
    rank[np.argsort(first)] = np.arange(len(first))
    return rank[group]


class _Plan:
    """How to evaluate entries: ``entry = sum over outer monomials u of u times a
    polynomial in the inner atoms``, each distinct polynomial (up to a factor) once.

    The terms of each entry are grouped by their outer monomial into *pairs* ``(u, entry)``,
    ordered by ``u`` (fewer atoms first, then as tuples) and entry; the polynomial of a pair
    is its terms' inner monomials, sorted as tuples, and its coefficients divided by the
    first one (the polynomials equal up to a factor are one: a symmetric mass matrix gives
    the same coefficient function to ``dL/dqd_i`` through ``qd_j`` and to ``dL/dqd_j``
    through ``qd_i``). Without outer atoms (``inner`` all true or all false) every entry is
    one polynomial of all the atoms, evaluated as such."""

    def __init__(self, terms: Terms, inner, peel=()):
        powers, coefficients, owners, self.n_entries = terms.arrays()
        factor = bool(inner.any() and not inner.all())
        entries = max(self.n_entries, 1)
        # pairs (outer monomial, entry), in order, and each term's pair
        if factor:
            outer_powers = powers[:, ~inner]
            outer_first, outer_of = _unique_rows(outer_powers)
            outer_rank = np.empty(len(outer_first), dtype=np.intp)  # by degree (1 first)
            outer_rank[np.argsort(outer_powers[outer_first].sum(axis=1), kind="stable")] = \
                np.arange(len(outer_first))
            pair_codes, pair_of = np.unique(outer_rank[outer_of] * entries + owners,
                                            return_inverse=True)
            pair_outer = np.argsort(outer_rank)[pair_codes // entries]
            pair_entry = pair_codes % entries
            distinct_outer = np.zeros((len(outer_first), len(inner)), dtype=np.int16)
            distinct_outer[:, ~inner] = outer_powers[outer_first]
            outer_keys = _monomials(distinct_outer)
        else:  # one pair per entry, even without terms
            pair_of, pair_entry = owners, np.arange(self.n_entries)
            pair_outer, outer_keys = np.zeros(self.n_entries, dtype=np.intp), [()]
        pair_of = pair_of.ravel()
        n_pairs = len(pair_entry)
        # each pair's terms sorted by inner monomial (stable), divided by the first one
        # (the inner atoms only: the factored polynomials are evaluated on their rows)
        self.inner = np.flatnonzero(inner) if factor else None
        inner_powers = powers[:, self.inner] if factor else powers
        inner_first, inner_of = _unique_rows(inner_powers)
        order = np.argsort(pair_of.astype(np.int64) * max(len(inner_first), 1) + inner_of,
                           kind="stable")
        pair_sorted, inner_sorted = pair_of[order], inner_of[order]
        bounds = np.searchsorted(pair_sorted, np.arange(n_pairs + 1))
        first = np.ones(n_pairs)
        leading = coefficients[order[bounds[:-1][bounds[:-1] < bounds[1:]]]]
        first[bounds[:-1] < bounds[1:]] = np.where(leading != 0, leading, 1.0)
        normal = coefficients[order] / first[pair_sorted]
        # the distinct polynomials, in order of first appearance (coefficients compared to
        # 40 bits: normalized twice, a factor's polynomial within a polynomial, they differ
        # in their last bits)
        rounded = ((normal + 0.0).view(np.int64) + (1 << 11)) & ~np.int64((1 << 12) - 1)
        index = _distinct_runs(bounds, rounded, inner_sorted)
        self.index = index
        distinct = np.flatnonzero(np.r_[True, np.diff(
            np.maximum.accumulate(index)) > 0]) if n_pairs else np.zeros(0, np.intp)
        # the terms of the distinct polynomials, in order
        sizes = bounds[1:] - bounds[:-1]
        rows = np.repeat(bounds[distinct] - np.cumsum(sizes[distinct]) + sizes[distinct],
                         sizes[distinct]) + np.arange(int(sizes[distinct].sum()))
        polynomial_of = np.repeat(np.arange(len(distinct)), sizes[distinct])
        wanted_ids = inner_sorted[rows]
        if factor:  # the distinct polynomials of the inner atoms: terms of their own
            self.polynomials = _best_plan(Terms.from_arrays(
                [terms.atoms[k] for k in self.inner], inner_powers[order[rows]], normal[rows],
                polynomial_of, len(distinct)), np.ones(len(self.inner), dtype=bool),
                [group[self.inner] for group in peel])
        else:
            used, position = np.unique(wanted_ids, return_inverse=True)
            keys = _monomials(inner_powers[inner_first[used]])
            self.polynomials = _MonomialValues(keys)
            columns = np.array([self.polynomials.position[key] for key in keys], dtype=np.intp)
            self.coefficients = scipy.sparse.csr_matrix(
                (normal[rows], (polynomial_of, columns[position.ravel()])),
                shape=(len(distinct), self.polynomials.size))
        self.outer = _MonomialValues([key for key in outer_keys if key])
        cuts = np.flatnonzero(np.diff(pair_outer)) + 1
        bounds = np.concatenate([[0], cuts, [n_pairs]]).tolist()
        self.runs = [(a, b, self.outer.position[outer_keys[pair_outer[a]]])
                     for a, b in zip(bounds[:-1], bounds[1:], strict=True)
                     if outer_keys[pair_outer[a]]]
        self.sum = scipy.sparse.csr_matrix(
            (first, (pair_entry, np.arange(n_pairs))), shape=(self.n_entries, n_pairs))
        # the polynomials are the entries themselves: no gather, scaling nor sum
        self.direct = (not self.runs and len(distinct) == n_pairs
                       and np.array_equal(index, np.arange(n_pairs))
                       and np.all(first == 1.0)
                       and np.array_equal(pair_entry, np.arange(self.n_entries)))
        # rows built at once, and operations per sample (a product and a sum per term and
        # per pair, a product per monomial)
        inner_size, inner_cost = ((self.polynomials.size, self.polynomials.cost) if factor else
                                  (self.polynomials.size + len(distinct),
                                   self.coefficients.nnz + self.polynomials.size))
        self.size = inner_size + (0 if self.direct else self.outer.size + 2 * n_pairs)
        self.cost = inner_cost + (0 if self.direct else self.outer.size + 2 * n_pairs)

    def __call__(self, atom_rows: np.ndarray) -> np.ndarray:
        if self.inner is not None:
            polynomials = self.polynomials(atom_rows[self.inner])
        else:
            polynomials = np.asarray(self.coefficients @ self.polynomials(atom_rows))
        if self.direct:
            return polynomials
        pairs = polynomials[self.index]
        if self.runs:
            outer = self.outer(atom_rows)
            for a, b, u in self.runs:
                pairs[a:b] *= outer[u]
        return np.asarray(self.sum @ pairs)


def compile_terms(variables, terms: Terms):
    """The vectorized evaluator of :class:`Terms` (see :func:`compile_entries`).

    With ``V`` the values of every monomial (one row per monomial, built degree by degree as
    parent times atom) and ``C`` the sparse matrix of term coefficients (entries x
    monomials), the entries are ``C @ V``: a handful of array operations per block of samples,
    whatever the number of terms.

    Entries of mechanical catalogs are polynomials in a few velocities (or forces) whose
    coefficients are long trigonometric polynomials of the angles. When it saves work, the
    monomials are factored as ``u * v`` with ``v`` a product of atoms of the angles only:
    ``entry = sum_u u * (C_u @ V)``, so that only the monomials ``v`` of the angles (and the
    few ``u``) are built, not each of their products.
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
    plan = _best_plan(terms, np.ones(len(atom_list), dtype=bool), [~angles, *groups])
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
