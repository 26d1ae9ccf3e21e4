"""The documentation builds with warnings as errors and every gallery example runs."""

import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_docs_build_without_warnings_and_run_the_gallery(tmp_path):
    sphinx = pytest.importorskip("sphinx")
    assert sphinx  # the docs extra is part of the dev install
    out = tmp_path / "html"
    result = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         str(ROOT / "docs"), str(out)],
        cwd=ROOT, capture_output=True, text=True, timeout=1200,
    )
    assert result.returncode == 0, result.stderr[-5000:]
    assert (out / "index.html").is_file()
    gallery = ROOT / "docs" / "auto_examples"
    examples = sorted(p.stem for p in (ROOT / "examples").glob("*.py"))
    built = sorted(p.stem for p in gallery.glob("*.py"))
    assert built, "the gallery produced no example"
    for name in built:
        assert any(gallery.glob(f"images/sphx_glr_{name}_*.png")), f"{name} made no figure"
    assert set(built) <= set(examples)
