"""The weak regression matrix of several trajectories, as :class:`~pysindy_xl.XLSINDy` fits it.

Each trajectory is smoothed, gets test functions of one shared width, loses those touching a
masked sample and contributes its ``(n, K, F)`` block; blocks are concatenated along the test
functions, so rows stay coordinate-major over all trajectories.
"""

from __future__ import annotations

import copy
import hashlib
import warnings

import numpy as np
import scipy.sparse

from .._memo import shared_derivation
from ..symbols import stack_variables
from .bumps import BumpTestFunctions
from .noise import WeakNoise, draw_moments
from .smoothing import WhittakerSmoother, is_uniform
from .timegrid import STAMP_NOISE_RATIO, grid_summary, split_at_gaps, stamp_noise_ratio

__all__ = ["weak_regression", "shared_half_width", "propagated_noise", "propagated_draws"]

#: Samples times draws of the noise propagation (longer records need fewer draws).
_PROPAGATION_SAMPLES = 24_000


def shared_half_width(test_functions, trajectories, columns=None) -> float:
    """One test-function half-width for all trajectories.

    The narrowest asked for by the trajectories at least half as long as the longest (short
    pieces have unreliable spectra). Only the coordinates in ``columns`` set it: still
    coordinates have only the noise's spectrum.

    Parameters
    ----------
    test_functions : BumpTestFunctions
        The test functions (:meth:`~BumpTestFunctions.half_width`).
    trajectories : list of dict
        With ``"t"`` and ``"x"``.
    columns : ndarray of bool, shape (n,), optional
        The coordinates that choose; default None: all.

    Returns
    -------
    float
        The half-width.

    Examples
    --------
    >>> import numpy as np
    >>> from pysindy_xl.weak import BumpTestFunctions
    >>> t = np.linspace(0, 10, 1001)
    >>> shared_half_width(BumpTestFunctions(width=0.5), [{"t": t, "x": np.sin(t)[:, None]}])
    0.5
    """
    durations = np.array([d["t"][-1] - d["t"][0] for d in trajectories])
    widths = []
    for d, duration in zip(trajectories, durations, strict=True):
        if duration >= durations.max() / 2:
            try:
                x = d["x"] if columns is None else d["x"][:, np.asarray(columns, bool)]
                widths.append(test_functions.half_width(d["t"], x))
            except ValueError:
                continue  # shorter than the width it asks for
    if not widths:
        raise ValueError(f"x: the trajectories ({durations.max():.3g} s at most) are shorter than "
                         "one test function; record longer trajectories, set a smaller "
                         "BumpTestFunctions(width=...), or use formulation='strong'")
    return min(widths)


def propagated_noise(library, d, smoothing, phi, dphi, block, n_draws, rng):
    r"""Second moments of the weak columns' errors caused by the noise of the positions.

    Fresh noise of the estimated level is added to the positions, which are smoothed again
    with the same weights and turned into weak columns; the change ``Delta`` from ``block`` is
    distributed (to first order) as the error ``E``:

    .. math:: \mathrm{E}[E_c^T E_c] \approx \frac{1}{D} \sum_{d=1}^{D} \Delta_{c,d}^T \Delta_{c,d}

    over ``D = n_draws`` draws, per coordinate block ``c``.

    Parameters
    ----------
    library : fitted SymbolicLibrary
        The catalog.
    d : dict
        The trajectory: ``"t"``, ``"x"`` (noisy positions), ``"u"``.
    smoothing : smoother or tuple
        The smoother as it smoothed ``d`` (with ``noise_`` and ``resmooth``), or
        ``(lam, noise, order)`` of a :class:`WhittakerSmoother`.
    phi, dphi : sparse matrix, shape (K, N)
        The test-function matrices of ``d``.
    block : ndarray, shape (n * K, F)
        The weak columns of ``d``.
    n_draws : int
        Draws of fresh noise.
    rng : numpy.random.Generator
        Source of the draws.

    Returns
    -------
    ndarray, shape (n, F, F)
        The moments of each coordinate's rows.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> coords = px.Coordinates(["x"])
    >>> library = px.LagrangeLibrary(coords, [coords.qd[0] ** 2, coords.q[0] ** 2]).fit()
    >>> t = np.linspace(0, 20, 2001)
    >>> x = np.sin(t)[:, None] + 0.01 * np.random.default_rng(0).normal(size=(2001, 1))
    >>> smoother = px.WhittakerSmoother()
    >>> q, qd, qdd = smoother.smooth(t, x)
    >>> phi, dphi, _ = px.BumpTestFunctions(width=2.0).matrices(t)
    >>> block = library.weak_transform(px.stack_variables(q, qd, qdd, t=t), phi, dphi)
    >>> d = {"t": t, "x": x, "u": None}
    >>> moments = propagated_noise(library, d, (smoother.lam_, smoother.noise_, 3), phi, dphi,
    ...                            block, 4, np.random.default_rng(1))
    >>> moments.shape, bool(np.all(np.diag(moments[0]) > 0))
    ((1, 2, 2), True)
    """
    return draw_moments(propagated_draws(library, d, smoothing, phi, dphi, block, n_draws, rng),
                        library.coords.n)


def propagated_draws(library, d, smoothing, phi, dphi, block, n_draws, rng):
    """Draws of the change of the weak columns under fresh noise of the estimated level.

    As :func:`propagated_noise`, without averaging.

    Parameters
    ----------
    library : fitted SymbolicLibrary
        The catalog.
    d : dict
        The trajectory: ``"t"``, ``"x"`` (noisy positions), ``"u"``.
    smoothing : smoother or tuple
        The smoother as it smoothed ``d`` (with ``noise_`` and ``resmooth``), or
        ``(lam, noise, order)`` of a :class:`WhittakerSmoother`.
    phi, dphi : sparse matrix, shape (K, N)
        The test-function matrices of ``d``.
    block : ndarray, shape (n * K, F)
        The weak columns of ``d``.
    n_draws : int
        Draws of fresh noise.
    rng : numpy.random.Generator
        Source of the draws.

    Returns
    -------
    ndarray, shape (n_draws, n * K, F)
        The changes ``Delta``, rows coordinate-major.
    """
    if isinstance(smoothing, tuple):  # (lam, noise, order) of a WhittakerSmoother
        lam, noise, order = smoothing
        smoothing = WhittakerSmoother(order=order)
        smoothing.lam_, smoothing.noise_ = np.asarray(lam, float), np.asarray(noise, float)
    n = d["x"].shape[1]
    noisy = [d["x"] + smoothing.noise_ * rng.normal(size=d["x"].shape) for _ in range(n_draws)]
    # all the draws smoothed side by side (Whittaker: each weight's system factored once)
    smoothed = smoothing.resmooth(d["t"], np.hstack(noisy))
    draws = np.empty((n_draws,) + block.shape)
    for k in range(n_draws):
        q, qd, qdd = (values[:, k * n : (k + 1) * n] for values in smoothed)
        draws[k] = library.weak_transform(stack_variables(q, qd, qdd, d["u"], d["t"]), phi,
                                          dphi) - block
    return draws


def weak_regression(library, trajectories, test_functions, smoother, noise="moments",
                    half_width=None, width_columns=None):
    """Weak regression matrix of all trajectories, rows coordinate-major.

    Trajectories are cut at steps longer than ``test_functions.max_gap(half_width)``
    (:mod:`~pysindy_xl.weak.timegrid`); pieces shorter than one test function are left out
    with a warning.

    Parameters
    ----------
    library : fitted SymbolicLibrary
        The catalog (:meth:`~pysindy_xl.feature_library.SymbolicLibrary.weak_transform`).
    trajectories : list of dict
        Keys ``"t"``, ``"x"``, ``"x_dot"`` (measured velocities or None), ``"u"`` (forces or
        None) and ``"mask"`` (bool (N,), samples to explain).
    test_functions : BumpTestFunctions
        The test functions.
    smoother : WhittakerSmoother
        Anything with ``smooth(t, x) -> (q, qd, qdd)``; it propagates the positions' noise when
        it also has ``noise_`` and ``resmooth``.
    noise : {"moments", "draws", "none"}, default "moments"
        Return the propagated noise's moments, or its draws as a
        :class:`~pysindy_xl.weak.noise.WeakNoise`; ``"none"``: not propagated.
    half_width : float, optional
        Default None: :func:`shared_half_width`.
    width_columns : array of bool, shape (n,), optional
        The coordinates whose spectra choose the default half-width; default None: all.

    Returns
    -------
    theta : ndarray, shape (n * K, F)
        The weak rows, coordinate-major.
    states : ndarray, shape (N_total, 4n + 1)
        The smoothed states of the pieces used.
    noise_moments : ndarray (n, F, F), WeakNoise or None
        ``E[E_c^T E_c]`` of each coordinate's rows (:func:`propagated_noise`); None unless the
        smoother estimated the noise of every piece and no velocities were measured.
    info : dict
        ``half_width``, ``test_functions`` (count per piece), ``noise`` (the smoother's
        estimate), ``time_grid`` (:func:`~pysindy_xl.weak.timegrid.grid_summary`), ``gaps``,
        ``segments`` (each piece's trajectory) and ``supports`` ((K, 3): each test function's
        trajectory and first and last time).

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> coords = px.Coordinates(["x"])
    >>> library = px.CatalogRepartition([
    ...     px.ExternalForces(coords),
    ...     px.LagrangeLibrary(coords, [coords.qd[0] ** 2, coords.q[0] ** 2])]).fit()
    >>> t = np.linspace(0, 20, 2001)
    >>> x = np.sin(t)[:, None] + 0.01 * np.random.default_rng(0).normal(size=(2001, 1))
    >>> d = {"t": t, "x": x, "x_dot": None, "u": np.zeros((2001, 1)),
    ...      "mask": np.ones(2001, bool)}
    >>> theta, states, moments, info = weak_regression(
    ...     library, [d], px.BumpTestFunctions(width=2.0), px.WhittakerSmoother())
    >>> theta.shape[1], states.shape, moments.shape, info["half_width"]
    (3, (2001, 5), (1, 3, 3), 2.0)
    """
    if noise not in ("moments", "draws", "none"):
        raise ValueError(f"noise: expected 'moments', 'draws' or 'none', got {noise!r}")
    for name, value, kind in (("test_functions", test_functions, "matrices"),
                              ("smoother", smoother, "smooth")):
        if not callable(getattr(value, kind, None)):
            raise TypeError(f"{name}: expected an object with a {kind} method, got "
                            f"{type(value).__name__}")
    if half_width is None:
        half_width = shared_half_width(test_functions, trajectories, width_columns)
    max_gap = getattr(test_functions, "max_gap", None)
    segments, source, gaps = split_at_gaps(
        trajectories, np.inf if max_gap is None else max_gap(half_width))
    durations = np.array([d["t"][-1] - d["t"][0] for d in segments])
    usable = np.flatnonzero(durations >= 2 * half_width)
    summary = grid_summary([d["t"] for d in trajectories])
    if len(usable) < len(segments):
        short = sorted(set(source[durations < 2 * half_width].tolist()))
        what = (f"pieces (between {len(gaps)} gaps longer than {max_gap(half_width):.3g} s) "
                "of " if gaps else "")
        warnings.warn(f"x: {what}trajectories {short} are shorter than one test function (support "
                      f"{2 * half_width:.3g} s) and are left out of the weak regression",
                      UserWarning, stacklevel=4)
    if usable.size == 0:
        raise ValueError(
            f"t: every piece of the trajectories between gaps longer than "
            f"{max_gap(half_width):.3g} s is shorter than one test function (support "
            f"{2 * half_width:.3g} s); resample across the gaps or set a smaller width")
    pieces = [segments[k] for k in usable]
    states, smoothing, noise_level = [], [], None
    propagates, warned = callable(getattr(smoother, "resmooth", None)), False
    for d in pieces:
        q, qd, qdd = smoother.smooth(d["t"], d["x"])
        if noise_level is None:
            noise_level = getattr(smoother, "noise_", None)
        # the smoother as it smoothed this trajectory (its weights), for the noise propagation
        smoothing.append(copy.copy(smoother) if propagates else None)
        if d["x_dot"] is not None:  # measured velocities are better than estimated ones
            q, qd = d["x"], d["x_dot"]
            smoothing[-1] = None
        elif not propagates and not warned and noise != "none":
            warned = True
            warnings.warn(f"smoother: {type(smoother).__name__} has no resmooth method (and noise_ "
                          "attribute), so the noise of the positions is not propagated into the "
                          "weak columns and the fit is not corrected for it; see "
                          "WhittakerSmoother.resmooth", UserWarning, stacklevel=4)
        states.append(stack_variables(q, qd, qdd, d["u"], d["t"]))

    def estimated(piece):  # a smoother copy that estimated its noise
        return piece is not None and np.all(np.isfinite(getattr(piece, "noise_", np.nan)))

    first = next((k for k, (d, piece) in enumerate(zip(pieces, smoothing, strict=True))
                  if estimated(piece) and not is_uniform(d["t"])), None)
    if first is not None:  # are the stamps sampling times?
        ratio = stamp_noise_ratio(pieces[first]["t"], pieces[first]["x"], smoothing[first].noise_,
                                  getattr(smoothing[first], "order", 3))
        summary["stamp_noise_ratio"] = ratio
        if ratio > STAMP_NOISE_RATIO:
            warnings.warn(f"t: the positions look {ratio:.3g} times noisier at their stamps than "
                          "read at uniform steps; the stamps may be arrival times of samples taken "
                          "at a fixed rate, whose delays pass for motion: if so, pass uniform "
                          "times", UserWarning, stacklevel=4)
    propagate = noise != "none" and all(estimated(piece) for piece in smoothing)
    n_samples = sum(len(d["t"]) for d in pieces)
    n_draws = int(np.clip(np.ceil(_PROPAGATION_SAMPLES / max(n_samples, 1)), 1, 16))
    rng = np.random.default_rng(0)  # reproducible fits
    n = library.coords.n
    blocks, draws, runs, supports = [], [], [], []
    for k, (d, z) in enumerate(zip(pieces, states, strict=True)):
        phi, dphi, overlap = _test_matrices(test_functions, d["t"], half_width)
        kept = np.arange(phi.shape[0])
        if not d["mask"].all():  # drop the test functions that see a masked sample
            kept = np.flatnonzero((abs(phi) @ (~d["mask"]).astype(float)) == 0)
            phi, dphi = phi[kept], dphi[kept]
            if phi.shape[0] == 0:
                continue
        block = library.weak_transform(z, phi, dphi)
        blocks.append(block.reshape(n, phi.shape[0], -1))
        supports.append(_supports(phi, d["t"], source[usable[k]]))
        runs.append((np.split(np.arange(len(kept)), np.flatnonzero(np.diff(kept) > 1) + 1),
                     overlap))
        if propagate:
            draws.append(propagated_draws(library, d, smoothing[k], phi, dphi, block, n_draws,
                                          rng).reshape(n_draws, n, phi.shape[0], -1))
    if not blocks:
        raise ValueError("sample_mask: every test function touches a masked sample; "
                         "unmask longer stretches or set a smaller test-function width")
    theta = np.concatenate(blocks, axis=1).reshape(-1, blocks[0].shape[-1])
    propagated = None
    if draws:
        propagated = WeakNoise(np.concatenate(draws, axis=2).reshape(n_draws, theta.shape[0], -1),
                               n, _row_runs(runs, n))
    info = {"half_width": half_width, "test_functions": [b.shape[1] for b in blocks],
            "noise": None if noise_level is None else np.asarray(noise_level).tolist(),
            "time_grid": summary, "gaps": gaps, "segments": source[usable].tolist(),
            "supports": np.concatenate(supports)}
    if noise == "moments" and propagated is not None:
        propagated = propagated.moments()
    return theta, np.vstack(states), propagated, info


def _supports(phi, t, trajectory) -> np.ndarray:
    """``(trajectory, first time, last time)`` of each test function's support, shape (K, 3)."""
    phi = scipy.sparse.csr_matrix(phi)
    starts = phi.indptr[:-1]
    first = np.minimum.reduceat(phi.indices, starts)
    last = np.maximum.reduceat(phi.indices, starts)
    return np.column_stack([np.full(len(first), float(trajectory)), t[first], t[last]])


#: The test-function matrices of pieces met before (:func:`_test_matrices`), most recently
#: used last: a growth fits many catalogs on the same pieces.
_MATRICES: dict = {}
_CACHED_MATRICES = 64


def _test_matrices(test_functions, t, half_width) -> tuple:
    """``(phi, dphi, overlap)`` of a piece: ``test_functions.matrices(t, half_width=...)``
    and :func:`_overlap_rows`, computed once per test functions' parameters, times and
    half-width (:class:`~pysindy_xl.weak.BumpTestFunctions`; other test functions each
    time). The matrices are shared: read, never modified."""
    if type(test_functions) is not BumpTestFunctions:
        phi, dphi, _ = test_functions.matrices(t, half_width=half_width)
        return phi, dphi, _overlap_rows(phi)
    t = np.ascontiguousarray(t, dtype=float)
    # (arrays by their bytes: their repr rounds and elides)
    state = tuple(sorted((name, (value.dtype.str, value.shape, value.tobytes())
                          if isinstance(value, np.ndarray) else repr(value))
                         for name, value in vars(test_functions).items()))
    key = (state, float(half_width), t.shape, hashlib.sha1(t).digest())

    def derive():
        phi, dphi, _ = test_functions.matrices(t, half_width=half_width)
        return phi, dphi, _overlap_rows(phi)

    return shared_derivation(key, derive, _MATRICES, _CACHED_MATRICES)


def _overlap_rows(phi) -> int:
    """The largest row lag at which two test functions (rows of ``phi``) overlap."""
    gram = (abs(phi) @ abs(phi).T).tocoo()
    return int(np.max(np.abs(gram.row - gram.col))) if gram.nnz else 0


def _row_runs(runs, n_coordinates):
    """``(start, stop, group, overlap)`` of the runs of consecutive test functions in the
    coordinate-major rows, from each trajectory's runs (local indices) and overlap.
    """
    counts = [sum(len(run) for run in local) for local, _ in runs]
    offsets = np.concatenate([[0], np.cumsum(counts)])
    rows = []
    for coordinate in range(n_coordinates):
        for k, (local, overlap) in enumerate(runs):
            start = coordinate * offsets[-1] + offsets[k]
            rows += [(start + run[0], start + run[-1] + 1, coordinate * len(runs) + k, overlap)
                     for run in local]
    return np.array(rows, dtype=int)
