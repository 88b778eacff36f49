"""
Installed as users install Mitsuba extensions: the wheel that ``pip install .`` builds, installed
into a fresh virtual environment outside the checkout, gives ``import mi_brdfs``, the plugins,
the ``mi-brdfs`` command and the bundled scenes. Offline: the wheel is built without build
isolation (hatchling comes with the test extra) and the fresh environment borrows the
dependencies (mitsuba, drjit, numpy, OpenEXR) already installed beside this interpreter.
"""

import os
import subprocess
import sys
import sysconfig
import venv
from pathlib import Path

import numpy as np
import pytest

import mi_brdfs

ROOT = Path(__file__).resolve().parents[1]


def _run(cmd, **kw):
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300, **kw)
    assert p.returncode == 0, f"{cmd}:\n{p.stdout[-3000:]}\n{p.stderr[-3000:]}"
    return p


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(python, mi-brdfs) of a fresh venv holding only the wheel of this checkout."""
    pytest.importorskip("hatchling")
    tmp = tmp_path_factory.mktemp("install")
    dist = tmp / "dist"
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
          "--no-index", "-q", "-w", str(dist), str(ROOT)])
    wheel = next(dist.glob("mi_brdfs-*.whl"))
    env_dir = tmp / "venv"
    venv.EnvBuilder(with_pip=False).create(env_dir)  # this interpreter's pip installs into it
    python = env_dir / "bin" / "python"
    site = _run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"]
                ).stdout.strip()
    # the dependencies of this interpreter, as a path entry (its .pth files, such as an
    # editable install of this checkout, are not processed from there)
    Path(site, "borrowed_dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    _run([sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps",
          "--no-index", "-q", str(wheel)])
    return python, env_dir / "bin" / "mi-brdfs", tmp


def test01_wheel_installs_imports_and_renders_outside_the_checkout(installed):
    """One installation (the wheel build takes seconds), used three ways, in one test: two
    tests would each build it where pytest-xdist runs them in two processes."""
    _imports_from_outside_the_checkout(installed)
    _the_command_renders_the_bundled_showcase(installed)
    _the_wheel_carries_the_fits_and_their_licence(installed)


def _imports_from_outside_the_checkout(installed):
    python, _, tmp = installed
    code = ("import mi_brdfs, mitsuba as mi; mi_brdfs.use_variant('scalar_rgb'); "
            "print(mi_brdfs.__file__); print(sorted(mi_brdfs.registry.register())); "
            "print(mi.load_dict({'type': 'cooktorrance'}).class_name())")
    out = _run([str(python), "-c", code], cwd=tmp).stdout.splitlines()
    assert str(tmp) in out[0] and str(ROOT) not in out[0]  # the installed copy, not this one
    assert out[1] == str(sorted(mi_brdfs.registry.PLUGINS))  # this checkout's plugins


def _the_command_renders_the_bundled_showcase(installed):
    _, command, tmp = installed
    out = tmp / "showcase.exr"
    env = dict(os.environ, MI_BRDFS_NO_PROGRESS="1")
    _run([str(command), "render", "showcase", "-o", str(out), "--spp", "2", "-D", "res=16",
          "--variant", "scalar_rgb"], cwd=tmp, env=env)
    from mi_brdfs.imageio import read_exr
    image, _ = read_exr(out)
    assert image.shape[:2] == (16, 16) and np.isfinite(image).all() and image.mean() > 0
    assert out.with_suffix(".png").is_file()


def _the_wheel_carries_the_fits_and_their_licence(installed):
    """mi_brdfs/data/ngan (bbm's fit files, its BSD licence, the README naming the source)
    is in the wheel, and the installed package reads it."""
    import zipfile

    python, _, tmp = installed
    wheel = next((tmp / "dist").glob("mi_brdfs-*.whl"))
    names = set(zipfile.ZipFile(wheel).namelist())
    for name in ("LICENSE", "README.md", "ngan_ward.fit", "ngan_he.fit"):
        assert f"mi_brdfs/data/ngan/{name}" in names, name
    code = ("from mi_brdfs import presets; print(presets.DATA); print(len(presets.materials())); "
            "print(presets.spec('ward', 'ngan:nickel')['form'])")
    out = _run([str(python), "-c", code], cwd=tmp).stdout.splitlines()
    assert str(tmp) in out[0] and out[1:] == ["86", "original"]
