"""An on-disk cache of kinematic-catalog derivations, keyed by the model's kinematic content.

A catalog's derivation (every body's trigonometric polynomials, their Euler-Lagrange columns,
the reduction to base parameters) depends on the kinematic tree alone: offsets, orientations,
joints' types, axes, anchors and references, gravity, coordinates, names and seed; never on
masses, inertias or armatures. Stored by :mod:`pysindy_xl._disk_cache`, named by a digest of
that content, the deriving code, numpy's and MuJoCo's versions and the file format.
"""

from __future__ import annotations

import functools
import hashlib
import os

import numpy as np

from ... import _disk_cache
from ..._disk_cache import directory
from ..._optional import import_mujoco
from ...feature_library import trigpoly
from ...feature_library.trigpoly import TrigPolynomial

__all__ = ["directory", "key", "load", "save"]

_FORMAT = 3  # bump when the stored arrays change
_KIND = "kinematic"
_SOURCES = ("kinematic.py", "_kinematic_tree.py", "_kinematic_build.py", "_derivation_cache.py")


@functools.cache
def _code_digest() -> str | None:
    """A digest of the code that derives catalogs (a change of it is a new key)."""
    here = os.path.dirname(os.path.abspath(__file__))
    polynomials = os.path.dirname(os.path.abspath(trigpoly.__file__))
    digest = _disk_cache.source_digest(
        [os.path.join(polynomials, name) for name in ("trigpoly.py", "_monomials.py",
                                                       "trigterms.py")]
        + [os.path.join(here, name) for name in _SOURCES],
        _FORMAT, import_mujoco().__version__)
    return None if digest is None else digest.hexdigest()


def key(system, model, names, seed) -> str | None:
    """The digest of what a derivation depends on (None: not cacheable)."""
    code = _code_digest()
    if code is None:
        return None
    digest = hashlib.sha256(code.encode())
    digest.update(repr((tuple(names), tuple(system.joint_names), tuple(system.coordinate_names),
                        sorted(system.angle_coordinates), int(seed))).encode())
    _disk_cache.add_arrays(digest, (
        model.body_parentid, model.body_pos, model.body_quat, model.body_jntnum,
        model.body_jntadr, model.jnt_type, model.jnt_axis, model.jnt_pos, model.jnt_qposadr,
        model.jnt_dofadr, model.qpos0, model.opt.gravity, system.joint_to_coordinates))
    return digest.hexdigest()


def _stacked(polynomials, prefix):
    return {f"{prefix}_exponents": np.vstack([p.exponents for p in polynomials]).astype(np.uint8),
            f"{prefix}_coefficients": np.concatenate([p.coefficients for p in polynomials]),
            f"{prefix}_lengths": np.array([len(p.coefficients) for p in polynomials])}


def _unstacked(data, prefix, angles):
    bounds = np.cumsum(np.append(0, data[f"{prefix}_lengths"])).tolist()
    exponents = data[f"{prefix}_exponents"].astype(np.int16)
    coefficients = data[f"{prefix}_coefficients"]
    return [TrigPolynomial(exponents[a:b], coefficients[a:b], angles, normalize=False)
            for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def _encoded(strings, prefix):
    """Strings as one UTF-8 byte array and their lengths (a fixed-width string array pads
    every name to the longest, and a term's name can run to a million characters)."""
    encoded = [text.encode() for text in strings]
    return {f"{prefix}_bytes": np.frombuffer(b"".join(encoded), dtype=np.uint8),
            f"{prefix}_lengths": np.array([len(b) for b in encoded], dtype=np.int64)}


def _decoded(data, prefix):
    joined = data[f"{prefix}_bytes"].tobytes()
    bounds = np.cumsum(np.append(0, data[f"{prefix}_lengths"])).tolist()
    return [joined[a:b].decode() for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def save(digest, derived) -> None:
    """Store a derivation (see :func:`load`); nothing happens where it cannot be written."""
    terms = derived["terms"]
    if directory() is None or digest is None or not terms or any(
            p.exponents.max(initial=0) > 255 for p in terms):
        return
    columns = [p for column in derived["columns"] for p in column]
    _disk_cache.write_arrays(_KIND, digest, {
        "format": np.array(_FORMAT), "bodies": np.asarray(derived["bodies"]),
        "names": np.array(derived["names"], dtype=str),
        **_encoded(derived["term_names"], "term_names"),
        "combination": derived["combination"], "n_candidates": np.array(derived["n_candidates"]),
        **_stacked(terms, "terms"), **_stacked(columns, "columns")})


def load(digest, angles) -> dict | None:
    """The derivation stored under ``digest``: ``bodies`` (moving body ids), ``names``
    (physical parameters), ``terms`` (kept polynomials), ``term_names`` (their ``str``),
    ``columns`` (their Euler-Lagrange columns), ``combination``, ``n_candidates``; None if
    absent, off or unreadable."""
    n = len(angles)
    data = None if digest is None else _disk_cache.read_arrays(_KIND, digest)
    if data is None or int(data.get("format", -1)) != _FORMAT:
        return None
    try:
        terms = _unstacked(data, "terms", angles)
        columns = _unstacked(data, "columns", angles)
        derived = {"bodies": data["bodies"].tolist(), "names": data["names"].tolist(),
                   "combination": data["combination"].astype(float),
                   "n_candidates": int(data["n_candidates"]), "terms": terms,
                   "term_names": _decoded(data, "term_names"),
                   "columns": [columns[k * n:(k + 1) * n] for k in range(len(terms))]}
    except (KeyError, ValueError, UnicodeDecodeError):
        return None
    return derived if len(columns) == n * len(terms) else None
