"""Probe of the share rule (``optimizers.laws.explained_coordinates``) on one case.

Fits the case's hand-built catalog as the growth's search does (its splits, test functions,
template) and on all the data, and logs every call of the share rule inside the law
selection: the law's size, each block's share of the largest, the verdict.

    PYTHONPATH=$PWD python benchmarks/share_probe.py half_car:unforced:0.01:0 --table blind2
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

import pysindy_xl as px  # noqa: E402
from pysindy_xl.catalog import candidates as cand  # noqa: E402
from pysindy_xl.catalog.folds import held_out_splits  # noqa: E402
from pysindy_xl.catalog.growth_data import data_span  # noqa: E402
from pysindy_xl.optimizers import homogeneous, laws  # noqa: E402
from pysindy_xl.optimizers.problem import coordinate_weights, scale_blocks  # noqa: E402

LOG = []


def _logged(original):
    def wrapper(theta, law, n_blocks, *args, **kwargs):
        verdict = original(theta, law, n_blocks, *args, **kwargs)
        support = np.flatnonzero(law)
        columns = np.asarray(theta, dtype=float)[:, support]
        own = scale_blocks(columns, coordinate_weights(columns, n_blocks))
        shares = [np.sum((c * law[support]).reshape(n_blocks, -1, support.size) ** 2,
                         axis=(1, 2)) for c in (columns, own)]
        LOG.append((support.size, [s / max(s.max(), 1e-300) for s in shares], verdict.copy()))
        return verdict
    return wrapper


def search_like(xs, ts, names, kinds, n_blocks=5, search_samples=6000):
    """The growth's search data (as grow_catalog builds it, unforced, default options)."""
    from pysindy_xl.fit import RememberedSmoother
    from pysindy_xl.weak import BumpTestFunctions
    fixed = {"coordinates": names, "kinds": list(kinds), "max_terms": 400,
             "bounds": data_span(xs),
             "coulomb_scale": max(1e-3, 0.02 * float(np.mean(
                 [np.std(np.gradient(x, t, axis=0), axis=0).mean()
                  for x, t in zip(xs, ts, strict=True)])))}
    total = sum(len(t) for t in ts)
    stride = max(1, int(np.ceil(total / search_samples)))
    arrays = {"x": xs, "t": ts, "u": None, "x_dot": None, "x_ddot": None}
    block = min(len(t) for t in ts) // n_blocks
    longest = int(np.argmax([len(t) for t in ts]))
    width = min(BumpTestFunctions().half_width(ts[longest], xs[longest]),
                min(t[block - 1] - t[0] for t in ts) / 3)
    splits, reported = held_out_splits(arrays, n_blocks, stride, False, "block", margin=width)
    template = px.XLSINDy(test_functions=BumpTestFunctions(width=width),
                          smoother=RememberedSmoother())
    return cand.SearchData([cand.SearchSplit(dict(fixed, bounds=data_span(train["x"])), train,
                                             held) for train, held in splits],
                           template, 400, False, reported, floor="off")


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("case")
    parser.add_argument("--table", default="blind2", choices=["blind2", "generic", "unseen"])
    args = parser.parse_args()
    if args.table == "blind2":
        import blind2_systems as table
    elif args.table == "unseen":
        import unseen_systems as table
    else:
        table = gs
    system, truth, forced, (runs, test, xs, ts, us) = gs.case_of(args.case, table.systems())
    names = list(system["coords"].names)
    homogeneous.explained_coordinates = _logged(laws.explained_coordinates)
    search = search_like(xs, ts, names, system["kinds"])
    cpu = time.process_time()
    result = cand.evaluate_candidate(search, dict(system["hand"]))
    print(f"search fits of the hand-built catalog: criterion {result['criterion']:.4g}, "
          f"definite {result['definite']:.2f}, kept {result['active']}, "
          f"blocks {np.round(result['block_errors'], 4).tolist()} "
          f"({time.process_time() - cpu:.1f} CPU s)")
    _report()
    from pysindy_xl.catalog.growth_data import END_PERCENTILE
    low, high = np.percentile(np.vstack(xs), [END_PERCENTILE, 100 - END_PERCENTILE], axis=0)
    bounds = [(float(a), float(b)) for a, b in zip(low, high, strict=True)]
    catalog = px.AutomaticCatalog(names, kinds=system["kinds"], bounds=bounds, **system["hand"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        hand = px.XLSINDy(catalog).fit(xs, ts, u=us)
    print("hand-built on all the data:", gs.score(*gs._xlsindy_functions(hand), system, truth,
                                                   test, runs, forced))
    _report()


def _report():
    refused = [entry for entry in LOG if not entry[2].all()]
    print(f"  share rule calls {len(LOG)}, refused {len(refused)}")
    for size, (catalog, own), verdict in sorted(LOG, key=lambda e: e[0])[-8:]:
        print(f"  size {size}: shares in the catalog's units {np.round(catalog, 5).tolist()}, "
              f"in the law's own {np.round(own, 5).tolist()}, explained {verdict.tolist()}")
    LOG.clear()


if __name__ == "__main__":
    main()
