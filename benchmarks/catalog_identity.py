"""Kinematic catalogs and fits before and after a change of their derivation: identical?

Writes (``--write PATH``) or compares with (``--compare PATH``) an NPZ reference holding, for
each system, the catalog's term names, base-parameter combination and kept terms' maps, the
library's feature names and Euler-Lagrange column values at fixed states, and the coefficients
of ``XLSINDy(catalog.library()).fit`` on a MuJoCo dataset. Run ``--write`` with the code before
the change (e.g. ``PYTHONPATH=/path/to/main``) and ``--compare`` after it; the comparison
prints the largest relative coefficient difference per system and fails above ``--rtol``.

Usage: ``python benchmarks/catalog_identity.py --write before.npz`` then
``python benchmarks/catalog_identity.py --compare before.npz``.
"""

import argparse
import json
import os
import sys
import warnings

import numpy as np

import pysindy_xl as px
from pysindy_xl.feature_library import stack_variables
from pysindy_xl.mujoco import MJCFSystem, generate_dataset

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "tests"))
import kinematic_models  # noqa: E402
from robot_arms import arm_mjcf  # noqa: E402

# (name, MJCF or registry name, force amplitude, fit samples per trajectory)
SYSTEMS = [
    ("cart-pole", "cart-pole", None, 400),
    ("planar-arm", kinematic_models.PLANAR_ARM, 4.0, 400),
    ("spatial-arm", kinematic_models.SPATIAL_ARM, 3.0, 400),
    ("cart-two-link", kinematic_models.CART_DOUBLE_PENDULUM, 3.0, 400),
    ("robot-arm-5", kinematic_models.robot_arm(5), 1.0, 400),
    ("panda", arm_mjcf("panda"), 1.0, 1650),
    # a real arm (non-axis-aligned joint frames), fitted on the first 1,650 samples of its log
    ("kinova-gen3", os.path.join(HERE, "data", "real", "gen3.urdf"), 1.0, "log"),
]


def system_of(source, amplitude):
    if amplitude is None:
        return px.mujoco.get_system(source)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Kinova URDF's impossible inertias, balanced
        return MJCFSystem(source, force_amplitude=amplitude)


def record(name, source, amplitude, samples):
    system = system_of(source, amplitude)
    catalog = px.kinematic_catalog(system)
    library = catalog.library().fit()
    rng = np.random.default_rng(1)
    n = system.n
    q, qd, qdd, tau = rng.normal(size=(4, 50, n))
    columns = library.transform(stack_variables(q, qd, qdd, tau))
    if samples == "log":
        import real_robots

        (t, q, tau), _, _ = real_robots.kinova()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = px.XLSINDy(catalog.library()).fit(q[:1650], t[:1650], u=tau[:1650])
    else:
        step = system.mj_model().opt.timestep
        data = generate_dataset(system, n_trajectories=2, duration=samples * step, seed=0,
                                progress=False)
        model = px.XLSINDy(catalog.library()).fit(**data.fit_arguments(forces="tau"))
    return {
        f"{name}/terms": np.array(json.dumps([str(t) for t in catalog.lagrange_terms])),
        f"{name}/parameters": np.array(json.dumps(catalog.parameters)),
        f"{name}/combination": catalog.combination,
        f"{name}/feature_names": np.array(json.dumps(library.get_feature_names())),
        f"{name}/columns": columns,
        f"{name}/coefficients": np.asarray(model.coefficients()),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--write", help="write the reference NPZ here")
    group.add_argument("--compare", help="compare with this reference NPZ")
    parser.add_argument("--rtol", type=float, default=1e-12)
    parser.add_argument("--systems", nargs="*", default=None)
    args = parser.parse_args()
    out = {}
    for name, source, amplitude, samples in SYSTEMS:
        if args.systems and name not in args.systems:
            continue
        out.update(record(name, source, amplitude, samples))
        print(name, "done", flush=True)
    if args.write:
        np.savez(args.write, **out)
        return
    reference = np.load(args.compare, allow_pickle=False)
    failed = False
    for key, value in out.items():
        old = reference[key]
        if value.dtype.kind in "US":
            same = str(old) == str(value)
            print(f"{key}: {'identical' if same else 'DIFFERENT'}")
            failed |= not same
            continue
        scale = np.maximum(np.abs(old), np.abs(old).max() * 1e-300 + 1e-300)
        rel = float(np.max(np.abs(value - old) / scale)) if old.size else 0.0
        bitwise = bool(np.array_equal(old, value))
        print(f"{key}: max relative difference {rel:.2e}{' (bit-identical)' if bitwise else ''}")
        failed |= not rel <= args.rtol or old.shape != value.shape
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
