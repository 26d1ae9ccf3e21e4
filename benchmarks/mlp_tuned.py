"""A tuned MLP inverse-dynamics baseline on the forced cases of the unseen set.

The MLP of ``generic_systems.py`` (64 x 64, early stopping, scikit-learn's default tolerance) is
not tuned. Here the network is chosen among :data:`CANDIDATES` (that one, and 128 x 128 nets
trained to convergence with Adam or L-BFGS) by the force error on the last fifth of the
training runs when fitted on the first four fifths (the split the PySINDy baselines are tuned
on), then refitted on all the training data and scored as ``generic_systems``' MLP: held-out
force error on the fresh forced run, and off the training box widened by 20 %. The cases and
their data are those of ``unseen_systems.py`` (rebuilt from their seeds). Results are appended
to a JSONL file (finished cases are skipped). Usage::

    PYTHONPATH=$PWD python benchmarks/mlp_tuned.py --seeds 0
    python benchmarks/mlp_tuned.py --summary
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

import generic_systems as gs  # noqa: E402 - the benchmark's machinery
import unseen_systems  # noqa: E402

RESULTS = os.path.join(os.path.dirname(__file__), "results", "unseen_systems_mlp_tuned.jsonl")

#: The networks tried: (hidden layers, L2 penalty alpha, extra MLPRegressor parameters).
CANDIDATES = (
    ((64, 64), 1e-4, {"early_stopping": True, "max_iter": 300}),
    ((128, 128), 1e-5, {"solver": "adam", "max_iter": 3000, "tol": 1e-9,
                        "n_iter_no_change": 100}),
    ((128, 128), 1e-5, {"solver": "lbfgs", "max_iter": 5000, "max_fun": 50000, "tol": 1e-12}),
)


def _network(candidate):
    from sklearn.neural_network import MLPRegressor
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    hidden, alpha, extra = candidate
    return make_pipeline(StandardScaler(), MLPRegressor(hidden_layer_sizes=hidden, alpha=alpha,
                                                        random_state=0, **extra))


def _fit(candidate, features, targets):
    model = _network(candidate).fit(features, targets if targets.shape[1] > 1 else targets[:, 0])
    return lambda x: model.predict(x).reshape(len(x), -1)


def tuned_mlp(truth, data):
    """The tuned MLP's figures on one forced case's ``data`` (as ``gs.case_data`` gives)."""
    runs, test, xs, ts, us = data
    started = time.process_time()
    features = [np.c_[q, qd, qdd] for q, qd, qdd in gs._derivatives(xs, ts)]
    cut = [int(0.8 * len(t)) for t in ts]
    fit_x = np.vstack([f[:c] for f, c in zip(features, cut, strict=True)])[::4]
    fit_y = np.vstack([u[:c] for u, c in zip(us, cut, strict=True)])[::4]
    val_x = np.vstack([f[c:] for f, c in zip(features, cut, strict=True)])
    val_y = np.vstack([u[c:] for u, c in zip(us, cut, strict=True)])
    validation = [gs._relative(_fit(c, fit_x, fit_y)(val_x), val_y) for c in CANDIDATES]
    best = int(np.argmin(validation))
    predict = _fit(CANDIDATES[best], np.vstack(features)[::4], np.vstack(us)[::4])
    box = gs._widened_box(runs, truth.n)
    return {"candidate": best, "validation": validation,
            "held_out": gs._relative(predict(np.c_[test["q"], test["qd"], test["qdd"]]),
                                     test["u"]),
            "off_box": gs._relative(predict(np.c_[box["q"], box["qd"], box["qdd"]]),
                                    truth.forces(box["q"], box["qd"], box["qdd"])),
            "cpu_seconds": time.process_time() - started}


def summary(path):
    """Per noise level: cases, right (held-out <= 2 %, off-box <= 5 %), median held-out and
    off-box (%), the candidates chosen; printed as a markdown table."""
    with open(path, encoding="utf-8") as handle:
        records = [json.loads(line) for line in handle if line.strip()]
    print("| noise | cases | right (held-out, off-box) | median held-out % | "
          "median off-box % | chosen (64x64 / adam / L-BFGS) |")
    print("| --- | --- | --- | --- | --- | --- |")
    for level in sorted({r["noise"] for r in records}):
        group = [r for r in records if r["noise"] == level]
        right = sum(r["held_out"] <= 0.02 and r["off_box"] <= 0.05 for r in group)
        chosen = [sum(r["candidate"] == k for r in group) for k in range(len(CANDIDATES))]
        print(f"| {100 * level:g} % | {len(group)} | {right} | "
              f"{100 * np.median([r['held_out'] for r in group]):.2f} | "
              f"{100 * np.median([r['off_box'] for r in group]):.2f} | "
              f"{' / '.join(map(str, chosen))} |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2])
    parser.add_argument("--noise", nargs="*", type=float, default=[0.0, 0.01, 0.05])
    parser.add_argument("--out", default=RESULTS)
    parser.add_argument("--summary", action="store_true")
    args = parser.parse_args(argv)
    if args.summary:
        summary(args.out)
        return 0
    table = unseen_systems.systems()
    done = gs.recorded(args.out, lambda r: (r["system"], r["noise"], r["seed"]))
    warnings.simplefilter("ignore")
    for seed in args.seeds:
        for noise in args.noise:
            for name, system in table.items():
                if (name, noise, seed) in done:
                    continue
                truth = gs.Truth(system)
                data = gs.case_data(system, truth, noise, seed, True)
                record = {"system": name, "n": truth.n, "forcing": "forced", "noise": noise,
                          "seed": seed, **tuned_mlp(truth, data)}
                with open(args.out, "a", encoding="utf-8") as handle:
                    handle.write(json.dumps(record) + "\n")
                print(f"{name} {noise:g} {seed}: held-out {record['held_out']:.4f} off-box "
                      f"{record['off_box']:.4f} candidate {record['candidate']} cpu "
                      f"{record['cpu_seconds']:.1f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
