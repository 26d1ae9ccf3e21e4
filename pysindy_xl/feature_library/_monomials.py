"""Rows of monomial exponents (int16, one column per slot): sorting, merging and the canonical
form of trigonometric polynomials (:mod:`.trigpoly`), bit for bit the rows and order of the
plain algorithm.
"""

from __future__ import annotations

import functools

import numpy as np

# Coefficients below this fraction of the largest one are round-off of float arithmetic.
ROUND_OFF = 1e-13


@functools.lru_cache(maxsize=64)
def _angle_slots(angles):
    """Which coordinates are angles (bool array) and their cosine slots."""
    angle = np.asarray(angles, dtype=bool)
    return angle, len(angles) + np.flatnonzero(angle)


def _reduce_cosine_squares(exponents, coefficients, owners, angles):
    """Rewrite ``cos^2 = 1 - sin^2`` until no cosine power reaches 2 (``owners``, if not None,
    follow their rows): a row with ``p`` halves of cosine powers becomes ``2^p`` rows, ordered by
    ``p``, then by the choices of the last pass to the first, then by row.
    """
    angle, cosines = _angle_slots(angles)
    if not len(cosines) or not len(exponents) or (
            exponents[:, cosines] if len(exponents) <= _FEW
            else _column_or(exponents)[cosines]).max() < 2:  # (an entry >= 2 has a bit >= 2)
        return exponents, coefficients, owners
    halves = exponents[:, cosines] // 2
    passes = halves.sum(axis=1)
    pieces = []  # (exponents, coefficients, owners) by number of passes
    for count in range(int(passes.max()) + 1):
        rows = np.flatnonzero(passes == count)
        if not len(rows):
            continue
        base = exponents[rows]
        if count:
            base[:, cosines] %= 2
            # each pass's angle (its sine slot), and each child's choices (bit i: pass i)
            sines = np.repeat(np.tile(cosines - len(angles), len(rows)),
                              halves[rows].ravel()).reshape(len(rows), count)
            choices = (np.arange(2 ** count)[:, None] >> np.arange(count)) & 1
            base = np.repeat(base[None], 2 ** count, axis=0)
            for i in range(count):
                base[:, np.arange(len(rows)), sines[:, i]] += 2 * choices[:, i:i + 1].astype(
                    np.int16)
            signs = np.where(choices.sum(axis=1) % 2, -1.0, 1.0)
            pieces.append((base.reshape(-1, exponents.shape[1]),
                           (signs[:, None] * coefficients[rows]).ravel(),
                           None if owners is None else np.tile(owners[rows], 2 ** count)))
        else:
            pieces.append((base, coefficients[rows], None if owners is None else owners[rows]))
    exponents = np.vstack([p[0] for p in pieces])
    coefficients = np.concatenate([p[1] for p in pieces])
    if owners is not None:
        owners = np.concatenate([p[2] for p in pieces])
    return exponents, coefficients, owners


_CHUNK = 8192  # rows turned into keys at once (kept in cache)
_FEW = 32  # fewer rows are checked for cosine squares directly


def _column_or(rows) -> np.ndarray:
    """The bitwise or of each column of a C-contiguous 2-d int array."""
    wide = len(rows) // 64 * 64
    ored = np.bitwise_or.reduce(rows[wide:], axis=0)
    if wide:
        ored |= np.bitwise_or.reduce(np.bitwise_or.reduce(
            rows[:wide].reshape(-1, 64 * rows.shape[1]), axis=0).reshape(64, -1), axis=0)
    return ored


def _row_keys(rows, major=None):
    """One key per row of a non-negative int16 array, ordered as the rows are lexicographically
    (``major``, if given, first), or None when entries are negative, reach 256 or need over 62
    bits. Each column is a bit field; float64 keys (one BLAS product) when 52 bits suffice.
    """
    n_rows, width = rows.shape
    ored = _column_or(rows)
    if ored.min() < 0 or ored.max() >= 256:
        return None
    bits = np.ceil(np.log2(ored.astype(float) + 1.0)).astype(np.int64)
    major_bits = 0 if major is None else int(major.max(initial=0)).bit_length()
    total = int(bits.sum()) + major_bits
    if total > 62:
        return None
    shifts = np.cumsum(bits[::-1])[::-1] - bits
    dtype = float if total <= 52 else np.int64
    weights = (np.int64(1) << shifts).astype(dtype)
    keys = np.empty(n_rows, dtype=dtype)
    for start in range(0, n_rows, _CHUNK):
        np.matmul(rows[start:start + _CHUNK].astype(dtype), weights, out=keys[start:start + _CHUNK])
    if major_bits:
        keys += major.astype(dtype) * dtype(1 << (total - major_bits))
    return keys


def unique_rows(rows, major=None) -> tuple[np.ndarray, np.ndarray]:
    """``(index, inverse)`` of ``numpy.unique`` on int16 rows read as bytes (``major``, small
    non-negative integers, sorting before the first column), by :func:`_row_keys` when it can.
    """
    rows = np.ascontiguousarray(rows, dtype=np.int16)
    if len(rows) < 2 or not rows.shape[1]:  # (rows without columns are all equal)
        return np.arange(min(len(rows), 1)), np.zeros(len(rows), dtype=np.intp)
    keys = _row_keys(rows, major)
    if keys is None:
        if major is not None:
            rows = np.column_stack([major.astype(np.int16), rows])
        keys = rows.view(np.dtype((np.void, 2 * rows.shape[1]))).ravel()
        _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
        return first, inverse.ravel()
    order = np.argsort(keys)  # not stable: the first of each group is its smallest index
    ordered = keys[order]
    new = np.empty(len(keys), dtype=bool)
    new[0] = True
    np.not_equal(ordered[1:], ordered[:-1], out=new[1:])
    starts = np.flatnonzero(new)
    inverse = np.empty(len(keys), dtype=np.intp)
    inverse[order] = np.cumsum(new) - 1
    return np.minimum.reduceat(order, starts), inverse


def normalize_terms(exponents, coefficients, angles):
    """Rewrite cos^2 = 1 - sin^2, merge equal monomials, drop zero and round-off terms."""
    exponents, coefficients, _ = _reduce_cosine_squares(exponents, coefficients, None, angles)
    if len(coefficients) <= 1:  # the rule below for one term, without arrays
        value = float(coefficients[0]) if len(coefficients) else 0.0
        keep = abs(value) > ROUND_OFF * max(abs(value), 1.0)
        return exponents[:int(keep)].copy(), coefficients[:int(keep)].copy()
    first, inverse = unique_rows(exponents)
    merged = np.bincount(inverse, weights=coefficients, minlength=len(first))
    scale = np.abs(coefficients).max()
    keep = np.abs(merged) > ROUND_OFF * max(scale, 1.0)
    return exponents[first[keep]], merged[keep]


def normalize_owned(exponents, coefficients, owners, angles, count):
    """:func:`normalize_terms` of each owner's rows (the same operations, per owner)."""
    exponents, coefficients, owners = _reduce_cosine_squares(exponents, coefficients, owners,
                                                             angles)
    if len(coefficients) == 0:
        return exponents, coefficients, owners
    # the owner first in each key: rows group by owner, and within an owner sort as alone
    first, inverse = unique_rows(exponents, major=owners)
    merged = np.bincount(inverse, weights=coefficients, minlength=len(first))
    scale = np.zeros(count)
    np.maximum.at(scale, owners, np.abs(coefficients))
    kept_owners = owners[first]
    keep = np.abs(merged) > ROUND_OFF * np.maximum(scale[kept_owners], 1.0)
    return exponents[first[keep]], merged[keep], kept_owners[keep]
