"""Runtime preflight: the native libraries that drjit needs before it is imported.

Two things break a drjit 1.5 installation in ways whose error messages hide the cause:

* ``libatomic.so.1`` (Debian package ``libatomic1``) is missing on minimal images such as the
  ``python:*-slim`` containers; ``import drjit`` then fails with a ``NameError``.
* drjit's LLVM backend loads whatever ``libLLVM`` it finds first. Debian 12 ships LLVM 14/15 by
  default, and with LLVM 15 or 16 the JIT *aborts the whole process* ("LLVM ERROR: Cannot select:
  fminimum") at the first kernel that uses ``dr.minimum``, which every render does. LLVM 19
  (Debian package ``libllvm19``) works.

This module finds a libLLVM that really works, by running a one-kernel probe in a subprocess (an
abort there cannot take the caller down), caches the verdict per library file, and points drjit at
it through ``DRJIT_LIBLLVM_PATH`` before drjit is imported. A path the user set in
``DRJIT_LIBLLVM_PATH`` is respected: it is probed, never replaced.
"""

from __future__ import annotations

import ctypes
import glob
import json
import os
import re
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

#: How to fix a missing or broken LLVM, in one line.
LLVM_FIX = ("install LLVM 19 (Debian/Ubuntu: apt-get install libllvm19) or point "
            "DRJIT_LIBLLVM_PATH at a working libLLVM")

#: How to fix a missing libatomic, in one line.
ATOMIC_FIX = "install it (Debian/Ubuntu: apt-get install libatomic1)"

#: Where drjit itself looks, plus the usual places of versioned LLVM builds.
_SEARCH_PATTERNS = (
    "/usr/lib/x86_64-linux-gnu/libLLVM*.so*",
    "/usr/lib/aarch64-linux-gnu/libLLVM*.so*",
    "/usr/lib/wsl/lib/libLLVM*.so*",
    "/usr/lib/llvm-*/lib/libLLVM*.so*",
    "/usr/lib64/libLLVM*.so*",
    "/usr/lib/libLLVM*.so*",
    "/usr/local/lib/libLLVM*.so*",
    "/opt/homebrew/opt/llvm/lib/libLLVM.dylib",
    "/usr/local/opt/llvm/lib/libLLVM.dylib",
)

# The probe compiles the kernel that LLVM 15/16 cannot select (an fminimum against a constant).
_PROBE = (
    "import drjit as dr\n"
    "x = dr.llvm.Float([float(i) for i in range(17)])\n"
    "y = dr.minimum(x * x, 0.95) + dr.maximum(x, 0.5)\n"
    "dr.eval(y)\n"
    "print('MI_BRDFS_LLVM_OK', *dr.detail.llvm_version())\n"
)


@dataclass
class LLVMStatus:
    """What the preflight found out about the LLVM backend."""

    #: The library drjit will use (None: none works).
    path: str | None = None
    #: Its version as (major, minor, patch), where the probe could read it.
    version: tuple | None = None
    #: Whether the probe compiled and ran a kernel with it.
    ok: bool = False
    #: One line for the user when ``ok`` is false.
    message: str = ""
    #: Every candidate tried, with its verdict.
    tried: list = field(default_factory=list)


def version_from_name(path: str) -> int:
    """Major version from a library name (libLLVM-15.so.1, libLLVM.so.19.1, llvm-18/lib/...)."""
    for pattern in (r"libLLVM-(\d+)", r"libLLVM\.so\.(\d+)", r"llvm-(\d+)"):
        m = re.search(pattern, path)
        if m:
            return int(m.group(1))
    return 0


def llvm_candidates() -> list[str]:
    """Every libLLVM on the usual paths, one per real file, newest major version first."""
    seen, result = set(), []
    for pattern in _SEARCH_PATTERNS:
        for path in sorted(glob.glob(pattern)):
            try:
                real = os.path.realpath(path)
            except OSError:
                continue
            if real in seen or not os.path.isfile(real):
                continue
            seen.add(real)
            result.append(path)
    return sorted(result, key=version_from_name, reverse=True)


def _cache_file() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "mi_brdfs" / "llvm-probe.json"


def _cache_key(path: str) -> str:
    st = os.stat(os.path.realpath(path))
    try:
        from importlib.metadata import version
        drjit_version = version("drjit")
    except Exception:  # pragma: no cover - drjit always has metadata when installed by pip
        drjit_version = "?"
    return f"{os.path.realpath(path)}|{st.st_size}|{int(st.st_mtime)}|drjit-{drjit_version}"


def _load_cache() -> dict:
    try:
        return json.loads(_cache_file().read_text())
    except (OSError, ValueError):
        return {}


def _store_cache(cache: dict) -> None:
    try:
        f = _cache_file()
        f.parent.mkdir(parents=True, exist_ok=True)
        tmp = f.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps(cache, indent=1))
        os.replace(tmp, f)
    except OSError:
        pass  # a read-only home only costs a re-probe next time


def probe_llvm(path: str, use_cache: bool = True,
               timeout: float = 120.0) -> tuple[bool, tuple | None, str]:
    """
    Compile and run one kernel with drjit's LLVM backend bound to ``path``, in a subprocess.

    Returns ``(ok, version, reason)``. The verdict is cached per file (path, size, mtime) and drjit
    version in ``~/.cache/mi_brdfs/llvm-probe.json``, so the probe costs about a second once.
    """
    try:
        key = _cache_key(path)
    except OSError as e:
        return False, None, f"cannot read {path}: {e.strerror}"
    cache = _load_cache() if use_cache else {}
    if key in cache:
        entry = cache[key]
        return entry["ok"], tuple(entry["version"]) if entry["version"] else None, entry["reason"]

    env = dict(os.environ, DRJIT_LIBLLVM_PATH=path)
    try:
        proc = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True,
                              text=True, timeout=timeout)
        out = proc.stdout + proc.stderr
    except subprocess.TimeoutExpired:
        return False, None, f"the probe timed out after {timeout:.0f} s"
    m = re.search(r"MI_BRDFS_LLVM_OK (\d+) (\d+) (\d+)", out)
    if proc.returncode == 0 and m:
        ok, version, reason = True, tuple(int(g) for g in m.groups()), "works"
    else:
        ok, version = False, None
        if "could not be found" in out or "Unable to load" in out:
            reason = "cannot be loaded"
        elif "Cannot select" in out or proc.returncode < 0:
            reason = "aborts inside the JIT (LLVM too old for drjit 1.5)"
        else:
            lines = [ln for ln in out.strip().splitlines() if ln.strip()]
            reason = lines[-1][:160] if lines else f"exit code {proc.returncode}"
    cache[key] = {"ok": ok, "version": list(version) if version else None, "reason": reason}
    if use_cache:
        _store_cache(cache)
    return ok, version, reason


_status: LLVMStatus | None = None

#: Set by ``mi_brdfs/__init__``: whether drjit was imported (and its libLLVM chosen) before us.
DRJIT_IMPORTED_FIRST = False


def find_llvm(refresh: bool = False) -> LLVMStatus:
    """
    Find a libLLVM that drjit can use (cached for the process).

    With ``DRJIT_LIBLLVM_PATH`` set, only that library is considered. Otherwise the candidates of
    :func:`llvm_candidates` are probed newest first and the first that works wins.
    """
    global _status
    if _status is not None and not refresh:
        return _status
    status = LLVMStatus()
    user_path = os.environ.get("DRJIT_LIBLLVM_PATH")
    if user_path == LLVM_DISABLED:
        user_path = None
    candidates = [user_path] if user_path else llvm_candidates()
    for path in candidates:
        ok, version, reason = probe_llvm(path)
        status.tried.append((path, reason))
        if ok:
            status.path, status.version, status.ok = path, version, True
            break
    if not status.ok:
        if user_path:
            found = f"DRJIT_LIBLLVM_PATH={user_path} {status.tried[0][1]}"
        elif status.tried:
            found = "found " + ", ".join(f"{os.path.basename(p)} ({r})" for p, r in status.tried)
        else:
            found = "no libLLVM found"
        status.message = f"no working libLLVM for drjit's LLVM backend: {found}; fix: {LLVM_FIX}"
    _status = status
    return status


#: What DRJIT_LIBLLVM_PATH is set to when no libLLVM works: drjit then leaves its LLVM backend
#: off (``mi.set_variant('llvm_*')`` raises ImportError) instead of loading a libLLVM that aborts.
LLVM_DISABLED = "mi_brdfs-found-no-working-libLLVM--apt-get-install-libllvm19"


def configure_llvm() -> LLVMStatus:
    """
    Point drjit at a working libLLVM before drjit is imported (it reads the variable at import).

    Does nothing once drjit is imported, or when the user set ``DRJIT_LIBLLVM_PATH``.
    """
    status = find_llvm()
    if "DRJIT_LIBLLVM_PATH" not in os.environ and "drjit" not in sys.modules:
        os.environ["DRJIT_LIBLLVM_PATH"] = status.path if status.ok else LLVM_DISABLED
    return status


def loaded_llvm_problem() -> str | None:
    """
    One line if the libLLVM that drjit has loaded is one the probe saw fail, else None.

    That happens when the user's ``DRJIT_LIBLLVM_PATH`` names a broken library, or when drjit
    was imported before mi_brdfs and chose one itself.
    """
    import drjit as dr
    if not dr.has_backend(dr.JitBackend.LLVM):
        return None
    major = dr.detail.llvm_version()[0]
    user_path = os.environ.get("DRJIT_LIBLLVM_PATH")
    if user_path == LLVM_DISABLED:
        return None
    paths = [user_path] if user_path else [p for p in llvm_candidates()
                                           if version_from_name(p) == major]
    for path in paths:
        ok, _, reason = probe_llvm(path)
        if not ok:
            where = ("drjit was imported before mi_brdfs and loaded" if DRJIT_IMPORTED_FIRST
                     else f"DRJIT_LIBLLVM_PATH={path} is")
            hint = ", and import mi_brdfs before mitsuba/drjit" if DRJIT_IMPORTED_FIRST else ""
            return f"{where} LLVM {major}, which {reason}; fix: {LLVM_FIX}{hint}"
    return None


def running_cli() -> bool:
    """Whether this process is the ``mi-brdfs`` command (console script or ``python -m``)."""
    argv0 = os.path.basename(sys.argv[0]) if sys.argv else ""
    main = os.path.join("mi_brdfs", "__main__.py")
    return argv0 in ("mi-brdfs", "-m") or bool(sys.argv and sys.argv[0].endswith(main))


def check_libatomic() -> None:
    """Raise ImportError with the fix when libatomic.so.1 (needed by drjit) is missing."""
    if not sys.platform.startswith("linux"):
        return
    try:
        ctypes.CDLL("libatomic.so.1")
    except OSError:
        raise ImportError(
            f"mi_brdfs: drjit needs libatomic.so.1, which this system lacks; {ATOMIC_FIX}"
        ) from None


def import_drjit_quietly() -> None:
    """
    Import drjit with its own stderr lines about an unloadable libLLVM suppressed: when the
    preflight found no working libLLVM, mi_brdfs says so itself, once, with the fix.
    """
    if "drjit" in sys.modules:
        return
    try:
        saved = os.dup(2)
    except OSError:  # pragma: no cover - no stderr at all
        import drjit  # noqa: F401
        return
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), 2)
            import drjit  # noqa: F401
    finally:
        os.dup2(saved, 2)
        os.close(saved)
