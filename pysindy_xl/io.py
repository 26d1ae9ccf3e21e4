"""JSON persistence of identified models.

The file holds the coordinate names, the catalog specification (terms as strings of the
restricted grammar of :mod:`pysindy_xl.expressions`, masks, interlink matrices), the
coefficients, the optimizer's plain parameters and, after an ensemble fit, the inclusion
probabilities and coefficient intervals. Loading validates every field and parses terms with
that grammar only: nothing in the file is executed (no pickle, no ``eval``, no ``sympify``).
"""

from __future__ import annotations

import json
import math
import os

import numpy as np

from .expressions import expression_size, parse_expression
from .feature_library import CatalogRepartition, ClassicalLibrary, ExternalForces, LagrangeLibrary
from .symbols import Coordinates

__all__ = ["save_model", "load_model", "FORMAT", "VERSION", "OPTIMIZER_TYPES"]

FORMAT = "pysindy-xl-model"
VERSION = 1
_MAX_BYTES = 50_000_000
_MAX_TERMS = 5_000  # catalog terms in one file (about a minute of derivation)
_MAX_TOTAL_SIZE = 20_000  # sum over the terms of their expanded size (expression_size)
#: optimizer types a model file may name (the documented catalog optimizers, nothing else);
#: an EnsembleOptimizer's own ``optimizer`` is one of the others, never an ensemble
OPTIMIZER_TYPES = ("ExplicitOptimizer", "ImplicitOptimizer", "MixedOptimizer",
                   "EnsembleOptimizer")


def save_model(model, path) -> None:
    """Write a fitted :class:`~pysindy_xl.XLSINDy` to ``path`` as JSON.

    Parameters
    ----------
    model : XLSINDy
        A fitted model.
    path : str or os.PathLike

    Examples
    --------
    >>> import json, os, tempfile
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> t = np.linspace(0, 5, 501)
    >>> x, xd, xdd = (np.sin(t) + t)[:, None], (np.cos(t) + 1)[:, None], -np.sin(t)[:, None]
    >>> model = px.XLSINDy(px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2]))
    >>> model = model.fit(x, t, xd, xdd, u=2 * xdd + x)
    >>> path = os.path.join(tempfile.mkdtemp(), "model.json")
    >>> save_model(model, path)
    >>> [round(c, 6) for c in json.load(open(path))["coefficients"]]
    [-1.0, 1.0, -0.5]
    """
    from sklearn.utils.validation import check_is_fitted

    check_is_fitted(model, "coef_")
    library = model.feature_library_
    optimizer = model.optimizer_
    document = {
        "format": FORMAT,
        "version": VERSION,
        "coordinates": list(library.coords.names),
        "feature_library": library.to_spec(),
        "feature_names": library.get_feature_names(),
        "coefficients": [float(c) for c in model.coef_],
        "dropped_features": model.dropped_features_,
        "forced_coordinates": [bool(f) for f in model.forced_coordinates_],
        "optimizer": _optimizer_spec(optimizer),
    }
    if getattr(model, "inclusion_probability_", None) is not None:
        document["uncertainty"] = {
            "inclusion_probability": [float(p) for p in model.inclusion_probability_],
            "coef_interval": [[float(c) for c in bound] for bound in model.coef_interval_]}
    text = json.dumps(document, indent=1, allow_nan=False)
    _check_writable(path)
    try:
        with open(os.fspath(path), "w", encoding="utf-8") as fh:
            fh.write(text)
    except OSError as err:
        raise ValueError(f"path: cannot write {os.fspath(path)!r} ({err.strerror or err})") \
            from None


def _check_writable(path) -> None:
    """A clear ValueError for a path that cannot hold the file (a directory, no folder)."""
    try:
        path = os.fspath(path)
    except TypeError:
        raise TypeError(f"path: expected a str or os.PathLike, got {type(path).__name__}") \
            from None
    if isinstance(path, bytes):
        path = os.fsdecode(path)
    if not path or "\x00" in path:
        raise ValueError(f"path: expected a file name, got {path!r}")
    if os.path.isdir(path):
        raise ValueError(f"path: {path!r} is a directory; give a file name such as "
                         f"{os.path.join(path, 'model.json')!r}")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise ValueError(f"path: the folder {folder!r} does not exist; create it first")


def _optimizer_spec(optimizer, nested: bool = False):
    """``{"type", "params"}`` of a documented optimizer (plain parameters only; an ensemble's
    own optimizer as a nested spec), or None."""
    name = type(optimizer).__name__
    if name not in OPTIMIZER_TYPES or (nested and name == "EnsembleOptimizer"):
        return None
    params = {}
    for key, value in optimizer.get_params(deep=False).items():
        if value is None or isinstance(value, (bool, int, float, str)):
            if isinstance(value, float) and not math.isfinite(value):
                continue
            params[key] = value
        elif name == "EnsembleOptimizer" and key == "optimizer":
            params[key] = _optimizer_spec(value, nested=True)
    return {"type": name, "params": params}


def _optimizer_from_spec(spec, path, nested: bool = False):
    """The optimizer a file's spec names: documented types and plain values only."""
    from . import optimizers

    types = tuple(t for t in OPTIMIZER_TYPES if not (nested and t == "EnsembleOptimizer"))
    where = "optimizer.params.optimizer" if nested else "optimizer"
    _expect(isinstance(spec, dict) and spec.get("type") in types, path,
            f"'{where}' must be null or an object whose 'type' is one of {types}")
    candidate = getattr(optimizers, spec["type"])
    params = dict(spec.get("params", {})) if isinstance(spec.get("params", {}), dict) else None
    valid = candidate().get_params(deep=False)
    _expect(params is not None and set(params) <= set(valid), path,
            f"{where}.params must be an object with keys among {sorted(valid)}")
    inner = params.pop("optimizer", None) if spec["type"] == "EnsembleOptimizer" else None
    _expect(all(v is None or isinstance(v, (bool, int, float, str)) for v in params.values()),
            path, f"{where}.params must be plain values")
    if inner is not None:
        params["optimizer"] = _optimizer_from_spec(inner, path, nested=True)
    optimizer = candidate(**params)
    try:
        optimizer._check_params()
    except (TypeError, ValueError) as err:
        raise _fail(path, f"{where}: {err}") from None
    return optimizer


def _uncertainty_from_document(document, n_features, path):
    """``(inclusion_probability, coef_interval)`` of an ensemble fit, or ``(None, None)``."""
    spec = document.get("uncertainty")
    if spec is None:
        return None, None
    _expect(isinstance(spec, dict) and set(spec) == {"inclusion_probability", "coef_interval"},
            path, "'uncertainty' must be an object with inclusion_probability and coef_interval")

    def numbers(values):
        return (isinstance(values, list) and len(values) == n_features
                and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                        and math.isfinite(v) for v in values))

    probability, interval = spec["inclusion_probability"], spec["coef_interval"]
    _expect(numbers(probability) and all(0 <= p <= 1 for p in probability), path,
            "uncertainty.inclusion_probability must be one number in [0, 1] per feature")
    _expect(isinstance(interval, list) and len(interval) == 2
            and all(numbers(bound) for bound in interval)
            and all(lo <= hi for lo, hi in zip(*interval, strict=True)), path,
            "uncertainty.coef_interval must be [low, high], one finite number per feature "
            "each, low <= high")
    return np.asarray(probability, dtype=float), np.asarray(interval, dtype=float)


def _fail(path, what: str):
    return ValueError(f"path: {os.fspath(path)!r} is not a valid pysindy-xl model file: {what}")


def _expect(condition: bool, path, what: str):
    if not condition:
        raise _fail(path, what)


def _library_from_spec(spec, coords: Coordinates, path, budget=None, depth=0):
    budget = {"terms": 0, "size": 0} if budget is None else budget
    _expect(depth <= 4, path, "libraries nested deeper than 4 levels")
    _expect(isinstance(spec, dict) and isinstance(spec.get("type"), str), path,
            "library spec must be an object with a 'type'")
    kind = spec["type"]
    table = {str(s): s for s in coords.variables}

    def terms():
        raw = spec.get("terms")
        _expect(isinstance(raw, list) and raw and all(isinstance(t, str) for t in raw), path,
                f"{kind}.terms must be a non-empty list of strings")
        _expect(len(raw) <= _MAX_TERMS - budget["terms"], path,
                f"more than {_MAX_TERMS} catalog terms")
        budget["terms"] += len(raw)
        parsed = []
        for text in raw:
            try:
                expr = parse_expression(text, table)
            except (TypeError, ValueError) as err:
                raise _fail(path, str(err)) from None
            budget["size"] += expression_size(expr)["terms"]
            _expect(budget["size"] <= _MAX_TOTAL_SIZE, path,
                    f"the catalog is too large (more than {_MAX_TOTAL_SIZE} expanded terms)")
            parsed.append(expr)
        return parsed

    if kind == "CatalogRepartition":
        libs = spec.get("libraries")
        _expect(isinstance(libs, list) and libs, path, "libraries must be a non-empty list")
        return CatalogRepartition([_library_from_spec(s, coords, path, budget, depth + 1)
                                   for s in libs])
    if kind == "LagrangeLibrary":
        return LagrangeLibrary(coords, terms())
    if kind == "ClassicalLibrary":
        parsed = terms()
        mask = np.asarray(spec.get("mask"))
        _expect(mask.shape == (len(parsed), coords.n) and np.isin(mask, (0, 1)).all(), path,
                "ClassicalLibrary.mask must be a 0/1 matrix (n_terms, n)")
        return ClassicalLibrary(coords, parsed, mask=mask.astype(bool))
    if kind == "ExternalForces":
        try:
            interlink = np.asarray(spec.get("interlink"), dtype=float)
        except (TypeError, ValueError):
            raise _fail(path, "ExternalForces.interlink must be a numeric matrix") from None
        _expect(interlink.shape == (coords.n, coords.n) and np.all(np.isfinite(interlink)), path,
                "ExternalForces.interlink must be a finite (n, n) matrix")
        return ExternalForces(coords, interlink=interlink)
    raise _fail(path, f"unknown library type {kind!r}")


def load_model(path):
    """Read a model written by :func:`save_model`.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    XLSINDy
        A fitted model that predicts and simulates like the saved one.

    Raises
    ------
    ValueError
        If the file is not a valid model file (the message says what is wrong).

    Examples
    --------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "bad.json")
    >>> _ = open(path, "w").write('{"format": "something else"}')
    >>> load_model(path)
    Traceback (most recent call last):
    ...
    ValueError: path: '...bad.json' is not a valid pysindy-xl model file: 'format' must be ...
    """
    from .model import XLSINDy

    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ValueError(f"path: no such file {path!r}")
    if os.path.getsize(path) > _MAX_BYTES:
        raise _fail(path, "file too large")
    try:
        with open(path, encoding="utf-8") as fh:
            document = json.load(fh, parse_constant=lambda c: (_ for _ in ()).throw(
                _fail(path, f"non-finite number {c}")))
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise _fail(path, f"not JSON ({err})") from None
    _expect(isinstance(document, dict) and document.get("format") == FORMAT, path,
            f"'format' must be {FORMAT!r}")
    _expect(document.get("version") == VERSION, path, f"unsupported version "
            f"{document.get('version')!r}")
    names = document.get("coordinates")
    _expect(isinstance(names, list) and all(isinstance(n, str) for n in names), path,
            "'coordinates' must be a list of names")
    try:
        coords = Coordinates(names)
    except (TypeError, ValueError) as err:
        raise _fail(path, str(err)) from None
    library = _library_from_spec(document.get("feature_library"), coords, path)
    if not isinstance(library, CatalogRepartition):
        library = CatalogRepartition([library])
    try:
        library.fit()
    except (RecursionError, OverflowError):
        raise _fail(path, "catalog: the terms are too complex to differentiate") from None
    except (TypeError, ValueError) as err:
        raise _fail(path, f"catalog: {err}") from None
    feature_names = library.get_feature_names()
    _expect(document.get("feature_names") == feature_names, path,
            "feature_names do not match the catalog")
    coef = document.get("coefficients")
    _expect(isinstance(coef, list) and len(coef) == len(feature_names)
            and all(isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c)
                    for c in coef), path,
            "'coefficients' must be one number per feature, all finite")
    forced = document.get("forced_coordinates", [True] * coords.n)
    _expect(isinstance(forced, list) and len(forced) == coords.n, path,
            "'forced_coordinates' must have one flag per coordinate")
    dropped = document.get("dropped_features", {})
    _expect(isinstance(dropped, dict), path, "'dropped_features' must be an object")

    spec = document.get("optimizer")
    optimizer = None if spec is None else _optimizer_from_spec(spec, path)
    probability, interval = _uncertainty_from_document(document, len(feature_names), path)
    model = XLSINDy(feature_library=library, optimizer=optimizer)
    model.feature_library_ = library
    model.optimizer_ = optimizer
    model.coef_ = np.asarray(coef, dtype=float)
    model.dropped_features_ = {str(k): str(v) for k, v in dropped.items()}
    model.n_coordinates_ = coords.n
    model.n_samples_ = 0
    model.forced_coordinates_ = np.asarray(forced, dtype=bool)
    model.inclusion_probability_, model.coef_interval_ = probability, interval
    model._build_dynamics()
    return model
