"""Where a sweep's runs execute: this process, a local process pool, or a Ray cluster.

Every engine takes the same :class:`RunSpec` list and yields a :class:`RunResult` per run, in
whatever order runs finish; the table sorts them by run number, so the order never shows. A run
is deterministic and executes the same code wherever it lands, so the engines' tables are
identical row for row (all but the wall time). A run that raises comes back as a result with
its error; a worker that dies takes only its own run with it, reported as that run's error.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
from abc import ABC, abstractmethod
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from fleet_async.sweep.orphans import init_worker
from fleet_async.sweep.scenarios import RunResult, RunSpec, describe_error, execute_run

__all__ = ["ENGINES", "Engine", "InlineEngine", "PoolEngine", "RayEngine", "make_engine"]

logger = logging.getLogger(__name__)

RAY_MISSING = (
    "the Ray engine needs Ray, which is not installed: pip install 'fleet-async[ray]' "
    "(or run on the local process pool: --engine pool)"
)


def _lost(spec: RunSpec, error: BaseException) -> RunResult:
    """The row of a run whose worker process died while running it."""
    return RunResult(
        index=spec.index,
        params=dict(spec.params),
        seed=spec.seed,
        kpis=None,
        robots=None,
        error=f"worker process died: {describe_error(error)}",
        wall_time_s=0.0,
    )


class Engine(ABC):
    """Runs RunSpecs somewhere and yields their results as they finish."""

    name: str

    @abstractmethod
    def map_unordered(self, specs: Sequence[RunSpec]) -> Iterator[RunResult]:
        """Yield one result per spec, in completion order.

        Stopping the iteration early (Ctrl+C, ``close()`` of the generator) starts no further
        run.
        """

    def describe(self) -> str:
        """A short description for progress messages (engine and worker count)."""
        return self.name


class InlineEngine(Engine):
    """Runs in this process, one run at a time (for debugging: breakpoints work)."""

    name = "inline"

    def map_unordered(self, specs: Sequence[RunSpec]) -> Iterator[RunResult]:
        """Run each spec here, in order."""
        for spec in specs:
            yield execute_run(spec)


class PoolEngine(Engine):
    """A pool of worker processes on this machine, one run per worker at a time.

    Workers are started fresh (``spawn``), as Ray's are, so a run never inherits state from
    the process that started the sweep; they ignore Ctrl+C, which the sweep handles: no new run
    starts, the ones in progress finish and are written. They exit when the sweep's process
    dies, even by ``kill -9`` (``orphans.py``).

    Args:
        workers: Worker processes (default: one per CPU core).
    """

    name = "pool"

    def __init__(self, workers: int | None = None) -> None:
        if workers is not None and workers < 1:
            raise ValueError(f"workers: expected a whole number >= 1, got {workers!r}")
        self.workers = workers or os.cpu_count() or 1

    def describe(self) -> str:
        """``pool of N workers``."""
        return f"pool of {self.workers} worker{'s' if self.workers != 1 else ''}"

    def _new_pool(self, workers: int) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(
            max_workers=workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=init_worker,  # ignore Ctrl+C; exit when this process dies
            initargs=(os.getpid(),),
        )

    def map_unordered(self, specs: Sequence[RunSpec]) -> Iterator[RunResult]:
        """Run the specs on the pool; yield results as runs finish."""
        if not specs:
            return
        workers = min(self.workers, len(specs))
        pool = self._new_pool(workers)
        pending: dict[Future[RunResult], RunSpec] = {}
        suspects: list[RunSpec] = []
        interrupted = False
        try:
            # One run queued beyond the busy workers: enough to keep them busy, and little for
            # a stopped sweep to wait for (the pool hands queued runs to its workers early).
            queue = list(reversed(specs))
            while queue or pending:
                while queue and not suspects and len(pending) < workers + 1:
                    spec = queue.pop()
                    pending[pool.submit(execute_run, spec)] = spec
                try:
                    done, _ = wait(pending, return_when=FIRST_COMPLETED)
                except KeyboardInterrupt:
                    if interrupted:
                        raise
                    interrupted = True  # first Ctrl+C: start nothing new, finish what runs
                    queue.clear()
                    for future in [f for f in pending if f.cancel()]:
                        del pending[future]
                    # At most `workers` runs are running; the pool hands one more to a
                    # worker early, and that one cannot be cancelled any more.
                    running = min(len(pending), workers)
                    logger.warning(
                        "interrupted: finishing the %d runs already started on %d workers%s "
                        "(Ctrl+C again to stop at once)",
                        running,
                        workers,
                        f" and {len(pending) - running} queued in the pool"
                        if len(pending) > running
                        else "",
                    )
                    continue
                for future in sorted(done, key=lambda f: pending[f].index):
                    spec = pending.pop(future)
                    try:
                        yield future.result()
                    except BrokenProcessPool:
                        suspects.append(spec)
                if suspects and not pending:  # a worker died: every run in flight failed
                    pool.shutdown(wait=True)
                    yield from self._isolate(sorted(suspects, key=lambda s: s.index))
                    suspects.clear()
                    pool = self._new_pool(workers)
        finally:
            pool.shutdown(wait=not pending, cancel_futures=True)
        if interrupted:
            raise KeyboardInterrupt

    def _isolate(self, specs: list[RunSpec]) -> Iterator[RunResult]:
        """Run each spec alone, so that a worker that dies again names the run that kills it.

        Raises:
            RuntimeError: if a worker cannot even start (then no run is to blame).
        """
        pool = self._new_pool(1)
        try:
            for spec in specs:
                try:
                    yield pool.submit(execute_run, spec).result()
                except BrokenProcessPool as exc:
                    pool.shutdown(wait=True)
                    pool = self._new_pool(1)
                    self._probe(pool)
                    yield _lost(spec, exc)
        finally:
            pool.shutdown(wait=True)

    @staticmethod
    def _probe(pool: ProcessPoolExecutor) -> None:
        try:
            pool.submit(os.getpid).result()
        except BrokenProcessPool as exc:
            raise RuntimeError(
                "the sweep's worker processes die as they start (a script run from standard "
                "input, or a __main__ module that does work when imported: guard it with "
                "if __name__ == '__main__'); see the messages above"
            ) from exc


def _import_ray() -> Any:
    try:
        import ray
    except ImportError as exc:
        raise ImportError(RAY_MISSING) from exc
    return ray


class RayEngine(Engine):
    """Runs on Ray: a local instance started for the sweep, or an existing cluster.

    On a cluster, every node needs fleet_async (and the module of a function scenario)
    installed; a YAML scenario travels as data, but the files it names (worlds, meshes) must
    exist at the same paths on the nodes.

    Args:
        address: A cluster's address (``ray://host:10001``, ``host:6379`` or ``auto``); None
            starts a local instance for the sweep and stops it afterwards.
        workers: CPUs of the local instance (default: all); ignored with ``address``.

    Raises:
        ImportError: naming the ``ray`` extra, when Ray is not installed.
    """

    name = "ray"

    def __init__(self, address: str | None = None, workers: int | None = None) -> None:
        self._ray = _import_ray()
        self.address = address
        self.workers = workers

    def describe(self) -> str:
        """``ray (local)`` or ``ray at ADDRESS``."""
        return f"ray at {self.address}" if self.address else "ray (local)"

    def _start(self) -> bool:
        """Connect or start Ray unless it is already up; return whether this call did."""
        ray = self._ray
        if ray.is_initialized():
            return False
        options: dict[str, Any] = {
            "include_dashboard": False,
            "log_to_driver": False,
            "logging_level": logging.WARNING,
        }
        if self.address:
            ray.init(address=self.address, **options)
        else:
            ray.init(num_cpus=self.workers, **options)
        return True

    def map_unordered(self, specs: Sequence[RunSpec]) -> Iterator[RunResult]:
        """Submit the specs as Ray tasks (a window of twice the cluster's CPUs at a time)."""
        if not specs:
            return
        ray = self._ray
        started = self._start()
        remote = ray.remote(num_cpus=1, max_retries=0)(execute_run)
        window = max(2, 2 * int(ray.cluster_resources().get("CPU", 1)))
        queue = list(reversed(specs))
        pending: dict[Any, RunSpec] = {}
        try:
            while queue or pending:
                while queue and len(pending) < window:
                    spec = queue.pop()
                    pending[remote.remote(spec)] = spec
                done, _ = ray.wait(list(pending), num_returns=1)
                spec = pending.pop(done[0])
                try:
                    result = ray.get(done[0])
                except Exception as exc:  # the worker died, or Ray lost the task
                    result = _lost(spec, exc)
                yield result
        finally:
            for ref in pending:
                ray.cancel(ref)
            if started:
                ray.shutdown()


ENGINES = ("pool", "ray", "inline")
"""Engine names ``make_engine`` (and ``fleet-async sweep --engine``) accept."""


def make_engine(name: str, workers: int | None = None, address: str | None = None) -> Engine:
    """The engine called ``name`` (see :data:`ENGINES`).

    Raises:
        ValueError: for an unknown name, or ``address`` with an engine other than Ray.
        ImportError: for ``ray`` without Ray installed (naming the extra).
    """
    if address is not None and name != "ray":
        raise ValueError(f"--address is for the Ray engine (--engine ray), not {name!r}")
    if name == "pool":
        return PoolEngine(workers)
    if name == "ray":
        return RayEngine(address, workers)
    if name == "inline":
        return InlineEngine()
    raise ValueError(f"unknown engine {name!r}; valid: {', '.join(ENGINES)}")
