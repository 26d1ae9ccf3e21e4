"""Evaluation plans of polynomial entries: few array operations per block of samples.

Entries are sums of ``coefficient * monomial`` in atoms (the rows of an atom array: one row
per atom, one column per sample), given as the arrays of
:meth:`~pysindy_xl.feature_library._compile.Terms.arrays`. A flat :class:`Plan` builds every
distinct monomial degree by degree (each one its parent times one atom) and the entries as one
sparse product of the coefficients with the monomials. A factored plan writes each entry as a
sum over *outer* monomials ``u`` of ``u`` times a polynomial of the *inner* atoms, each
distinct polynomial (up to a factor) evaluated once, by a plan of its own: :func:`best_plan`
factors the velocities out of a mechanical catalog's entries, then the atoms of one angle after
the other, for as long as that saves operations.
"""

from __future__ import annotations

import functools
import hashlib
import os

import numpy as np
import scipy
import scipy.sparse

from .. import _disk_cache
from ._monomials import unique_rows

__all__ = ["Plan", "best_plan", "MonomialValues", "plan_arrays", "plan_of", "stored_plan"]

Monomial = tuple  # sorted tuple of (atom index, integer power)


def _monomial_schedule(wanted) -> tuple[list, np.ndarray, np.ndarray, dict]:
    """The monomials ``wanted`` (set of Monomial) and the sub-monomials that build them, as
    ``(monomials, parents, atoms, position)``: ordered by degree and by last atom within a
    degree (a run of one atom is one product), the constant first; each one's parent (one
    power less of its last atom; -1 for atoms and the constant) and the atom multiplied in
    (-1 for the constant); and each monomial's position.
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


class MonomialValues:
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


def best_plan(arrays, inner, peel) -> Plan:
    """The cheaper of the flat plan of the terms ``arrays`` (``(powers, coefficients,
    owners, n_entries)``, :meth:`~pysindy_xl.feature_library._compile.Terms.arrays`) and the
    plan that factors the atoms ``peel[0]`` out of the ``inner`` ones (and so on, recursively,
    with ``peel[1:]``): an arm's coefficient functions, written as polynomials in the last
    joint's sines and cosines of polynomials in the others, each distinct one once, take
    fewer operations than as sums of products of all the joints' atoms.

    ``v s + 2 v`` in the atoms ``(v, s)``, ``v`` factored out: ``v (s + 2)``.

    >>> arrays = (np.array([[1, 1], [1, 0]], dtype=np.int16), np.array([1.0, 2.0]),
    ...           np.array([0, 0]), 1)
    >>> plan = best_plan(arrays, np.array([True, True]), [np.array([True, False])])
    >>> plan(np.array([[3.0], [0.5]])).ravel().tolist()
    [7.5]
    """
    powers = arrays[0]
    present = inner & powers.any(axis=0)
    peel = [group for group in peel if (present & group).any() and (present & ~group).any()]
    if not peel:
        return Plan(arrays, np.zeros(len(inner), dtype=bool))
    factored = Plan(arrays, inner & ~peel[0], peel[1:])
    # the flat plan's cost when it shares no polynomial (the entries of a factored plan's
    # polynomials are distinct): a product per monomial, one per term
    if factored.cost < len(powers) or factored.cost < len(powers) + len(
            unique_rows(powers)[0]):
        return factored
    flat = Plan(arrays, np.zeros(len(inner), dtype=bool))
    return factored if factored.cost < flat.cost else flat


def monomial_tuples(powers) -> list:
    """The rows of ``powers`` as monomials (sorted tuples of ``(atom, power)``)."""
    rows, atoms = np.nonzero(powers)
    pairs = list(zip(atoms.tolist(), powers[rows, atoms].tolist(), strict=True))
    bounds = np.searchsorted(rows, np.arange(len(powers) + 1)).tolist()
    return [tuple(pairs[bounds[m]:bounds[m + 1]]) for m in range(len(powers))]


def _distinct_codes(codes, space):
    """``numpy.unique(codes, return_inverse=True)`` of non-negative integers below ``space``,
    by a table of the codes present when it is no larger than a few times the codes."""
    if space > 8 * len(codes) + 1024:
        return np.unique(codes, return_inverse=True)
    present = np.zeros(space, dtype=bool)
    present[codes] = True
    return np.flatnonzero(present), (np.cumsum(present) - 1)[codes]


def _distinct_runs(bounds, *columns) -> np.ndarray:
    """For each run ``bounds[m]:bounds[m + 1]`` of the rows of ``columns`` (integer arrays),
    the number of the first run equal to it, counted in order of first appearance.

    Runs are grouped by a hash of their rows, and each group is checked row by row against
    its first run (a collision, never seen, falls back to comparing the runs one by one).

    >>> bounds = np.array([0, 2, 4, 4, 6, 7, 9])
    >>> a, b = np.array([1, 2, 1, 2, 3, 4, 1, 1, 2]), np.array([5, 6, 5, 6, 5, 6, 5, 5, 6])
    >>> _distinct_runs(bounds, a, b).tolist()
    [0, 0, 1, 2, 3, 0]
    """
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


class Plan:
    """How to evaluate entries: ``entry = sum over outer monomials u of u times a
    polynomial in the inner atoms``, each distinct polynomial (up to a factor) once.

    The terms of each entry are grouped by their outer monomial into *pairs* ``(u, entry)``,
    ordered by ``u`` (by degree, the constant first) and entry; the polynomial of a pair is
    its terms' inner monomials, in a canonical order, and its coefficients divided by the
    first one (the polynomials equal up to a factor are one: a symmetric mass matrix gives
    the same coefficient function to ``dL/dqd_i`` through ``qd_j`` and to ``dL/dqd_j``
    through ``qd_i``). The distinct polynomials are evaluated by a plan of their own on the
    inner atoms' rows (:func:`best_plan` with ``peel``). Without outer atoms (``inner`` all
    true or all false) every entry is one polynomial of all the atoms, evaluated flat: the
    monomials (:class:`MonomialValues`) times a sparse matrix of coefficients.

    Attributes
    ----------
    cost : int
        Operations per sample: a product per monomial, a product and a sum per term and
        per pair.
    size : int
        Rows of the arrays built per block of samples.
    """

    def __init__(self, arrays, inner, peel=()):
        powers, coefficients, owners, self.n_entries = arrays
        factor = bool(inner.any() and not inner.all())
        entries = max(self.n_entries, 1)
        # pairs (outer monomial, entry), in order, and each term's pair
        if factor:
            outer_powers = powers.compress(~inner, axis=1)  # (faster than a fancy index)
            outer_first, outer_of = unique_rows(outer_powers)
            outer_rank = np.empty(len(outer_first), dtype=np.intp)  # by degree (1 first)
            outer_rank[np.argsort(outer_powers[outer_first].sum(axis=1), kind="stable")] = \
                np.arange(len(outer_first))
            pair_codes, pair_of = _distinct_codes(outer_rank[outer_of] * entries + owners,
                                                  len(outer_first) * entries)
            pair_outer = np.argsort(outer_rank)[pair_codes // entries]
            pair_entry = pair_codes % entries
            distinct_outer = np.zeros((len(outer_first), len(inner)), dtype=np.int16)
            distinct_outer[:, ~inner] = outer_powers[outer_first]
            outer_keys = monomial_tuples(distinct_outer)
        else:  # one pair per entry, even without terms
            pair_of, pair_entry = owners, np.arange(self.n_entries)
            pair_outer, outer_keys = np.zeros(self.n_entries, dtype=np.intp), [()]
        pair_of = pair_of.ravel()
        n_pairs = len(pair_entry)
        # each pair's terms sorted by inner monomial (stable), divided by the first one
        # (the inner atoms only: the factored polynomials are evaluated on their rows)
        self.inner = np.flatnonzero(inner) if factor else None
        inner_powers = powers.compress(inner, axis=1) if factor else powers
        inner_first, inner_of = unique_rows(inner_powers)
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
            self.polynomials = best_plan(
                (inner_powers[order[rows]], normal[rows], polynomial_of, len(distinct)),
                np.ones(len(self.inner), dtype=bool), [group[self.inner] for group in peel])
        else:
            used, position = np.unique(wanted_ids, return_inverse=True)
            keys = monomial_tuples(inner_powers[inner_first[used]])
            self.polynomials = MonomialValues(keys)
            columns = np.array([self.polynomials.position[key] for key in keys], dtype=np.intp)
            self.coefficients = scipy.sparse.csr_matrix(
                (normal[rows], (polynomial_of, columns[position.ravel()])),
                shape=(len(distinct), self.polynomials.size))
        self.outer = MonomialValues([key for key in outer_keys if key])
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


#: Terms from which a plan is stored on disk: smaller ones are planned faster than read.
STORED_TERMS = 50_000
_PLAN_FORMAT = 1


def _csr_arrays(matrix, prefix) -> dict:
    return {f"{prefix}data": matrix.data, f"{prefix}indices": matrix.indices,
            f"{prefix}indptr": matrix.indptr, f"{prefix}shape": np.array(matrix.shape)}


def _csr_of(data, prefix):
    return scipy.sparse.csr_matrix((data[f"{prefix}data"], data[f"{prefix}indices"],
                                    data[f"{prefix}indptr"]), shape=tuple(data[f"{prefix}shape"]))


def _values_arrays(values: MonomialValues, prefix) -> dict:
    first, atoms = values.first
    return {f"{prefix}header": np.array([values.size, values.constant, first.start, first.stop]),
            f"{prefix}atoms": atoms,
            f"{prefix}levels": np.array([(a, b, len(runs)) for a, b, _, runs in values.levels],
                                        dtype=np.intp).reshape(-1, 3),
            f"{prefix}parents": np.concatenate([p for _, _, p, _ in values.levels] or [[]]),
            f"{prefix}runs": np.array([r for *_, runs in values.levels for r in runs],
                                      dtype=np.intp).reshape(-1, 3)}


def _values_of(data, prefix) -> MonomialValues:
    values = MonomialValues.__new__(MonomialValues)
    size, constant, start, stop = data[f"{prefix}header"].tolist()
    values.size, values.constant = size, bool(constant)
    values.first = (slice(start, stop), data[f"{prefix}atoms"])
    parents = data[f"{prefix}parents"].astype(np.intp)
    runs = [tuple(r) for r in data[f"{prefix}runs"].tolist()]
    values.levels, used, offset = [], 0, 0
    for a, b, count in data[f"{prefix}levels"].tolist():
        values.levels.append((a, b, parents[offset:offset + b - a], runs[used:used + count]))
        offset, used = offset + b - a, used + count
    return values


def plan_arrays(plan: Plan, prefix="") -> dict:
    """A plan as named arrays (:func:`plan_of` reads them back): what evaluation uses."""
    arrays = {f"{prefix}header": np.array([plan.n_entries, plan.size, plan.cost, plan.direct,
                                           plan.inner is not None]),
              f"{prefix}index": plan.index, f"{prefix}pair_runs": np.array(
                  plan.runs, dtype=np.intp).reshape(-1, 3),
              **_csr_arrays(plan.sum, f"{prefix}sum."),
              **_values_arrays(plan.outer, f"{prefix}outer.")}
    if plan.inner is not None:
        return {**arrays, f"{prefix}inner": plan.inner,
                **plan_arrays(plan.polynomials, f"{prefix}p.")}
    return {**arrays, **_csr_arrays(plan.coefficients, f"{prefix}coefficients."),
            **_values_arrays(plan.polynomials, f"{prefix}monomials.")}


def plan_of(data, prefix="") -> Plan:
    """The plan stored by :func:`plan_arrays`."""
    plan = Plan.__new__(Plan)
    plan.n_entries, plan.size, plan.cost, direct, factored = data[f"{prefix}header"].tolist()
    plan.direct = bool(direct)
    plan.index = data[f"{prefix}index"]
    plan.runs = [tuple(r) for r in data[f"{prefix}pair_runs"].tolist()]
    plan.sum = _csr_of(data, f"{prefix}sum.")
    plan.outer = _values_of(data, f"{prefix}outer.")
    if factored:
        plan.inner = data[f"{prefix}inner"]
        plan.polynomials = plan_of(data, f"{prefix}p.")
    else:
        plan.inner = None
        plan.coefficients = _csr_of(data, f"{prefix}coefficients.")
        plan.polynomials = _values_of(data, f"{prefix}monomials.")
    return plan


@functools.cache
def _code_digest() -> str | None:
    here = os.path.dirname(os.path.abspath(__file__))
    digest = _disk_cache.source_digest([os.path.join(here, name) for name in (
        "_plans.py", "_monomials.py")], _PLAN_FORMAT, scipy.__version__)
    return None if digest is None else digest.hexdigest()


def stored_plan(arrays, inner, peel) -> Plan:
    """:func:`best_plan`, kept on disk (:mod:`pysindy_xl._disk_cache`) for terms of
    :data:`STORED_TERMS` or more, named by a digest of the terms, masks and planning code."""
    code = _code_digest()
    if len(arrays[1]) < STORED_TERMS or code is None or _disk_cache.directory() is None:
        return best_plan(arrays, inner, peel)
    digest = hashlib.sha256(code.encode())
    _disk_cache.add_arrays(digest, (*arrays[:3], np.array(arrays[3]), inner, *peel))
    name = digest.hexdigest()
    stored = _disk_cache.read_arrays("plan", name)
    if stored is not None:
        try:
            return plan_of(stored)
        except (KeyError, ValueError, TypeError):
            pass
    plan = best_plan(arrays, inner, peel)
    _disk_cache.write_arrays("plan", name, plan_arrays(plan))
    return plan
