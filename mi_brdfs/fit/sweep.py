"""
Sweeps that outgrow a machine: ``mi-brdfs fit DIR/*.binary --models all`` fits every lecture
model to every measured material, one task per (material, model), and merges the results into
one table (the objective of each fit under the chosen metric, the models ranked per material,
their mean rank over the materials: Ngan et al. 2005's comparison, for the user's data).

One code path for every scheduler: a task is :func:`run_task`, which runs the fit in a Python
process of its own (``python -m mi_brdfs.fit.sweep TASK``), because Mitsuba registers Python
plugins per process and a process keeps its variant, its JIT caches and its memory; the result
comes back as JSON. :func:`mi_brdfs.runner.run` runs the tasks: locally on ``workers`` threads
(each waits on its process), or with ``scheduler`` (``tcp://HOST:PORT``) on a Dask cluster
(`dask.distributed <https://distributed.dask.org>`_, the optional extra ``mi-brdfs[sweep]``;
on SLURM or PBS, `dask-jobqueue <https://jobqueue.dask.org>`_ starts the workers and gives the
address), each worker running the same :func:`run_task`. The machines need the files at the
same paths and mi_brdfs installed.

Before any fit: the scheduler's address is parsed, every file checked (there, readable, a MERL
file's size and dimensions), a file given twice (by path or by content) kept once, and the
scheduler reached (the runner's checks). A fit that fails is one line and the others go on;
Ctrl-C or SIGTERM stops the sweep at once. Either way every finished fit is kept in
``OUT/.sweep-cache/`` under the SHA-256 of the material file's content and the settings
(model, metric, pairs, steps, seed, mi_brdfs's version): the same command resumes where the
sweep stopped, and one that changes nothing recomputes nothing.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import sys
import warnings
from pathlib import Path

import numpy as np

from .. import runner
from .._version import __version__
from ..errors import MiBrdfsError, MiBrdfsWarning
from ..imageio import atomic_path
from ..markdown import md_table
from ..measured import merl

CACHE = ".sweep-cache"


@functools.lru_cache(maxsize=None)
def _digest(path: str, mtime_ns: int, size: int) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def file_digest(path) -> str:
    """SHA-256 of a file's content (computed once per process while the file is unchanged)."""
    try:
        st = os.stat(path)
    except OSError as e:
        raise MiBrdfsError(f"{path}: cannot read the MERL file ({e.strerror or e})") from None
    return _digest(os.path.abspath(path), st.st_mtime_ns, st.st_size)


def task_key(task: dict) -> str:
    """The cache key of a task: its file's content and its settings."""
    settings = {k: task[k] for k in ("model", "metric", "pairs", "steps", "seed")}
    text = json.dumps([file_digest(task["file"]), settings, __version__], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def run_task(task: dict) -> dict:
    """One task in a Python process of its own (:func:`mi_brdfs.runner.run_command`): its
    result (JSON), or MiBrdfsError with the process's last line of error."""
    env = dict(os.environ, MI_BRDFS_NO_PROGRESS="1")
    proc = runner.run_command([sys.executable, "-m", "mi_brdfs.fit.sweep", json.dumps(task)],
                              env=env)
    lines = proc.stdout.strip().splitlines()
    if proc.returncode != 0 or not lines:
        why = (proc.stderr.strip().splitlines() or [f"exit status {proc.returncode}, no output"])
        raise MiBrdfsError(why[-1].split("Error: ", 1)[-1])
    return json.loads(lines[-1])


def _task_main(text: str) -> int:
    """The process of one task: fit, score, print the result as one JSON line."""
    import warnings

    from .models import fit_one

    task = json.loads(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # energy warnings of a fitted spec: in the table
        result, scores = fit_one(task["file"], task["model"], task["metric"], task["pairs"],
                                 task["steps"], task["seed"])
    print(json.dumps({"task": task, "fitted": result.command_line(),
                      "parameters": result.parameters, "scores": scores,
                      "albedo_error": result.albedo_error, "flags": result.flags,
                      "seconds": result.seconds}))
    return 0


def check_files(files) -> list[str]:
    """
    The files of a sweep, each once (by path, then by content: a repeat is a warning), as
    absolute paths; every file there, readable and of a MERL file's size and dimensions, else
    one MiBrdfsError naming each file that is not and why (its values are read in the fit).
    """
    kept, seen, bad = [], {}, []
    for given in files:
        path = str(Path(given).resolve())
        why = _unusable(path)
        if why:
            bad.append(f"{given}: {why}")
            continue
        digest = file_digest(path)
        first = seen.get(path) or seen.get(digest)
        if first is not None:
            same = "given twice" if seen.get(path) else f"the same content as {first}"
            warnings.warn(MiBrdfsWarning(f"sweep: {given} is {same}: fitted and listed once"))
            continue
        seen[path] = seen[digest] = str(given)
        kept.append(path)
    if bad:
        head = f"{len(bad)} of {len(files)} files are not MERL files a fit can read: " \
            if len(bad) > 1 else ""
        raise MiBrdfsError(f"sweep: {head}" + "; ".join(bad) + " (no fit started)")
    return kept


def _unusable(path: str) -> str | None:
    """Why ``path`` is no MERL file a fit can read, from its size and its 12-byte header (None:
    it looks like one)."""
    try:
        with open(path, "rb") as f:
            size = os.fstat(f.fileno()).st_size
            head = f.read(12)
    except OSError as e:
        return f"cannot read the MERL file ({e.strerror or e})"
    if len(head) < 12:
        return f"{size} bytes, too short for a MERL file"
    dims = tuple(int(v) for v in np.frombuffer(head, dtype="<i4"))
    if dims != merl.RES:
        return f"dimensions {dims}, not MERL's {merl.RES} (θh, θd, φd): not a MERL .binary file"
    if size != merl.SIZE:
        return f"{size} bytes where a MERL file has {merl.SIZE}: truncated or padded"
    return None


def sweep(files, models: list, metric: str, out, *, pairs: int = 16384, steps: int = 800,
          seed: int = 0, workers: int | None = None, scheduler: str | None = None,
          progress: bool = False, wait: float = runner.WORKER_WAIT) -> dict:
    """
    Every model of ``models`` fitted to every MERL file of ``files`` under ``metric``; the
    merged table in ``out`` (``sweep.md``, ``sweep.json``). Returns {'results': {(file,
    model): result}, 'computed': fits run now, 'cached': fits taken from the cache, 'files':
    the files fitted (absolute, each once), 'written': paths}.

    The scheduler's address and the files are checked before anything else; a fit that fails
    is one line on stderr and the others go on (then one MiBrdfsError); Ctrl-C or SIGTERM
    raises :class:`mi_brdfs.runner.Interrupted`. Every finished fit is in the cache either way.
    ``wait``: seconds to wait for the first worker of a Dask scheduler that has none.
    """
    address = runner.scheduler_address(scheduler) if scheduler is not None else None
    files = check_files(files)
    if address is not None:
        runner.reach(address)  # before the folder is made: nothing left for a wrong address
    out = Path(out)
    cache = out / CACHE
    cache.mkdir(parents=True, exist_ok=True)
    tasks = [dict(file=f, model=m, metric=metric, pairs=pairs, steps=steps, seed=seed)
             for f in files for m in models]
    results, todo = {}, []
    for t in tasks:
        path = cache / f"{task_key(t)}.json"
        if path.exists():
            results[(t["file"], t["model"])] = json.loads(path.read_text())
        else:
            todo.append(t)

    def keep(task, result):
        with atomic_path(cache / f"{task_key(task)}.json", ".json") as tmp:
            Path(tmp).write_text(json.dumps(result))
        results[(task["file"], task["model"])] = result

    failures = runner.run(todo, run_task, workers=workers, scheduler=address, on_done=keep,
                          describe=lambda t: f"{t['model']} on {t['file']}", label="sweep",
                          unit=" fits", keep=f"{cache} (the same command resumes from there)",
                          progress=progress, wait=wait)
    if failures:
        raise MiBrdfsError(f"sweep: {len(failures)} of {len(todo)} fits failed (each above); "
                           f"the {len(todo) - len(failures)} finished are kept in {cache}, and "
                           f"the same command computes only the rest")
    written = write_table(results, files, models, metric, out)
    return {"results": results, "computed": len(todo), "cached": len(tasks) - len(todo),
            "files": files, "written": written}


def merged(results: dict, files, models: list, metric: str) -> tuple[list, dict]:
    """(rows: material, each model's objective (rank), the best model; {model: mean rank})."""
    rows, ranks = [], {m: [] for m in models}
    for f in files:
        key = str(Path(f).resolve())
        values = {m: results[(key, m)]["scores"][metric] for m in models}
        order = sorted(models, key=values.get)
        for i, m in enumerate(order):
            ranks[m].append(i + 1)
        rows.append((Path(f).stem, *[f"{values[m]:.4g} ({order.index(m) + 1})" for m in models],
                     order[0]))
    return rows, {m: float(np.mean(r)) for m, r in ranks.items()}


def write_table(results: dict, files, models: list, metric: str, out: Path) -> list:
    """sweep.md and sweep.json in ``out``."""
    rows, mean_rank = merged(results, files, models, metric)
    text = "\n".join([
        f"# Lecture models fitted to {len(files)} measured materials", "",
        f"The objective of each fit under `{metric}` (rank among the models), one fit per "
        "material and model (`mi_brdfs.fit.sweep`):", "",
        md_table(["material", *models, "best"], rows), "",
        md_table(["model", "mean rank"], [(m, f"{mean_rank[m]:.2f}") for m in
                                          sorted(models, key=mean_rank.get)]), ""])
    doc = {"metric": metric, "mean_rank": mean_rank,
           "fits": [results[(str(Path(f).resolve()), m)] for f in files for m in models]}
    written = []
    for name, content in (("sweep.md", text), ("sweep.json", json.dumps(doc, indent=1))):
        with atomic_path(out / name, Path(name).suffix) as tmp:
            Path(tmp).write_text(content)
        written.append(str(out / name))
    return written


if __name__ == "__main__":
    sys.exit(_task_main(sys.argv[1]))
