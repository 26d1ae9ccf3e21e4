"""Import times of pysindy_xl, pysindy and the ``pysindy-xl --help`` command.

Each measurement runs in a fresh interpreter (``subprocess``), best of ``--repeat`` runs, so
caches of a previous import never help. Measured:

* ``import pysindy`` and ``import pysindy_xl`` (time of the import statement, in-process);
* ``pysindy_xl.XLSINDy`` (``import pysindy_xl`` followed by the first touch of the estimator:
  what a fit pays before its first sample, since the public names load on first use);
* ``import pysindy_xl.mujoco`` (the simulation subpackage: its public names load on first use);
* ``pysindy-xl --help`` (wall time of the whole command, interpreter start included), run as
  ``python -m pysindy_xl.cli --help`` from the working tree;
* the same, again, in a *light* environment where cvxpy, JAX and MuJoCo are made unimportable
  (what ``pip install pysindy-xl`` without extras gives: PySINDy imports cvxpy, which imports
  JAX, whenever they are installed).

Heavy modules found in ``sys.modules`` after each import are listed.

Usage: ``python benchmarks/import_time.py [--repeat 7] [--out benchmarks/results/import_time.json]
[--root OTHER_CHECKOUT]``
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time

HEAVY = ("sympy", "pysindy", "sklearn", "cvxpy", "jax", "mujoco", "matplotlib", "pandas")

# makes the named packages unimportable (simulates an install without the extras)
BLOCK = """
import sys
class _Block:
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0] in {blocked!r}:
            raise ModuleNotFoundError(f"No module named {{name!r}} (blocked)")
        return None
sys.meta_path.insert(0, _Block())
"""

TIMED = """
import sys, time, json
start = time.perf_counter()
{statement}
elapsed = time.perf_counter() - start
print(json.dumps({{"seconds": elapsed,
                  "heavy": [m for m in {heavy!r} if m in sys.modules]}}))
"""

STATEMENTS = {
    "import pysindy": "import pysindy",
    "import pysindy_xl": "import pysindy_xl",
    "pysindy_xl.XLSINDy": "import pysindy_xl\npysindy_xl.XLSINDy",
    "import pysindy_xl.mujoco": "import pysindy_xl.mujoco",
}


def _run(code: str, root: str) -> dict:
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=root)
    if out.returncode:  # the statement itself fails (an import needing a blocked package)
        return {"error": (out.stderr.strip().splitlines() or ["failed"])[-1]}
    return json.loads(out.stdout.strip().splitlines()[-1])


def time_statement(statement: str, repeat: int, root: str, blocked=()) -> dict:
    """Best of ``repeat`` fresh interpreters for one import statement."""
    prelude = BLOCK.format(blocked=set(blocked)) if blocked else ""
    code = prelude + TIMED.format(statement=statement, heavy=HEAVY)
    runs = [_run(code, root) for _ in range(repeat)]
    if any("error" in r for r in runs):
        return {"best_s": None, "error": next(r["error"] for r in runs if "error" in r)}
    best = min(runs, key=lambda r: r["seconds"])
    return {"best_s": best["seconds"], "runs_s": [r["seconds"] for r in runs],
            "heavy_modules": best["heavy"]}


def time_help(repeat: int, root: str, blocked=()) -> dict:
    """Best wall time of ``python -m pysindy_xl.cli --help`` (interpreter start included)."""
    prelude = BLOCK.format(blocked=set(blocked)) if blocked else ""
    code = prelude + ("import sys, runpy\nsys.argv = ['pysindy-xl', '--help']\n"
                      "runpy.run_module('pysindy_xl.cli', run_name='__main__')")
    runs = []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], capture_output=True, cwd=root, check=True)
        runs.append(time.perf_counter() - start)
    return {"best_s": min(runs), "runs_s": runs}


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=7, help="fresh interpreters per timing")
    parser.add_argument("--out", default=None, help="write the results as JSON there")
    parser.add_argument("--root", default=None,
                        help="checkout to time (default: this one), e.g. an older commit's")
    args = parser.parse_args(argv)
    root = args.root or os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

    results = {"python": sys.version.split()[0], "machine": platform.machine(),
               "cpu_count": os.cpu_count(), "repeat": args.repeat, "environments": {}}
    for env, blocked in (("installed", ()), ("light", ("cvxpy", "jax", "jaxlib", "mujoco"))):
        rows = {label: time_statement(stmt, args.repeat, root, blocked)
                for label, stmt in STATEMENTS.items()}
        rows["pysindy-xl --help"] = time_help(args.repeat, root, blocked)
        base = rows["import pysindy"]["best_s"]
        results["environments"][env] = {"blocked": list(blocked), "timings": rows,
                                        "ratio_import_to_pysindy":
                                            rows["import pysindy_xl"]["best_s"] / base,
                                        "ratio_first_use_to_pysindy":
                                            rows["pysindy_xl.XLSINDy"]["best_s"] / base}
        title = env + (f" (unimportable: {', '.join(blocked)})" if blocked else "")
        print(f"{title}, best of {args.repeat}:")
        for label, row in rows.items():
            if row["best_s"] is None:
                print(f"  {label:<26} fails: {row['error']}")
                continue
            heavy = row.get("heavy_modules")
            extra = f"   loads: {', '.join(heavy) or '-'}" if heavy is not None else ""
            print(f"  {label:<26} {row['best_s']:7.3f} s{extra}")
        print(f"  import pysindy_xl / import pysindy = "
              f"{results['environments'][env]['ratio_import_to_pysindy']:.2f} (target <= 1.5); "
              f"first use of XLSINDy / import pysindy = "
              f"{results['environments'][env]['ratio_first_use_to_pysindy']:.2f}")
    if args.out:
        with open(args.out, "w", encoding="utf-8") as handle:
            json.dump(results, handle, indent=2)
        print(f"wrote {args.out}")
    return results


if __name__ == "__main__":
    main()
