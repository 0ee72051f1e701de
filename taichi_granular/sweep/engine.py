"""Runs jobs, each in a Python process of its own, on Dask distributed or one after another.

A job names a function (``module:function``) and its JSON payload; :func:`execute` runs it in a
fresh process (``python -m taichi_granular.sweep.child``), so that every run has its own Taichi
runtime (precision and arch are global in Taichi), its own peak memory, and a crash or a hang
(``timeout``) ends that run only. :func:`run_jobs` hands the jobs to Dask: a ``LocalCluster``
of ``workers`` processes (one job at a time each) by default, or the scheduler at an address (a
cluster started with ``dask scheduler`` / ``dask worker``, or dask-jobqueue); a worker that dies
has its job rescheduled by Dask on another. Without Dask (``workers=0``, or the ``sweep``
extra not installed) the jobs run one after another here, through the same :func:`execute`.

A job that fails -- an exception in the child, a timeout, a killed process, a lost worker --
comes back as ``{"status": "failed", "error": ...}``; it never stops the others.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from typing import Callable, Dict, Optional, Sequence

from ..runtime import THREADS_ENV

RESULT_PREFIX = "taichi-granular-result: "  # the child's result line on stdout


@dataclass(frozen=True)
class Job:
    id: str
    entry: str  # "module:function", called with the payload in the child; returns a JSON-able dict
    payload: dict


def failed(message: str, **extra) -> dict:
    return {"status": "failed", "error": message, **extra}


def execute(job: Job, threads: Optional[int], timeout: float) -> dict:
    """Run ``job`` in a fresh process with ``threads`` Taichi CPU threads (None: Taichi's
    default) and at most ``timeout`` seconds; its result dict with ``status`` and
    ``job_seconds`` (the process's wall time, start-up included)."""
    env = dict(os.environ)
    if threads:
        env[THREADS_ENV] = str(int(threads))
    start = time.perf_counter()
    try:
        proc = subprocess.run([sys.executable, "-m", "taichi_granular.sweep.child"],
                              input=json.dumps({"entry": job.entry, "payload": job.payload}),
                              capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return failed(f"timed out after {timeout:.0f} s", job_seconds=time.perf_counter() - start)
    seconds = time.perf_counter() - start
    lines = [ln[len(RESULT_PREFIX):] for ln in proc.stdout.splitlines() if ln.startswith(RESULT_PREFIX)]
    if not lines:
        last = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        return failed(f"exit code {proc.returncode}: {last[:500]}", job_seconds=seconds)
    return {**json.loads(lines[-1]), "job_seconds": seconds}


class Progress:
    """'runs: done/total, failed, elapsed, ETA', a line per finished job."""

    def __init__(self, total: int, quiet: bool = False):
        self.total, self.done, self.failed, self.quiet = total, 0, 0, quiet
        self.start = time.perf_counter()

    def update(self, job: Job, result: dict) -> None:
        self.done += 1
        self.failed += result.get("status") != "ok"
        if self.quiet:
            return
        elapsed = time.perf_counter() - self.start
        eta = elapsed / self.done * (self.total - self.done)
        note = "" if result.get("status") == "ok" else f"  {job.id} failed: {result.get('error', '')[:200]}"
        print(f"runs: {self.done}/{self.total} done, {self.failed} failed, {_clock(elapsed)} elapsed, "
              f"ETA {_clock(eta)}{note}", flush=True)


def _clock(seconds: float) -> str:
    seconds = int(round(seconds))
    return f"{seconds // 3600}h{seconds // 60 % 60:02d}m" if seconds >= 3600 else f"{seconds // 60}m{seconds % 60:02d}s"


def dask_available() -> bool:
    try:
        import dask.distributed  # noqa: F401
    except ImportError:
        return False
    return True


def run_jobs(jobs: Sequence[Job], *, workers: Optional[int] = None, scheduler: Optional[str] = None,
             threads: Optional[int] = None, timeout: float = 6 * 3600.0,
             on_result: Optional[Callable[[Job, dict], None]] = None, quiet: bool = False) -> Dict[str, dict]:
    """Every job's result by id. ``workers``: LocalCluster processes (default: one per core;
    0 runs the jobs here one after another, without Dask); ``scheduler``: the address of a
    running Dask scheduler instead; ``threads``: Taichi's CPU threads per run (default with a
    LocalCluster: cores // workers, so that workers x threads <= cores)."""
    progress = Progress(len(jobs), quiet)
    results: Dict[str, dict] = {}

    def finish(job: Job, result: dict) -> None:
        results[job.id] = result
        progress.update(job, result)
        if on_result is not None:
            on_result(job, result)

    cores = os.cpu_count() or 1
    if not jobs:
        return results
    if scheduler is None and workers == 0:
        for job in jobs:
            finish(job, execute(job, threads, timeout))
        return results
    if not dask_available():
        raise RuntimeError("Dask is not installed: pip install -e \".[sweep]\" (or run one job at a time with "
                           "--workers 0)")
    from dask.distributed import Client, LocalCluster, as_completed

    cluster = None
    if scheduler is None:
        workers = workers or cores
        threads = threads or max(1, cores // workers)
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True)
        client = Client(cluster)
    else:
        client = Client(scheduler)
    try:
        if not quiet:
            where = f"LocalCluster, {workers} workers x {threads} threads" if cluster else scheduler
            print(f"Dask: {where}; dashboard {client.dashboard_link}", flush=True)
        token = f"{time.time_ns():x}"
        futures = {client.submit(execute, job, threads, timeout, key=f"taichi-granular-{job.id}-{token}",
                                 pure=False): job for job in jobs}
        for future in as_completed(futures):
            job = futures[future]
            try:
                result = future.result()
            except Exception as err:  # noqa: BLE001 - a lost worker (KilledWorker) is that run's failure
                result = failed(f"{type(err).__name__}: {err}")
            finish(job, result)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return results

