"""An on-disk store of arrays that are slow to derive and cheap to read: NPZ files, no pickle.

Used for kinematic-catalog derivations and for the evaluation plans of large catalogs; each
user names its files by a digest of everything the arrays depend on, the deriving code
included, so a stale file is never read (it is a miss, and the newest :data:`KEEP` files of
each kind are kept).

The directory is ``$PYSINDY_XL_CACHE`` if set, else ``$XDG_CACHE_HOME/pysindy_xl`` (default
``~/.cache/pysindy_xl``); ``PYSINDY_XL_CACHE=off`` (or ``0``, ``false``, ``no``, empty) turns
the store off. Files are written to a temporary name and renamed (readers never see half a
file); a directory that cannot be created or written is skipped silently, and a file that is
missing or unreadable is a miss.
"""

from __future__ import annotations

import glob
import hashlib
import os
import tempfile
import zipfile

import numpy as np

__all__ = ["directory", "read_arrays", "source_digest", "write_arrays"]

KEEP = 16
_OFF = {"", "0", "off", "false", "no", "none"}


def directory() -> str | None:
    """The store's directory, or None when it is off."""
    value = os.environ.get("PYSINDY_XL_CACHE")
    if value is not None:
        return None if value.strip().lower() in _OFF else value
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "pysindy_xl")


def source_digest(paths, *versions) -> hashlib.sha256 | None:
    """A running digest of source files and version strings (None if a file is unreadable)."""
    digest = hashlib.sha256(" ".join(map(str, (np.__version__, *versions))).encode())
    try:
        for path in paths:
            with open(path, "rb") as f:
                digest.update(f.read())
    except OSError:
        return None
    return digest


def write_arrays(kind: str, digest: str, arrays: dict) -> None:
    """Store ``arrays`` as ``{kind}-{digest}.npz``, keeping the newest files of ``kind``."""
    folder = directory()
    if folder is None:
        return
    try:
        os.makedirs(folder, exist_ok=True)
        handle, temporary = tempfile.mkstemp(dir=folder, suffix=".tmp")
        try:
            with os.fdopen(handle, "wb") as f:
                np.savez(f, **arrays)  # uncompressed: deflating costs more than reading
            os.replace(temporary, os.path.join(folder, f"{kind}-{digest}.npz"))
        finally:
            if os.path.exists(temporary):
                os.unlink(temporary)
        for old in sorted(glob.glob(os.path.join(folder, f"{kind}-*.npz")),
                          key=os.path.getmtime)[:-KEEP]:
            os.unlink(old)
    except OSError:
        pass


def read_arrays(kind: str, digest: str) -> dict | None:
    """The arrays stored as ``{kind}-{digest}.npz``, or None (absent, off or unreadable)."""
    folder = directory()
    if folder is None:
        return None
    try:
        with np.load(os.path.join(folder, f"{kind}-{digest}.npz"), allow_pickle=False) as data:
            return {name: data[name] for name in data.files}
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):
        return None
