"""
Variant fixtures, after the pattern of Mitsuba's own ``src/conftest.py`` (not shipped in the
wheel): each sets its variant, registers the plugins there, and yields the variant name.
LLVM variants are skipped, with the reason, where no working libLLVM is installed.
"""

import os

# One BLAS thread per test process: make test runs one process per core, and NumPy's threaded
# BLAS would compete with drjit's thread pool for the same cores (set before NumPy loads).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
import signal  # noqa: E402

# Ctrl-C as a terminal delivers it: a job started in the background (`make test &`, a CI
# runner) starts with SIGINT ignored, which the runner rightly respects and every child
# process would inherit, so the tests of what Ctrl-C does would see nothing happen. A handler
# (unlike SIG_IGN) is reset to the default in a child at exec, where Python installs its own.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

import mi_brdfs  # noqa: F401  (import first: it chooses the libLLVM before drjit loads)
import drjit as dr

LLVM_OK = mi_brdfs.llvm_usable()
REQUIRED = ["scalar_rgb", "llvm_ad_rgb"]
CHEAP = ["scalar_spectral", "llvm_ad_spectral", "llvm_ad_mono"]


def set_variant(name: str) -> str:
    if name.startswith("llvm_") and not LLVM_OK:
        pytest.skip(f"{name}: no working libLLVM ({mi_brdfs._env.find_llvm().message})")
    return mi_brdfs.use_variant(name, fallback=False)


@pytest.fixture(autouse=True)
def _jit_cleanup():
    yield
    if dr.has_backend(dr.JitBackend.LLVM):
        dr.sync_thread()
        dr.kernel_history_clear()


@pytest.fixture
def variant_scalar_rgb():
    return set_variant("scalar_rgb")


@pytest.fixture
def variant_llvm_ad_rgb():
    return set_variant("llvm_ad_rgb")


@pytest.fixture
def variant_llvm_ad_spectral():
    return set_variant("llvm_ad_spectral")


@pytest.fixture
def variant_scalar_spectral():
    return set_variant("scalar_spectral")


@pytest.fixture
def variant_scalar_spectral_polarized():
    return set_variant("scalar_spectral_polarized")


@pytest.fixture(params=["llvm_ad_rgb", "llvm_ad_spectral"])
def variants_llvm_rgb_spectral(request):
    """llvm_ad_rgb and llvm_ad_spectral."""
    return set_variant(request.param)


@pytest.fixture(params=REQUIRED)
def variants_rgb(request):
    """scalar_rgb and llvm_ad_rgb."""
    return set_variant(request.param)


@pytest.fixture(params=REQUIRED + CHEAP)
def variants_all(request):
    """The required variants plus spectral and mono."""
    return set_variant(request.param)


@pytest.fixture
def np_rng():
    return np.random.default_rng(12345)


def _tiers(items, slow=None) -> list:
    """Mark ``slow`` the tests ``slow`` (default :data:`tiers.SLOW`) lists; return the entries
    that name no collected test of a file collected."""
    from tiers import SLOW

    slow = SLOW if slow is None else slow
    by_function = {}
    for item in items:
        path, _, name = item.nodeid.partition("::")
        function, _, ident = name.partition("[")
        by_function.setdefault((path, function), []).append((item, ident[:-1]))
    stale = []
    for path, entries in slow.items():
        if not any(p == path for p, _ in by_function):
            continue
        for function, entry in entries.items():
            instances = by_function.get((path, function))
            ids = entry[1] if isinstance(entry, tuple) else None
            if not instances:
                stale.append(f"{path}::{function}")
                continue
            for want in ids if ids is not None else [None]:
                chosen = [item for item, ident in instances
                          if want is None or ident == want or
                          (want.endswith("*") and ident.startswith(want[:-1]))]
                if not chosen:
                    stale.append(f"{path}::{function}[{want}]")
                for item in chosen:
                    item.add_marker(pytest.mark.slow)
    return stale


def _variant(item) -> str:
    """The variant a test sets through a fixture of this file ('' for none or its own)."""
    params = getattr(item, "callspec", None)
    for value in (params.params.values() if params else ()):
        if isinstance(value, str) and value in VARIANTS:
            return value
    for name in item.fixturenames:
        if name.startswith("variant_") and name[len("variant_"):] in VARIANTS:
            return name[len("variant_"):]
    return ""


#: Files whose tests start first: one long test (a server and a browser, most of a minute)
#: collected late would run alone at the end of a two-worker run; first, the other worker
#: takes the rest meanwhile.
FIRST = ("tests/explore/test_browser.py",)


def _by_variant(items) -> None:
    """Within each file, the tests in the order of their variant (stable otherwise): each
    switch into a JIT variant costs about 0.1 s in Mitsuba (it executes its AD integrators'
    modules again), and a parametrized test alternates variants case by case. The files of
    :data:`FIRST` first."""
    order = {}
    for i, item in enumerate(items):
        order.setdefault(item.nodeid.partition("::")[0], i)
    items.sort(key=lambda item: (item.nodeid.partition("::")[0] not in FIRST,
                                 order[item.nodeid.partition("::")[0]], _variant(item)))


#: The variants the fixtures and parametrized tests of this suite set.
VARIANTS = {"scalar_rgb", "scalar_spectral", "scalar_spectral_polarized", "llvm_ad_rgb",
            "llvm_ad_mono", "llvm_ad_spectral", "llvm_ad_spectral_polarized"}


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    _by_variant(items)
    stale = _tiers(items)
    # stale entries are judged where whole files were collected (not `pytest file::test`)
    if stale and all("::" not in arg for arg in config.args):
        raise pytest.UsageError("tests/tiers.py names tests that are not there: " +
                                ", ".join(stale))
