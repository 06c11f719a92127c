"""The guard against stale numba caches (lgt_bridge.kernels.guard_cache): numba's cache=True
keys a kernel on its own file only, so a kernel whose callee in another module changed would
run old machine code. The guard deletes a module's cache files when any source it compiles
from changed, and keeps them otherwise."""
import os

import pytest

from lgt_bridge.kernels import guard_cache


@pytest.fixture
def tree(tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.delenv("NUMBA_DISABLE_JIT", raising=False)
    mod, callee = tmp_path / "mykernels.py", tmp_path / "helpers.py"
    mod.write_text("def f(): pass\n")
    callee.write_text("def g(): return 1\n")
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    return mod, callee, cache


def fill(cache):
    names = ["mykernels.f-1.py311.nbi", "mykernels.f-1.py311.1.nbc", "other.h-3.py311.nbi"]
    for n in names:
        (cache / n).write_bytes(b"x")
    return names


def test_cache_files_go_when_a_callee_changes_and_stay_otherwise(tree):
    mod, callee, cache = tree
    fill(cache)
    guard_cache(mod, extra=[callee])              # no stamp yet: the cache cannot be trusted
    assert sorted(os.listdir(cache)) == ["mykernels.lgt-kernels-stamp", "other.h-3.py311.nbi"]
    fill(cache)
    guard_cache(mod, extra=[callee])              # nothing changed: kept
    assert {"mykernels.f-1.py311.nbi", "mykernels.f-1.py311.1.nbc"} <= set(os.listdir(cache))
    callee.write_text("def g(): return 2\n")      # the callee changed, the module did not
    guard_cache(mod, extra=[callee])
    assert not any(n.startswith("mykernels.f") for n in os.listdir(cache))
    assert "other.h-3.py311.nbi" in os.listdir(cache)


def test_nothing_is_touched_with_numba_cache_dir_set(tree, monkeypatch):
    mod, callee, cache = tree
    fill(cache)
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache.parent / "elsewhere"))
    guard_cache(mod, extra=[callee])
    assert "mykernels.f-1.py311.nbi" in os.listdir(cache)


def test_the_library_kernels_are_stamped():
    """Importing the kernels leaves a stamp next to each module's cache (when the cache
    directory is writable, as in a source checkout)."""
    from lgt_bridge.kernels import stage
    cache = os.path.join(os.path.dirname(stage.__file__), "__pycache__")
    if not os.access(os.path.dirname(stage.__file__), os.W_OK) or os.environ.get("NUMBA_CACHE_DIR"):
        pytest.skip("the kernels' directory is not writable here")
    assert os.path.exists(os.path.join(cache, "stage.lgt-kernels-stamp"))
