"""
Sweeps that outgrow a machine: ``mi-brdfs fit DIR/*.binary --models all`` fits every lecture
model to every measured material, one task per (material, model), and merges the results into
one table (the objective of each fit under the chosen metric, the models ranked per material,
their mean rank over the materials: Ngan et al. 2005's comparison, for the user's data).

One code path for every scheduler: a task is :func:`run_task`, which runs the fit in a Python
process of its own (``python -m mi_brdfs.fit.sweep TASK``), because Mitsuba registers Python
plugins per process and a process keeps its variant, its JIT caches and its memory; the result
comes back as JSON. Locally a thread pool of ``workers`` runs the tasks (each thread waits on
its process); with ``scheduler`` (``tcp://HOST:PORT``) a Dask cluster does
(`dask.distributed <https://distributed.dask.org>`_, the optional extra ``mi-brdfs[sweep]``;
on SLURM or PBS, `dask-jobqueue <https://jobqueue.dask.org>`_ starts the workers and gives the
address), each worker running the same :func:`run_task`. The machines need the files at the
same paths and mi_brdfs installed.

Finished tasks are kept in ``OUT/.sweep-cache/`` under the SHA-256 of the material file's
content and the settings (model, metric, pairs, steps, seed, mi_brdfs's version): a sweep that
stops (Ctrl-C, a lost worker) resumes where it was, and one that changes nothing recomputes
nothing.
"""

from __future__ import annotations

import concurrent.futures
import functools
import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from .._version import __version__
from ..errors import MiBrdfsError
from ..imageio import atomic_path
from ..markdown import md_table

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
    """One task in a Python process of its own; its result (JSON) or MiBrdfsError."""
    env = dict(os.environ, MI_BRDFS_NO_PROGRESS="1")
    proc = subprocess.run([sys.executable, "-m", "mi_brdfs.fit.sweep", json.dumps(task)],
                          capture_output=True, text=True, env=env)
    lines = proc.stdout.strip().splitlines()
    if proc.returncode != 0 or not lines:
        why = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        raise MiBrdfsError(f"sweep: {task['model']} on {task['file']} failed: {why}")
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


def _run_all(todo: list, workers: int, scheduler: str | None, done: callable) -> None:
    """Run the tasks ``todo``, calling ``done(task, result)`` as each finishes."""
    if scheduler:
        try:
            from distributed import Client, as_completed
        except ImportError:
            raise MiBrdfsError("--scheduler needs dask.distributed: pip install "
                               "'mi-brdfs[sweep]'") from None
        with Client(scheduler) as client:
            futures = {client.submit(run_task, t, pure=False): t for t in todo}
            for future in as_completed(futures):
                done(futures[future], future.result())
        return
    with concurrent.futures.ThreadPoolExecutor(max_workers=workers) as pool:
        futures = {pool.submit(run_task, t): t for t in todo}
        for future in concurrent.futures.as_completed(futures):
            done(futures[future], future.result())


def sweep(files, models: list, metric: str, out, *, pairs: int = 16384, steps: int = 800,
          seed: int = 0, workers: int | None = None, scheduler: str | None = None,
          progress: bool = False) -> dict:
    """
    Every model of ``models`` fitted to every MERL file of ``files`` under ``metric``; the
    merged table in ``out`` (``sweep.md``, ``sweep.json``). Returns {'results': {(file,
    model): result}, 'computed': tasks run now, 'written': paths}.
    """
    from ..progress import Progress

    out = Path(out)
    cache = out / CACHE
    cache.mkdir(parents=True, exist_ok=True)
    tasks = [dict(file=str(Path(f).resolve()), model=m, metric=metric, pairs=pairs, steps=steps,
                  seed=seed) for f in files for m in models]
    results, todo = {}, []
    for t in tasks:
        path = cache / f"{task_key(t)}.json"
        if path.exists():
            results[(t["file"], t["model"])] = json.loads(path.read_text())
        else:
            todo.append(t)
    bar = Progress(len(todo), label="sweep", unit=" fits") if progress and todo else None

    def done(task, result):
        with atomic_path(cache / f"{task_key(task)}.json", ".json") as tmp:
            Path(tmp).write_text(json.dumps(result))
        results[(task["file"], task["model"])] = result
        if bar is not None:
            bar.update(len(results) - (len(tasks) - len(todo)))

    try:
        _run_all(todo, workers or os.cpu_count() or 1, scheduler, done)
    finally:
        if bar is not None:
            bar.close()
    written = write_table(results, files, models, metric, out)
    return {"results": results, "computed": len(todo), "written": written}


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
