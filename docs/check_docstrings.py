"""List public objects whose docstrings lack Parameters, Returns or Examples.

Usage::

    python docs/check_docstrings.py                 # classes and functions of the public API
    python docs/check_docstrings.py --methods       # + public methods (Parameters / Returns)
    python docs/check_docstrings.py --run-examples  # + run every Examples section (doctest)

The public API is the ``__all__`` of the modules documented in the API reference
(``API_MODULES`` in ``docs/conf.py``). Checks use :func:`numpydoc.validate.validate`:

=====  =============================================================================
code   meaning
=====  =============================================================================
GL08   no docstring
PR01   parameters of the signature not documented under Parameters
PR02   documented parameters that are not in the signature
RT01   no Returns section although the code returns a value
EX01   no Examples section (classes and functions; methods with ``--method-examples``)
DT     the Examples section fails when run as a doctest (``--run-examples``)
=====  =============================================================================

An object without an Examples section counts as illustrated when a gallery example calls it
(``name(`` or ``.name`` in a script of ``examples/``); it is then listed for information only.

Exit status 1 when something is missing, so the script can gate a CI job.
"""

from __future__ import annotations

import argparse
import doctest
import functools
import importlib
import inspect
import re
import sys
from pathlib import Path

from numpydoc.validate import validate

DOCS = Path(__file__).resolve().parent
EXAMPLES = DOCS.parent / "examples"
sys.path.insert(0, str(DOCS / "_ext"))

from pxl_docs import GALLERY_EXCLUDED, object_kind, public_objects  # noqa: E402

#: Modules of the public API, the top-level package first (as in docs/conf.py).
API_MODULES = [
    "pysindy_xl",
    "pysindy_xl.feature_library",
    "pysindy_xl.catalog",
    "pysindy_xl.optimizers",
    "pysindy_xl.fit",
    "pysindy_xl.weak",
    "pysindy_xl.dynamics",
    "pysindy_xl.export.jax_dynamics",
    "pysindy_xl.io",
    "pysindy_xl.data",
    "pysindy_xl.export.gym_env",
    "pysindy_xl.control",
    "pysindy_xl.expressions",
    "pysindy_xl.mujoco",
    "pysindy_xl.benchmark",
    "pysindy_xl.held_out",
    "pysindy_xl.cli",
]
CHECKED = ("GL08", "PR01", "PR02", "RT01", "EX01")
SECTION_NAMES = {
    "GL08": "no docstring",
    "PR01": "Parameters incomplete",
    "PR02": "unknown parameters documented",
    "RT01": "no Returns",
    "EX01": "no Examples",
    "DT": "Examples fail",
}


def api_objects(modules) -> list[tuple[str, object]]:
    """``(import path, object)`` of every public class and function, each object once."""
    seen, out = set(), []
    for module_name in modules:
        try:
            objects = public_objects(module_name)
        except ImportError:
            print(f"note: {module_name} is not importable, skipped", file=sys.stderr)
            continue
        for name, obj in objects:
            if id(obj) in seen or object_kind(obj) == "data":
                continue
            seen.add(id(obj))
            out.append((f"{module_name}.{name}", obj))
    return out


def _is_ours(obj) -> bool:
    return (getattr(obj, "__module__", None) or "").split(".")[0] == "pysindy_xl"


def public_methods(path: str, cls) -> list[tuple[str, object]]:
    """Public methods a class defines or inherits from pysindy_xl classes (not properties)."""
    out = []
    for name in sorted(dir(cls)):
        if name.startswith("_") and name != "__call__":
            continue
        for owner in cls.__mro__:
            if name in owner.__dict__:
                raw = owner.__dict__[name]
                break
        else:
            continue
        if not _is_ours(owner) or isinstance(raw, (property, functools.cached_property)):
            continue
        function = raw.__func__ if isinstance(raw, (classmethod, staticmethod)) else raw
        if inspect.isfunction(function):
            out.append((f"{path}.{name}", function))
    return out


def gallery_users(name: str) -> list[str]:
    """Gallery scripts that call ``name`` (``name(`` or ``.name``)."""
    pattern = re.compile(rf"(\b{re.escape(name)}\s*\(|\.{re.escape(name)}\b)")
    return sorted(
        p.name for p in EXAMPLES.glob("*.py")
        if p.name not in GALLERY_EXCLUDED and pattern.search(p.read_text(encoding="utf-8"))
    )


def missing_sections(path: str, codes) -> list[str]:
    result = validate(path)
    return [code for code, _ in result["errors"] if code in codes]


def failing_examples(path: str, obj) -> str | None:
    """Run the doctest examples of one docstring; a failure message or None."""
    module = importlib.import_module(obj.__module__) if _is_ours(obj) else None
    globs = dict(vars(module)) if module is not None else {}
    finder = doctest.DocTestFinder(recurse=False)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    failures = []
    for test in finder.find(obj, path, globs=globs):
        result = runner.run(test, out=failures.append, clear_globs=True)
        if result.failed:
            return "".join(failures).strip().splitlines()[-1][:200]
    return None


def find_problems(modules=API_MODULES, methods: bool = False, method_examples: bool = False,
                  run_examples: bool = False) -> dict:
    """Check the public API of ``modules``; what each object lacks, and the examples that fail.

    Parameters
    ----------
    modules : sequence of str, default=API_MODULES
        Modules whose ``__all__`` is checked (an object re-exported by several is checked
        once, under the first).
    methods : bool, default=False
        Also check public methods (Parameters, Returns).
    method_examples : bool, default=False
        With ``methods``, also require Examples in methods.
    run_examples : bool, default=False
        Run the Examples sections as doctests.

    Returns
    -------
    dict
        ``problems`` (``{path: [code, ...]}``, the codes of the module docstring),
        ``failures`` (``{path: message}`` of failing examples), ``illustrated``
        (``{path: [gallery script, ...]}`` for objects without Examples that the gallery
        calls) and ``checked`` (the number of objects checked).
    """
    targets = []
    for path, obj in api_objects(modules):
        targets.append((path, obj, CHECKED))
        if methods and inspect.isclass(obj):
            codes = CHECKED if method_examples else CHECKED[:-1]
            targets += [(p, m, codes) for p, m in public_methods(path, obj)]

    problems, failures, illustrated = {}, {}, {}
    seen_functions = set()
    for path, obj, codes in targets:
        if id(obj) in seen_functions:
            continue
        seen_functions.add(id(obj))
        found = missing_sections(path, codes)
        if run_examples and (inspect.getdoc(obj) or "").find(">>>") >= 0:
            message = failing_examples(path, obj)
            if message:
                found.append("DT")
                failures[path] = message
        if "EX01" in found:
            users = gallery_users(path.rsplit(".", 1)[-1])
            if users:
                found.remove("EX01")
                illustrated[path] = users
        if found:
            problems[path] = found
    return {"problems": problems, "failures": failures, "illustrated": illustrated,
            "checked": len(seen_functions)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--methods", action="store_true",
                        help="also check public methods (Parameters, Returns)")
    parser.add_argument("--method-examples", action="store_true",
                        help="with --methods, also require Examples in methods")
    parser.add_argument("--run-examples", action="store_true",
                        help="run the Examples sections as doctests")
    args = parser.parse_args(argv)

    found = find_problems(API_MODULES, methods=args.methods,
                          method_examples=args.method_examples, run_examples=args.run_examples)
    problems = found["problems"]
    for path, message in found["failures"].items():
        print(f"{path}: example fails: {message}", file=sys.stderr)
    for path, codes in problems.items():
        print(f"{path}: " + ", ".join(SECTION_NAMES[c] for c in codes))
    for path, users in found["illustrated"].items():
        print(f"(info) {path}: no Examples section, called in " + ", ".join(users),
              file=sys.stderr)
    print(f"{len(problems)} of {found['checked']} public objects need docstring work",
          file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
