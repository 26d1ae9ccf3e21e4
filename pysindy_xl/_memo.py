"""One bounded cache of derived values by key, shared by the modules that keep results of
costly derivations (terms, test-function matrices, smoothing factorizations)."""

from __future__ import annotations

__all__ = ["shared_derivation"]


def shared_derivation(key, derive, cache: dict, size: int):
    """``derive()``, shared by every call with the same ``key`` in ``cache`` (at most ``size``
    entries, the least recently used dropped first).

    Parameters
    ----------
    key : hashable
        What the derived value depends on, whole.
    derive : callable
        ``derive() -> value``, called when ``key`` is not in ``cache``.
    cache : dict
        The cache, most recently used last (read and reordered in place).
    size : int
        Most entries kept.

    Returns
    -------
    object
        The derived value (shared: read, never modified).

    Examples
    --------
    >>> cache = {}
    >>> shared_derivation("a", lambda: 1, cache, 2), shared_derivation("a", lambda: 2, cache, 2)
    (1, 1)
    """
    found = cache.pop(key, None)
    if found is None:
        found = derive()
    cache[key] = found
    while len(cache) > size:
        del cache[next(iter(cache))]
    return found
