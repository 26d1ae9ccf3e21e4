"""Probe of the unforced law search (``optimizers.homogeneous.select_law``) on one case.

Fits the case's hand-built catalog as the growth's search does (``share_probe.search_like``:
its splits, test functions, template) and saves, for every split, the law search's inputs
(``select_laws``' arguments) and the catalog's term names to an ``.npz`` per split, for the
analysis in ``law_paths_analysis.py``.

    PYTHONPATH=$PWD python benchmarks/law_paths_probe.py half_car:unforced:0.01:0 --out /tmp/lp
"""
from __future__ import annotations

import argparse
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

import generic_systems as gs  # noqa: E402
import share_probe  # noqa: E402
from sklearn.base import clone  # noqa: E402

from pysindy_xl.catalog import AutomaticCatalog  # noqa: E402
from pysindy_xl.optimizers import implicit  # noqa: E402

CAPTURED = []


def _capturing(original):
    def wrapper(theta, moments, n_blocks, mass_matrices=None, max_ratio_factor=10.0,
                noise_draws=None):
        CAPTURED.append({"theta": theta, "moments": moments, "n_blocks": n_blocks,
                         "mass_matrices": mass_matrices, "draws": noise_draws})
        return original(theta, moments, n_blocks, mass_matrices, max_ratio_factor, noise_draws)
    return wrapper


def table_of(name):
    if name == "blind2":
        import blind2_systems as table
    elif name == "unseen":
        import unseen_systems as table
    else:
        table = gs
    return table


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("case")
    parser.add_argument("--table", default="blind2", choices=["blind2", "generic", "unseen"])
    parser.add_argument("--out", default="/tmp/lp")
    parser.add_argument("--all-data", action="store_true",
                        help="fit on all the data (as share_probe's reference fit), not the splits")
    args = parser.parse_args()
    system, truth, forced, (runs, test, xs, ts, us) = gs.case_of(
        args.case, table_of(args.table).systems())
    names = list(system["coords"].names)
    implicit.select_laws = _capturing(implicit.select_laws)
    tag = args.case.replace(":", "_")
    if args.all_data:
        import pysindy_xl as px
        from pysindy_xl.catalog.growth_data import END_PERCENTILE
        low, high = np.percentile(np.vstack(xs), [END_PERCENTILE, 100 - END_PERCENTILE], axis=0)
        catalog = AutomaticCatalog(names, kinds=system["kinds"], bounds=list(zip(
            low.tolist(), high.tolist(), strict=True)), **system["hand"])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = px.XLSINDy(catalog).fit(xs, ts, u=us)
        features = list(model.get_feature_names())
        print(f"all data: {len(CAPTURED)} law searches, kept",
              [f for f, c in zip(features, model.coefficients(), strict=True) if c != 0])
        for k, entry in enumerate(CAPTURED):
            np.savez(os.path.join(args.out, f"{tag}_all{k}.npz"), features=np.array(features),
                     n_blocks=entry["n_blocks"],
                     **{key: entry[key] for key in ("theta", "moments", "mass_matrices", "draws")
                        if entry[key] is not None})
        return
    search = share_probe.search_like(xs, ts, names, system["kinds"])
    for k, split in enumerate(search.splits):
        CAPTURED.clear()
        cpu = time.process_time()
        model = clone(search.template).set_params(
            feature_library=AutomaticCatalog(**split.fixed, **system["hand"]))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model.fit(**split.train)
        features = list(model.get_feature_names())
        kept = [f for f, c in zip(features, model.coefficients(), strict=True) if c != 0]
        print(f"split {k}: {len(CAPTURED)} law searches, kept {len(kept)}: {kept} "
              f"({time.process_time() - cpu:.1f} CPU s)")
        entry = CAPTURED[-1]
        np.savez(os.path.join(args.out, f"{tag}_split{k}.npz"), features=np.array(features),
                 kept=np.array(kept), n_blocks=entry["n_blocks"],
                 **{key: entry[key] for key in ("theta", "moments", "mass_matrices", "draws")
                    if entry[key] is not None})


if __name__ == "__main__":
    main()
