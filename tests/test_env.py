"""The preflight: finding a libLLVM that works, and a clear word when libatomic is missing."""

import ctypes
import os
import subprocess
import sys

import pytest

from mi_brdfs import _env


@pytest.mark.parametrize("path,major", [
    ("/usr/lib/x86_64-linux-gnu/libLLVM-15.so.1", 15),
    ("/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1", 19),
    ("/usr/lib/llvm-18/lib/libLLVM.so", 18),
    ("/opt/homebrew/opt/llvm/lib/libLLVM.dylib", 0),
])
def test01_version_from_name(path, major):
    assert _env.version_from_name(path) == major


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    return tmp_path


def test02_probe_rejects_missing_and_non_libraries(cache, tmp_path):
    ok, version, reason = _env.probe_llvm(str(tmp_path / "libLLVM-99.so"))
    assert not ok and version is None and "cannot read" in reason
    fake = tmp_path / "libLLVM-99.so"
    fake.write_text("not a library")
    ok, version, reason = _env.probe_llvm(str(fake))
    assert not ok and reason == "cannot be loaded"


def test03_probe_detects_the_llvm_that_aborts(cache):
    """LLVM 15 (Debian 12's default) aborts drjit's JIT: the probe survives and says so."""
    bad = [p for p in _env.llvm_candidates() if _env.version_from_name(p) in (15, 16)]
    if not bad:
        pytest.skip("no LLVM 15/16 on this machine")
    ok, _, reason = _env.probe_llvm(bad[0])
    assert not ok and "aborts inside the JIT" in reason


def test04_probe_verdict_is_cached(cache, monkeypatch):
    good = _env.find_llvm()
    if not good.ok:
        pytest.skip("no working libLLVM")
    assert _env.probe_llvm(good.path)[0]  # fills the cache in XDG_CACHE_HOME

    def no_subprocess(*args, **kwargs):
        raise AssertionError("the probe ran again despite the cache")
    monkeypatch.setattr(_env.subprocess, "run", no_subprocess)
    ok, version, reason = _env.probe_llvm(good.path)
    assert ok and version == good.version and reason == "works"


def test05_user_path_is_respected(cache, monkeypatch, tmp_path):
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", str(tmp_path / "nope.so"))
    status = _env.find_llvm(refresh=True)
    try:
        assert not status.ok and [p for p, _ in status.tried] == [str(tmp_path / "nope.so")]
        assert "DRJIT_LIBLLVM_PATH=" in status.message and "libllvm19" in status.message
    finally:
        monkeypatch.delenv("DRJIT_LIBLLVM_PATH")
        _env.find_llvm(refresh=True)


def test06_missing_libatomic_library_error(monkeypatch):
    def cdll(name, *args, **kwargs):
        raise OSError(f"{name}: cannot open shared object file")
    monkeypatch.setattr(ctypes, "CDLL", cdll)
    with pytest.raises(ImportError, match=r"libatomic\.so\.1.*apt-get install libatomic1"):
        _env.check_libatomic()


CLI_WITHOUT_LIBATOMIC = r"""
import ctypes, runpy, sys
real = ctypes.CDLL
def cdll(name, *a, **k):
    if 'libatomic' in str(name):
        raise OSError('libatomic.so.1: cannot open shared object file')
    return real(name, *a, **k)
ctypes.CDLL = cdll
sys.argv = ['mi-brdfs', 'info']
runpy.run_module('mi_brdfs', run_name='__main__')
"""


def test07_missing_libatomic_cli_says_one_line():
    p = subprocess.run([sys.executable, "-c", CLI_WITHOUT_LIBATOMIC], capture_output=True,
                       text=True, timeout=60, env=dict(os.environ))
    assert p.returncode == 2
    assert p.stderr.strip().splitlines() == [
        "mi-brdfs: error: drjit needs libatomic.so.1, which this system lacks; "
        "install it (Debian/Ubuntu: apt-get install libatomic1)"]
