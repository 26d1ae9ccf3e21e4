"""Speed of the support selection (``select_support``) on catalog-like columns of 250 to 1,000
columns, the size of automatic catalogs.

The columns are products of a few smooth signals plus 1 % noise (strongly correlated, as the
columns of a product catalog are), ``n_blocks=3`` coordinates of 1,000 rows each, a law of 10
terms with 1 % noise on the target. Prints, per catalog size, the median of ``--repeats`` wall
times and of this process's CPU times (on a shared, loaded machine the CPU time moves less), the
support and whether every true column was selected. Compare two checkouts by running it under
each (``PYTHONPATH=/path/to/other/checkout python benchmarks/selection_speed.py``).

Usage: ``python benchmarks/selection_speed.py [--sizes 250 500 1000] [--repeats 3]``.
"""

import argparse
import json
import time

import numpy as np

from pysindy_xl.optimizers import select_support


def catalog_like(n_rows: int, n_columns: int, seed: int = 0):
    """``(x, y, true_columns)``: correlated product columns and a sparse noisy law."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 30, n_rows)
    signals = np.column_stack([np.sin(a * t + b) for a, b in rng.uniform(0.2, 3, (8, 2))])
    picks = rng.integers(0, 8, size=(n_columns, 3))
    powers = rng.integers(0, 3, size=n_columns)
    weights = 0.3 * rng.normal(size=n_columns)
    x = (signals[:, picks[:, 0]] * signals[:, picks[:, 1]] ** powers
         + weights * signals[:, picks[:, 2]] + 0.01 * rng.normal(size=(n_rows, n_columns)))
    true = rng.choice(n_columns, 10, replace=False)
    y = x[:, true] @ rng.normal(size=10)
    return x, y + 0.01 * np.std(y) * rng.normal(size=n_rows), true


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[250, 500, 1000])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--rows", type=int, default=3000)
    args = parser.parse_args(argv)
    rows = []
    for n_columns in args.sizes:
        x, y, true = catalog_like(args.rows, n_columns)
        times, cpu_times = [], []
        for _ in range(args.repeats):
            start, cpu = time.perf_counter(), time.process_time()
            support = select_support(x, y, n_blocks=3).support
            times.append(time.perf_counter() - start)
            cpu_times.append(time.process_time() - cpu)
        row = {"columns": n_columns, "rows": args.rows, "median_s": float(np.median(times)),
               "best_s": float(np.min(times)), "median_cpu_s": float(np.median(cpu_times)),
               "support": [int(c) for c in support], "terms": int(len(support)),
               "true_found": int(np.isin(true, support).sum())}
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


if __name__ == "__main__":
    main()
