"""
Image output: EXR through OpenEXR (full float32, metadata in the header) and an sRGB PNG preview.

Every write is atomic: the data goes to a temporary file in the destination folder, which is
renamed over the destination only once complete, so no reader ever sees a half-written file.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

import numpy as np

from .errors import MiBrdfsError


def channel_names(count: int, film_names: list[str] | None = None) -> list[str]:
    """EXR channel names for an image with ``count`` channels (Y, YA, RGB, RGBA or the film's)."""
    standard = {1: ["Y"], 2: ["Y", "A"], 3: ["R", "G", "B"], 4: ["R", "G", "B", "A"]}
    if count in standard:
        return standard[count]
    if film_names and len(film_names) == count:
        return list(film_names)
    return ["R", "G", "B"] + [f"C{i}" for i in range(3, count)]


def check_writable(path: str | os.PathLike) -> Path:
    """
    Fail early, before any rendering, when ``path`` cannot be written.

    Returns → Path: the absolute path. Raises MiBrdfsError naming the path and the reason.
    """
    path = Path(path).expanduser().absolute()
    folder = path.parent
    if path.is_dir():
        raise MiBrdfsError(f"cannot write {path}: it is a directory")
    if not folder.is_dir():
        raise MiBrdfsError(f"cannot write {path}: folder {folder} does not exist")
    try:
        fd, probe = tempfile.mkstemp(dir=folder, prefix=f".{path.name}.", suffix=".probe")
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        raise MiBrdfsError(f"cannot write {path}: {e.strerror or e}") from None
    if path.exists() and not os.access(path, os.W_OK):
        raise MiBrdfsError(f"cannot write {path}: permission denied")
    return path


def planned_outputs(command: str, named=(), unnamed=(), force: bool = False,
                    folder: tuple | None = None) -> list[Path]:
    """
    Every file a command is about to write, checked before any work: the one place that decides
    what may be replaced. A file the user named (``named``: paths given on the command line,
    such as ``-o OUT.exr``) is replaced; any other (``unnamed``: (path, what it is or "",
    advice) of a default output, a file written beside a named one, a report's file in its
    folder) that exists already is refused in one line, ``COMMAND: PATH (WHAT) exists; ADVICE,
    or pass --force to replace it``, unless ``force``. ``folder``: (path, how errors name it)
    of the folder the unnamed files go in, created (with its parents) once nothing is refused.
    Every file must be writable (:func:`check_writable`), but one in a subfolder not made yet;
    the writers replace each one atomically (:func:`atomic_path`).

    Returns → list[Path]: the absolute paths, ``named`` first, in the order given.
    """
    for path, what, advice in unnamed:
        path = Path(path).expanduser()
        if not force and (path.is_file() or path.is_symlink()):
            raise MiBrdfsError(f"{command}: {_shown(path)}{f' ({what})' if what else ''} "
                               f"exists; {advice}, or pass --force to replace it")
    if folder is not None:
        output_folder(*folder)
    return [check_writable(p) for p in named] + [  # (a subfolder: its writer makes it)
        check_writable(p) if Path(p).expanduser().absolute().parent.is_dir()
        else Path(p).expanduser().absolute() for p, _, _ in unnamed]


def _shown(path: Path) -> str:
    """``path`` as the user would type it: ``./NAME`` inside the current folder."""
    path, here = path.absolute(), Path.cwd()
    return f"./{path.relative_to(here).as_posix()}" if path.is_relative_to(here) else str(path)


def output_folder(path, name: str, filename: str | None = None) -> Path:
    """
    The folder ``path`` (created with its parents), checked writable for ``filename`` before
    any work; one-line errors name it as ``name`` (e.g. ``--out DIR``).
    """
    from .errors import MiBrdfsError

    out = Path(path).expanduser().absolute()
    if out.exists() and not out.is_dir():
        raise MiBrdfsError(f"{name}: not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise MiBrdfsError(f"{name}: cannot create the folder: {e.strerror or e}") from None
    check_writable(out / (filename or ".probe"))
    return out


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str = ""):
    """
    Yield a temporary path beside ``path``; on success it replaces ``path``, on error it is removed.

    ``suffix`` keeps the extension for writers that infer the format from it.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=f".partial{suffix}")
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; give the file the usual mode
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_exr(path: str | os.PathLike, image: np.ndarray, metadata: dict | None = None,
              names: list[str] | None = None) -> Path:
    """
    Write a float32 EXR (ZIP compression) with ``metadata`` as string attributes in the header.

    Parameter ``image`` (ndarray): H×W or H×W×C.

    Parameter ``names`` (list[str] | None): channel names; default from :func:`channel_names`.
    """
    import OpenEXR

    image = np.asarray(image, dtype=np.float32)
    if image.ndim == 2:
        image = image[:, :, None]
    names = names or channel_names(image.shape[2])
    channels = {name: np.ascontiguousarray(image[:, :, i]) for i, name in enumerate(names)}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for key, value in (metadata or {}).items():
        header[str(key)] = str(value)
    path = Path(path)
    with atomic_path(path, ".exr") as tmp:
        OpenEXR.File(header, channels).write(tmp)
    return path


def read_exr(path: str | os.PathLike) -> tuple[np.ndarray, dict]:
    """Read an EXR written by :func:`write_exr`: (H×W×C float32 image, header as dict)."""
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        part = f.parts[0]
        header = dict(part.header)
        chans = part.channels
        order = [n for n in ("R", "G", "B", "A", "Y") if n in chans] or list(chans)
        order += [n for n in chans if n not in order]
        image = np.stack([np.asarray(chans[n].pixels, dtype=np.float32) for n in order], axis=-1)
    return image, header


def to_srgb8(image: np.ndarray, exposure: float = 0.0) -> np.ndarray:
    """Linear radiance → 8-bit sRGB (H×W×{1,3}), clamped; NaN shows as black."""
    image = np.asarray(image, dtype=np.float32)
    if image.ndim == 2:
        image = image[:, :, None]
    image = image[:, :, :3] if image.shape[2] >= 3 else image[:, :, :1]
    x = np.nan_to_num(image * np.float32(2.0 ** exposure), nan=0.0, posinf=1.0, neginf=0.0)
    x = np.clip(x, 0.0, 1.0)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(srgb * 255.0).astype(np.uint8)


def from_srgb8(values) -> np.ndarray:
    """8-bit sRGB values → linear (float64), the inverse of :func:`to_srgb8`'s transfer
    function (IEC 61966-2-1)."""
    c = np.asarray(values, np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def write_png(path: str | os.PathLike, image: np.ndarray, exposure: float = 0.0) -> Path:
    """Write an sRGB 8-bit PNG preview of a linear image (via Mitsuba's Bitmap writer)."""
    import mitsuba as mi

    data = to_srgb8(image, exposure)
    fmt = mi.Bitmap.PixelFormat.Y if data.shape[2] == 1 else mi.Bitmap.PixelFormat.RGB
    bitmap = mi.Bitmap(data, fmt)
    path = Path(path)
    with atomic_path(path, ".png") as tmp:
        bitmap.write(tmp)
    return path
