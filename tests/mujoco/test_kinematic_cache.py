"""The on-disk cache of kinematic-catalog derivations: hits, invalidation, unwritable places.

A hit is proven by the derivation being unavailable (it raises) while the catalog is still
built; what a hit returns is checked against a fresh derivation and, after a change of the
masses (same kinematics: a hit), against MuJoCo's own mass matrix (``mj_fullM``).
"""

import os

import mujoco
import numpy as np
import pytest
from kinematic_models import SPATIAL_ARM

from pysindy_xl.mujoco import MJCFSystem
from pysindy_xl.mujoco.catalogs import _derivation_cache, kinematic
from pysindy_xl.mujoco.catalogs.kinematic import kinematic_catalog


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("PYSINDY_XL_CACHE", str(folder))
    kinematic._CACHE.clear()  # the in-memory cache would answer first
    yield folder
    kinematic._CACHE.clear()


def _no_derivation(monkeypatch):
    def fail(*args, **kwargs):
        raise AssertionError("derived although cached")

    monkeypatch.setattr(kinematic, "derive_lagrangian", fail)


def _files(folder):
    return sorted(p.name for p in folder.glob("*")) if folder.exists() else []


def _same(a, b):
    assert a.lagrange_terms.names() == b.lagrange_terms.names()
    np.testing.assert_array_equal(a.combination, b.combination)
    assert a.parameters == b.parameters and a.physical_names == b.physical_names
    for column_a, column_b in zip(a.lagrange_terms.columns, b.lagrange_terms.columns,
                                  strict=True):
        for p, q in zip(column_a, column_b, strict=True):
            np.testing.assert_array_equal(p.exponents, q.exponents)
            np.testing.assert_array_equal(p.coefficients, q.coefficients)


def test_a_second_derivation_is_read_back_identical(cache, monkeypatch):
    first = kinematic_catalog(SPATIAL_ARM)
    assert len(_files(cache)) == 1 and _files(cache)[0].endswith(".npz")
    kinematic._CACHE.clear()
    _no_derivation(monkeypatch)
    second = kinematic_catalog(SPATIAL_ARM)
    _same(first, second)
    np.testing.assert_array_equal(first.base_parameters, second.base_parameters)
    # the names stored with the derivation are sympy's str of the terms
    assert second.lagrange_terms.names() == [str(term) for term in second.lagrange_terms]


def test_other_masses_hit_other_kinematics_or_code_miss(cache, monkeypatch):
    kinematic_catalog(SPATIAL_ARM)
    kinematic._CACHE.clear()
    heavier = SPATIAL_ARM.replace('mass="1.0"', 'mass="3.0"')
    moved = SPATIAL_ARM.replace('axis="0.3 1 0"', 'axis="0.3 1 0.1"')
    with monkeypatch.context() as patch:
        _no_derivation(patch)
        catalog = kinematic_catalog(MJCFSystem(heavier))  # same kinematics: read back
        with pytest.raises(AssertionError, match="derived although cached"):
            kinematic_catalog(moved)
        kinematic._CACHE.clear()  # other deriving code: other keys
        patch.setattr(_derivation_cache, "_code_digest", lambda: "another version")
        with pytest.raises(AssertionError, match="derived although cached"):
            kinematic_catalog(MJCFSystem(heavier))
    # the base parameters of the read-back derivation are those of the heavier arm
    model = mujoco.MjModel.from_xml_string(heavier)
    data = mujoco.MjData(model)
    for q in np.random.default_rng(0).uniform(-2, 2, (3, model.nq)):
        data.qpos[:] = q
        mujoco.mj_forward(model, data)
        truth = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, truth)
        np.testing.assert_allclose(catalog.mass_matrix(q), truth, rtol=1e-9, atol=1e-12)
    kinematic._CACHE.clear()
    kinematic_catalog(moved)
    assert len(_files(cache)) == 2


def test_a_damaged_file_is_a_miss_and_is_replaced(cache):
    reference = kinematic_catalog(SPATIAL_ARM)
    (path,) = cache.glob("*.npz")
    whole = path.read_bytes()
    for damaged in (b"not an npz file", whole[:len(whole) // 2]):
        path.write_bytes(damaged)
        kinematic._CACHE.clear()
        _same(kinematic_catalog(SPATIAL_ARM), reference)
        assert path.read_bytes() == whole


def test_off_and_unwritable_places_derive_without_failing(tmp_path, monkeypatch, cache):
    reference = kinematic_catalog(SPATIAL_ARM)
    blocker = tmp_path / "a file"
    blocker.write_text("not a directory")
    for setting in ("off", str(blocker / "cache")):  # a directory that cannot be created
        monkeypatch.setenv("PYSINDY_XL_CACHE", setting)
        kinematic._CACHE.clear()
        _same(kinematic_catalog(SPATIAL_ARM), reference)
    if os.geteuid() != 0:  # a read-only directory (the superuser writes anyway)
        readonly = tmp_path / "readonly"
        readonly.mkdir(mode=0o500)
        monkeypatch.setenv("PYSINDY_XL_CACHE", str(readonly))
        kinematic._CACHE.clear()
        _same(kinematic_catalog(SPATIAL_ARM), reference)
        assert _files(readonly) == []
    assert not (blocker / "cache").exists() and blocker.read_text() == "not a directory"
