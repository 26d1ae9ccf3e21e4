"""An on-disk store of arrays that are slow to derive and cheap to read: NPZ files, no pickle.

Kinematic-catalog derivations and large catalogs' evaluation plans, each file named by a
digest of all its arrays depend on, the deriving code included (a stale file is never read;
the newest :data:`KEEP` files of each kind are kept). The directory is ``$PYSINDY_XL_CACHE``,
else ``$XDG_CACHE_HOME/pysindy_xl`` (default ``~/.cache/pysindy_xl``); ``PYSINDY_XL_CACHE=off``
(or ``0``, ``false``, ``no``, empty) turns it off. Files are written under a temporary name
and renamed; an unwritable directory is skipped and an unreadable file is a miss.
"""

from __future__ import annotations

import glob
import hashlib
import os
import tempfile
import zipfile

import numpy as np

__all__ = ["add_arrays", "directory", "read_arrays", "source_digest", "write_arrays"]

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


def add_arrays(digest, arrays) -> None:
    """Update ``digest`` with each array's dtype, shape and bytes (read in place)."""
    for array in arrays:
        array = np.ascontiguousarray(array)
        digest.update(f"{array.dtype.str}{array.shape}".encode())
        digest.update(array.reshape(-1).view(np.uint8))


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
