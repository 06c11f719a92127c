"""Compiled kernels (numba ``@njit(cache=True)``) of the hot paths, one module per family.

They are plain Python loops over float64 arrays, so with ``NUMBA_DISABLE_JIT=1`` the same
source runs interpreted (debugging, coverage). Every kernel is tested equal (1e-13) to the
numpy reference functions it replaces; ``LGT_BRIDGE_BACKEND=numpy`` runs without them.
They import nothing above :mod:`lgt_bridge.groups`. Importing this package imports numba.
"""
import hashlib
import os
from pathlib import Path

_HERE = Path(__file__).resolve().parent
#: what every kernel module compiles in besides its own source: the scalar helpers it calls
#: and the series coefficients they bake in
SHARED_SOURCES = (_HERE / "rotations.py", _HERE / "charts.py", _HERE / "views.py", _HERE.parent / "_series.py",
                  *sorted((_HERE.parent / "charts").glob("*.py")))


def guard_cache(module_file, extra=()):
    """Drop the numba cache files of ``module_file`` when a source it compiles from changed.

    numba's ``cache=True`` keys a kernel's cached machine code on its own file only, so a
    kernel whose callee in another module changed (``kernels/rotations.py``, ``_series.py``)
    would keep running the old code in a working tree that was updated (an editable install
    after a pull). Each kernel module calls this at import: a stamp file in its
    ``__pycache__`` holds the hash of its own source and of SHARED_SOURCES (+ ``extra``);
    when it differs, the module's ``*.nbi``/``*.nbc`` files are deleted and numba compiles
    afresh. Best effort: a read-only or missing cache directory is left alone, and nothing
    is done with NUMBA_CACHE_DIR set (numba's cache is elsewhere then) or with the JIT off."""
    if os.environ.get("NUMBA_CACHE_DIR") or os.environ.get("NUMBA_DISABLE_JIT", "0") not in ("", "0"):
        return
    path = Path(module_file).resolve()
    digest = hashlib.sha1()
    for src in (path, *SHARED_SOURCES, *extra):
        try:
            digest.update(Path(src).read_bytes())
        except OSError:
            return
    digest = digest.hexdigest()
    cache = path.parent / "__pycache__"
    stamp = cache / f"{path.stem}.lgt-kernels-stamp"
    try:
        if stamp.read_text() == digest:
            return
    except OSError:
        pass
    try:
        for f in cache.glob(f"{path.stem}.*.nb[ic]"):
            f.unlink()
        cache.mkdir(exist_ok=True)
        tmp = cache / f"{stamp.name}.{os.getpid()}.tmp"
        tmp.write_text(digest)
        os.replace(tmp, stamp)
    except OSError:
        pass


def entry_point(kernel):
    """The compiled entry point of a kernel with one explicit signature: the call without
    numba's type dispatch (≈ 0.15 µs less for a few array arguments). It checks neither
    dtype nor layout nor shape, so it is only for arguments whose types the caller
    guarantees. The dispatcher itself where numba keeps no such entry
    (NUMBA_DISABLE_JIT=1, other numba versions)."""
    try:
        (cres,) = kernel.overloads.values()
        entry = cres.entry_point
    except (AttributeError, ValueError):
        return kernel
    return entry if callable(entry) else kernel
