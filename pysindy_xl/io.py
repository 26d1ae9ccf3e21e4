"""JSON persistence of identified models.

The file holds the coordinate names, the catalog specification (terms in the grammar of
:mod:`pysindy_xl.expressions`), the coefficients, the optimizer's and the model's plain
parameters and the fit's diagnostics. Loading checks every field and executes nothing (no
pickle, ``eval`` or ``sympify``); the library and optimizer types named are looked up among the
registered ones (:data:`~pysindy_xl.feature_library.LIBRARY_TYPES`,
:data:`~pysindy_xl.optimizers.OPTIMIZER_TYPES`). Non-finite numbers are written as strings.
"""

from __future__ import annotations

import dataclasses
import inspect
import json
import math
import os
import warnings

import numpy as np

from .feature_library import CatalogRepartition, SpecError, SpecReader
from .optimizers import OPTIMIZER_TYPES, optimizer_from_spec
from .registry import is_plain
from .symbols import Coordinates

__all__ = ["save_model", "read_model_file", "ModelFile", "FORMAT", "VERSION",
           "OPTIMIZER_TYPES"]

FORMAT = "pysindy-xl-model"
VERSION = 1
_MAX_BYTES = 50_000_000


@dataclasses.dataclass
class ModelFile:
    """The checked contents of a model file, as :func:`read_model_file` returns them.

    Parameters
    ----------
    settings : dict
        The estimator's parameters other than the library and the optimizer.
    feature_library : CatalogRepartition
        The fitted catalog.
    optimizer : object or None
        The optimizer (its parameters), or None when the estimator had none.
    fitted : dict
        The fitted attributes (``coef_``, ``n_coordinates_``...) by name.

    Examples
    --------
    See :func:`read_model_file`.
    """

    settings: dict
    feature_library: CatalogRepartition
    optimizer: object
    fitted: dict


def save_model(model, path) -> None:
    """Write a fitted :class:`~pysindy_xl.XLSINDy` to ``path`` as JSON.

    The body of :meth:`XLSINDy.save <pysindy_xl.XLSINDy.save>`: the catalog's specification
    (coordinates and terms in the restricted term grammar), the optimizer's type and
    parameters, the estimator's settings and the fitted state; no pickle.

    Parameters
    ----------
    model : XLSINDy
        A fitted model.
    path : str or path-like
        The file to write; its folder must exist.

    Raises
    ------
    sklearn.exceptions.NotFittedError
        When ``model`` is not fitted.

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
        "still_coordinates": [str(name) for name in getattr(model, "still_coordinates_", ())],
        "optimizer": optimizer.to_spec() if hasattr(optimizer, "to_spec") else None,
    }
    if getattr(model, "inclusion_probability_", None) is not None:
        document["uncertainty"] = {
            "inclusion_probability": [float(p) for p in model.inclusion_probability_],
            "coef_interval": [[float(c) for c in bound] for bound in model.coef_interval_]}
    document["settings"] = _settings_spec(model)
    document["training"] = _training_spec(model)
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


def invalid_model_file(path, what: str) -> ValueError:
    """The ``ValueError`` to raise for a file that is not a valid model file.

    Parameters
    ----------
    path : str or path-like
        The file.
    what : str
        What is wrong with it.

    Returns
    -------
    ValueError
        The error, naming the argument ``path`` and the file.
    """
    return ValueError(f"path: {os.fspath(path)!r} is not a valid pysindy-xl model file: {what}")


_fail = invalid_model_file


def _expect(condition: bool, path, what: str):
    if not condition:
        raise _fail(path, what)


def read_model_file(path) -> ModelFile:
    """Read and check a model written by :func:`save_model`.

    The body of :meth:`XLSINDy.load <pysindy_xl.XLSINDy.load>`: the file's size is bounded,
    terms are parsed by the restricted grammar (:func:`~pysindy_xl.expressions.parse_expression`)
    and only registered library and optimizer types are built.

    Parameters
    ----------
    path : str or path-like
        The JSON file.

    Returns
    -------
    ModelFile
        The checked settings, library, optimizer and fitted attributes.

    Raises
    ------
    ValueError
        When the file is not a valid model file, saying what is wrong.

    Examples
    --------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "bad.json")
    >>> _ = open(path, "w").write('{"format": "something else"}')
    >>> read_model_file(path)
    Traceback (most recent call last):
    ...
    ValueError: path: '...bad.json' is not a valid pysindy-xl model file: 'format' must be ...
    """
    document = _read_document(path)
    names = document.get("coordinates")
    _expect(isinstance(names, list) and all(isinstance(n, str) for n in names), path,
            "'coordinates' must be a list of names")
    try:
        coords = Coordinates(names)
    except (TypeError, ValueError) as err:
        raise _fail(path, str(err)) from None
    library = _library_from_document(document, coords, path)
    feature_names = library.get_feature_names()
    _expect(document.get("feature_names") == feature_names, path,
            "feature_names do not match the catalog")
    coef = document.get("coefficients")
    _expect(isinstance(coef, list) and len(coef) == len(feature_names)
            and all(isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c)
                    for c in coef), path,
            "'coefficients' must be one number per feature, all finite")
    forced = document.get("forced_coordinates", [True] * coords.n)
    _expect(isinstance(forced, list) and len(forced) == coords.n
            and all(isinstance(f, bool) for f in forced), path,
            "'forced_coordinates' must have one flag (true or false) per coordinate")
    still = document.get("still_coordinates", [])
    _expect(isinstance(still, list) and len(set(still)) == len(still)
            and all(isinstance(name, str) and name in coords.names for name in still), path,
            "'still_coordinates' must be a list of distinct coordinate names")
    dropped = document.get("dropped_features", {})
    _expect(isinstance(dropped, dict), path, "'dropped_features' must be an object")
    spec = document.get("optimizer")
    try:
        optimizer = None if spec is None else optimizer_from_spec(spec)
    except ValueError as err:
        raise _fail(path, str(err)) from None
    probability, interval = _uncertainty_from_document(document, len(feature_names), path)
    fitted = {"feature_library_": library,
              "optimizer_": optimizer,
              "coef_": np.asarray(coef, dtype=float),
              "dropped_features_": {str(k): str(v) for k, v in dropped.items()},
              "n_coordinates_": coords.n,
              "forced_coordinates_": np.asarray(forced, dtype=bool),
              "still_coordinates_": list(still),
              "inclusion_probability_": probability,
              "coef_interval_": interval,
              **_training_from_document(document.get("training"), len(feature_names), path)}
    return ModelFile(_settings_from_document(document, path), library, optimizer, fitted)


def _read_document(path) -> dict:
    """The JSON object of a model file of this format and version."""
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
    return document


def _library_from_document(document, coords, path) -> CatalogRepartition:
    """The file's catalog, read by the registered library types and fitted."""
    try:
        library = SpecReader(coords).library(document.get("feature_library"))
    except SpecError as err:
        raise _fail(path, str(err)) from None
    if not isinstance(library, CatalogRepartition):
        library = CatalogRepartition([library])
    try:
        library.fit()
    except (RecursionError, OverflowError):
        raise _fail(path, "catalog: the terms are too complex to differentiate") from None
    except (TypeError, ValueError) as err:
        raise _fail(path, f"catalog: {err}") from None
    return library


#: XLSINDy parameters that are plain values, and the objects saved as a type and plain params
_PLAIN_SETTINGS = ("drop_dependent", "formulation", "t_default", "blas_threads",
                   "residual_covariance", "hold_still")
_OBJECT_SETTINGS = ("test_functions", "smoother", "differentiation_method")
_NON_FINITE = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}


def _setting_types(name):
    """The classes a file may name for an object setting (documented ones only)."""
    if name == "differentiation_method":
        import pysindy.differentiation as differentiation
        base = differentiation.BaseDifferentiation
        return {k: v for k, v in vars(differentiation).items()
                if isinstance(v, type) and issubclass(v, base) and v is not base}
    from .weak import BumpTestFunctions, WhittakerSmoother
    return {"test_functions": {"BumpTestFunctions": BumpTestFunctions},
            "smoother": {"WhittakerSmoother": WhittakerSmoother}}[name]


def _init_params(value) -> dict:
    """The constructor parameters of an object, as they are set on it (not its fitted state)."""
    if hasattr(value, "get_params"):
        return value.get_params(deep=False)
    names = [name for name, p in inspect.signature(type(value).__init__).parameters.items()
             if name != "self" and p.kind is p.POSITIONAL_OR_KEYWORD]
    return {name: getattr(value, name, None) for name in names}


def _settings_spec(model) -> dict:
    """The model's parameters: plain ones as they are, objects as ``{"type", "params"}`` (or
    left out with a warning when they cannot be: the loaded model uses the default)."""
    settings = {key: getattr(model, key) for key in _PLAIN_SETTINGS}
    for key in _OBJECT_SETTINGS:
        value = getattr(model, key)
        if value is None:
            settings[key] = None
            continue
        name = type(value).__name__
        params = _init_params(value)
        if _setting_types(key).get(name) is type(value) and all(map(is_plain, params.values())):
            settings[key] = {"type": name, "params": params}
        else:
            settings[key] = None
            warnings.warn(f"{key}: {name} cannot be saved as plain JSON; the loaded model "
                          "will use the default", UserWarning, stacklevel=4)
    return settings


def _settings_from_document(document, path) -> dict:
    """The XLSINDy parameters a file names, checked (empty when absent)."""
    spec = document.get("settings", {})
    _expect(isinstance(spec, dict) and set(spec) <= set(_PLAIN_SETTINGS + _OBJECT_SETTINGS),
            path, f"'settings' must be an object with keys among "
                  f"{sorted(_PLAIN_SETTINGS + _OBJECT_SETTINGS)}")
    settings = {}
    for key, value in spec.items():
        if key in _PLAIN_SETTINGS:
            _expect(is_plain(value), path, f"settings.{key} must be a plain value")
            settings[key] = value
        elif value is not None:
            types = _setting_types(key)
            _expect(isinstance(value, dict) and isinstance(value.get("type"), str)
                    and value["type"] in types
                    and isinstance(value.get("params"), dict)
                    and all(map(is_plain, value["params"].values())), path,
                    f"settings.{key} must be null or {{'type': one of {sorted(types)}, "
                    "'params': plain values}")
            try:
                settings[key] = types[value["type"]](**value["params"])
                getattr(settings[key], "_check_params", lambda: None)()
            except (TypeError, ValueError, AttributeError) as err:
                raise _fail(path, f"settings.{key}: {err}") from None
    return settings


def _floats(values) -> list:
    """Numbers for JSON: non-finite ones as the strings "inf", "-inf", "nan"."""
    return [float(v) if math.isfinite(v) else ("nan" if math.isnan(v) else
                                               "inf" if v > 0 else "-inf")
            for v in np.asarray(values, dtype=float).ravel()]


def _floats_from(values, path, where) -> np.ndarray:
    _expect(isinstance(values, list) and all(
        (isinstance(v, (int, float)) and not isinstance(v, bool))
        or (isinstance(v, str) and v in _NON_FINITE)
        for v in values), path, f"{where} must be a list of numbers")
    return np.array([_NON_FINITE[v] if isinstance(v, str) else v for v in values], dtype=float)


def _selection_types():
    from .optimizers.homogeneous import LawSelection
    from .optimizers.selection import SelectionResult
    return {"SelectionResult": SelectionResult, "LawSelection": LawSelection}


def _field_json(name, value):
    """A selection field for JSON: text, integers, or numbers (:func:`_floats`)."""
    if isinstance(value, str):
        return value
    if np.ndim(value) == 0:
        return int(value)
    return [int(v) for v in value] if name == "order" else _floats(value)


def _training_spec(model) -> dict:
    """The fit's diagnostics for JSON."""
    info = getattr(model, "weak_info_", None)
    selection = getattr(model, "selection_", None)
    check = getattr(model, "mass_matrix_check_", None)
    names = {kind: name for name, kind in _selection_types().items()}
    if type(selection) in names:
        selection = {"type": names[type(selection)],
                     "fields": {field.name: _field_json(field.name, getattr(selection, field.name))
                                for field in dataclasses.fields(selection)}}
    else:
        selection = None
    return {"formulation": getattr(model, "formulation_", None),
            "n_samples": int(getattr(model, "n_samples_", 0)),
            "weak_info": None if info is None else {
                "half_width": float(info["half_width"]),
                "test_functions": [int(k) for k in info["test_functions"]],
                "noise": None if info["noise"] is None else _floats(info["noise"])},
            "selection": selection,
            "mass_matrix_check": None if check is None else {
                key: _floats([value])[0] for key, value in check.items()},
            "physical_consistency": _consistency_json(getattr(model, "physical_consistency_",
                                                              None))}


_CONSISTENCY_KEYS = ("consistent", "cost", "negative_friction", "min_pseudo_inertia_eigenvalue")


def _consistency_json(report):
    """``physical_consistency_`` for JSON (None when the fit did not check it)."""
    if report is None:
        return None
    return {"consistent": bool(report["consistent"]), "cost": _floats([report["cost"]])[0],
            "negative_friction": [str(name) for name in report["negative_friction"]],
            "min_pseudo_inertia_eigenvalue": _floats([report["min_pseudo_inertia_eigenvalue"]])[0]}


def _consistency_from_document(report, path):
    """The ``physical_consistency_`` a file holds, every field checked, or None."""
    if report is None:
        return None
    where = "training.physical_consistency"
    _expect(isinstance(report, dict) and set(report) == set(_CONSISTENCY_KEYS), path,
            f"{where} must hold {_CONSISTENCY_KEYS}")
    _expect(isinstance(report["consistent"], bool), path, f"{where}.consistent must be a bool")
    names = report["negative_friction"]
    _expect(isinstance(names, list) and all(isinstance(n, str) for n in names), path,
            f"{where}.negative_friction must be a list of feature names")
    cost, eigenvalue = _floats_from([report["cost"], report["min_pseudo_inertia_eigenvalue"]],
                                    path, where)
    return {"consistent": report["consistent"], "cost": float(cost),
            "negative_friction": list(names), "min_pseudo_inertia_eigenvalue": float(eigenvalue)}


def _training_from_document(spec, n_features, path) -> dict:
    """The fit's diagnostics in a file, checked, as fitted attributes (None when absent)."""
    spec = {} if spec is None else spec
    _expect(isinstance(spec, dict), path, "'training' must be an object")
    formulation = spec.get("formulation")
    _expect(formulation in (None, "strong", "weak"), path,
            "training.formulation must be 'strong', 'weak' or null")
    n_samples = spec.get("n_samples", 0)
    _expect(isinstance(n_samples, int) and not isinstance(n_samples, bool) and n_samples >= 0,
            path, "training.n_samples must be a non-negative integer")
    info = spec.get("weak_info")
    if info is not None:
        _expect(isinstance(info, dict) and set(info) == {"half_width", "test_functions",
                                                          "noise"}, path,
                "training.weak_info must hold half_width, test_functions and noise")
        half_width = _floats_from([info["half_width"]], path, "training.weak_info.half_width")
        _expect(0 < half_width[0] < math.inf, path,
                "training.weak_info.half_width must be positive")
        counts = info["test_functions"]
        _expect(isinstance(counts, list) and all(
            isinstance(k, int) and not isinstance(k, bool) and k > 0 for k in counts),
                path, "training.weak_info.test_functions must be positive integers")
        noise = info["noise"]
        info = {"half_width": float(half_width[0]), "test_functions": counts,
                "noise": None if noise is None else
                _floats_from(noise, path, "training.weak_info.noise").tolist()}
    check = spec.get("mass_matrix_check")
    if check is not None:
        keys = ("positive_definite_fraction", "median_condition")
        _expect(isinstance(check, dict) and set(check) == set(keys), path,
                f"training.mass_matrix_check must hold {keys}")
        check = dict(zip(keys, _floats_from([check[k] for k in keys], path,
                                            "training.mass_matrix_check").tolist(), strict=True))
    return {"formulation_": formulation, "n_samples_": n_samples, "weak_info_": info,
            "selection_": _selection_from_spec(spec.get("selection"), n_features, path),
            "mass_matrix_check_": check,
            "physical_consistency_": _consistency_from_document(
                spec.get("physical_consistency"), path)}


def _selection_from_spec(selection, n_features, path):
    """The ``SelectionResult`` or ``LawSelection`` a file holds, every field checked, or None."""
    if selection is None:
        return None
    types = _selection_types()
    _expect(isinstance(selection, dict) and isinstance(selection.get("type"), str)
            and selection["type"] in types
            and isinstance(selection.get("fields"), dict), path,
            f"training.selection must be null or {{'type': one of {sorted(types)}, "
            "'fields': ...}")
    kind = types[selection["type"]]
    fields, values = selection["fields"], {}
    names = [f.name for f in dataclasses.fields(kind)]
    _expect(set(fields) == set(names), path, f"training.selection.fields must be {names}")
    for name in names:
        value, where = fields[name], f"training.selection.{name}"
        if name == "rule":
            _expect(isinstance(value, str), path, f"{where} must be a string")
        elif name in ("size", "best_size"):
            _expect(isinstance(value, int) and not isinstance(value, bool)
                    and 0 <= value <= n_features, path,
                    f"{where} must be an integer in [0, {n_features}]")
        elif name == "order":
            _expect(isinstance(value, list) and all(
                isinstance(j, int) and not isinstance(j, bool) and 0 <= j < n_features
                for j in value), path, f"{where} must be feature indices")
            value = np.asarray(value, dtype=int)
        else:
            value = _floats_from(value, path, where)
        values[name] = value
    _expect(all(len(v) >= values["size"] for v in values.values()
                if isinstance(v, np.ndarray)), path,
            "training.selection: the arrays must cover the chosen size")
    return kind(**values)
