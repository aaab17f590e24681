"""Running slide jobs: serially, on a local process pool or on Ray, through the slide cache.

A backend takes a picklable function of one argument (a :class:`~.jobs.SlideWorker`) and runs
it on the items it is given: :class:`SerialBackend` in this process, :class:`ProcessBackend`
in local worker processes (fork where there is one), :class:`RayBackend` as Ray tasks on a
local instance or a cluster. :func:`stream` keeps a backend's slots busy and yields each
result as it finishes; :func:`run_slides` is the cached path of a task's data (every slide
saved in the cache, read instead of simulated next time). Results never depend on the
backend, the number of workers or the order of completion: a slide is its job's alone.
"""

from __future__ import annotations

import os
import time
from collections import Counter
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from .. import _validate as v
from ..cache import ArtefactCache
from ..errors import ConfigError, SimTactileError, WorkerError, require
from ..interrupts import raise_pending
from ..records import Recording
from .jobs import SlideJob, SlideOutcome, SlideWorker, cached_slide, slide_key

#: The backends ``generate --backend`` takes.
BACKENDS = ("local", "ray")
#: Most worker processes ``SIM_TACTILE_WORKERS`` or ``--workers`` may ask for.
MAX_WORKERS = 4096


def default_workers() -> int:
    """``$SIM_TACTILE_WORKERS`` if set, else every core this process may run on."""
    env = os.environ.get("SIM_TACTILE_WORKERS")
    if env:
        value = int(env) if env.isdigit() else env
        return v.integer("SIM_TACTILE_WORKERS", value, 1, MAX_WORKERS)
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


class Done:
    """A result already at hand (the serial backend, or data that needs no worker)."""

    def __init__(self, value: Any = None, exc: BaseException | None = None) -> None:
        self.value, self.exc = value, exc

    def result(self) -> Any:
        if self.exc is not None:
            raise self.exc
        return self.value


class SerialBackend:
    """One worker: this process."""

    name = "local"

    def __init__(self, fn: Callable[[Any], Any]) -> None:
        self.fn = fn
        self.slots = 1
        self.workers = 1

    def submit(self, item: Any) -> Done:
        try:
            return Done(self.fn(item))
        except Exception as exc:  # raised again when its result is asked for
            return Done(exc=exc)

    def wait(self, pending: Iterable) -> list:
        return list(pending)

    def result(self, handle: Done) -> Any:
        return handle.result()

    def close(self, cancel: bool = False) -> None:
        pass


#: How often a worker checks that its parent is alive [s] (where the kernel cannot tell it).
WATCHDOG_S = 1.0


def _worker_init(parent: int) -> None:  # pragma: no cover - runs in the workers
    """A worker ignores Ctrl-C (the parent handles it and stops the pool), dies of SIGTERM,
    and ends when its parent ends, however it ends (SIGTERM, SIGKILL, the OOM killer): the
    kernel sends it SIGKILL then (Linux's parent-death signal), and a watchdog thread ends it
    where there is no such signal, or where the parent died before it was set."""
    import signal
    import threading

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # not the parent's handler, copied by fork
    _die_with_parent()
    if os.getppid() != parent:
        os._exit(1)

    def watch() -> None:
        while True:
            time.sleep(WATCHDOG_S)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, name="parent-watchdog", daemon=True).start()


def _die_with_parent() -> None:  # pragma: no cover - runs in the workers
    """Linux: SIGKILL this process when the thread that made it ends (prctl
    PR_SET_PDEATHSIG); elsewhere nothing (the watchdog does it)."""
    import ctypes
    import ctypes.util
    import signal
    import sys

    if not sys.platform.startswith("linux"):
        return
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG = 1
    except (OSError, AttributeError):
        return


def _warm(_: int) -> int:  # pragma: no cover - runs in the workers
    return os.getpid()


class ProcessBackend:
    """Local worker processes; each ignores Ctrl-C (the parent handles it). Every worker is
    started when the backend is made, before the caller opens files or threads of its own
    (fork copies the parent as it is)."""

    name = "local"

    def __init__(self, fn: Callable[[Any], Any], workers: int) -> None:
        from concurrent.futures import ProcessPoolExecutor
        from multiprocessing import get_all_start_methods, get_context

        # fork where there is one: spawn would re-import the caller's __main__, which breaks
        # scripts without a main guard
        ctx = get_context("fork" if "fork" in get_all_start_methods() else "spawn")
        self.fn = fn
        self.workers = workers
        self.slots = 2 * workers
        self.pool = ProcessPoolExecutor(
            workers, mp_context=ctx, initializer=_worker_init, initargs=(os.getpid(),)
        )
        list(self.pool.map(_warm, range(workers)))
        # the workers, started by the map above (the pool keeps them in a private table)
        self._procs = list(getattr(self.pool, "_processes", {}).values())

    def submit(self, item: Any):
        return self.pool.submit(self.fn, item)

    def wait(self, pending: Iterable) -> list:
        from concurrent.futures import FIRST_COMPLETED, wait

        done, _ = wait(list(pending), return_when=FIRST_COMPLETED)
        return list(done)

    def result(self, handle) -> Any:
        from concurrent.futures.process import BrokenProcessPool

        try:
            return handle.result()
        except BrokenProcessPool:
            raise WorkerError("a worker process died (killed, or out of memory?)") from None

    def close(self, cancel: bool = False) -> None:
        """Stop the pool; with ``cancel``, drop what is queued and end the workers now
        (a slide in flight is not waited for: an interrupt or an error stops the run)."""
        self.pool.shutdown(wait=not cancel, cancel_futures=cancel)
        if cancel:
            for p in self._procs:
                if p.is_alive():
                    p.terminate()
            for p in self._procs:
                p.join(timeout=5)
                if p.is_alive():
                    p.kill()
                    p.join(timeout=5)


def _call(fn: Callable[[Any], Any], item: Any) -> Any:  # pragma: no cover - a Ray task
    return fn(item)


class RayBackend:
    """Ray tasks, on a local instance (``address`` None: ``workers`` CPUs) or a cluster. A
    task whose worker dies is run again (up to 3 times: the same job, the same slide)."""

    name = "ray"

    def __init__(
        self,
        fn: Callable[[Any], Any],
        workers: int | None,
        address: str | None,
        log: Callable[[str], None],
    ) -> None:
        ray = require("ray", "ray")
        self.ray, self.fn = ray, fn
        self.own = not ray.is_initialized()
        if self.own:
            kw = {"include_dashboard": False, "log_to_driver": False}
            if address:
                ray.init(address=address, **kw)
            else:
                ray.init(num_cpus=workers or os.cpu_count() or 1, **kw)
        cpus = int(ray.cluster_resources().get("CPU", 1))
        log(f"ray: {cpus} CPUs in the cluster" + (f" at {address}" if address else " (local)"))
        self.workers = workers if (workers and address) else cpus
        self.slots = 2 * self.workers
        self.remote = ray.remote(num_cpus=1, max_retries=3)(_call)

    def submit(self, item: Any):
        return self.remote.remote(self.fn, item)

    def wait(self, pending: Iterable) -> list:
        done, _ = self.ray.wait(list(pending), num_returns=1)
        return done

    def result(self, handle) -> Any:
        return self.ray.get(handle)

    def close(self, cancel: bool = False) -> None:
        if self.own:
            self.ray.shutdown()


Backend = SerialBackend | ProcessBackend | RayBackend


def make_backend(
    fn: Callable[[Any], Any],
    *,
    kind: str = "local",
    workers: int | None = None,
    address: str | None = None,
    log: Callable[[str], None] = lambda m: None,
) -> Backend:
    """The backend ``kind`` (local: one worker runs in this process) for ``fn``."""
    v.one_of("backend", kind, BACKENDS)
    if address and kind != "ray":
        raise ConfigError("an address is for the ray backend (--backend ray)")
    if workers is not None:
        workers = v.integer("workers", workers, 1, MAX_WORKERS)
    if kind == "ray":
        return RayBackend(fn, workers, address, log)
    n = workers or default_workers()
    return SerialBackend(fn) if n == 1 else ProcessBackend(fn, n)


def stream(
    backend: Backend,
    items: Iterable[tuple[Any, Any]],
    *,
    name: Callable[[Any], str] | None = None,
) -> Iterator[tuple[Any, Any]]:
    """Run ``backend`` on the items of ``(key, item)`` pairs, at most ``backend.slots`` at
    a time, and yield ``(key, result)`` as each finishes. A worker's error is raised here
    (its message led by ``name(key)`` when given)."""
    queue = iter(items)
    pending: dict = {}
    while True:
        raise_pending()  # a signal whose exception a compiled kernel swallowed stops here
        while len(pending) < backend.slots:
            nxt = next(queue, None)
            if nxt is None:
                break
            pending[backend.submit(nxt[1])] = nxt[0]
        if not pending:
            return
        for handle in backend.wait(pending):
            key = pending.pop(handle)
            try:
                result = backend.result(handle)
            except SimTactileError as exc:
                if name is None or isinstance(exc, WorkerError):
                    raise
                raise type(exc)(f"{name(key)}: {str(exc).splitlines()[0]}") from exc
            yield key, result


def run_slides(
    jobs: list[SlideJob],
    *,
    cache: ArtefactCache | None = None,
    workers: int | None = None,
    log: Callable[[str], None] | None = None,
) -> tuple[list[Recording], dict]:
    """The recordings of ``jobs`` in their order, simulating the ones not in the cache (in
    worker processes; every slide is saved in the cache), and statistics: ``simulate_s`` (wall
    time, 0 when all were cached), ``slides_simulated``, ``slides_cached``, ``sim_warnings``
    (each distinct warning with its count)."""
    cache = cache or ArtefactCache.default()
    keys = [slide_key(j) for j in jobs]
    recs: list[Recording | None] = [
        cached_slide(cache, j, k) for j, k in zip(jobs, keys, strict=True)
    ]
    todo = [i for i, r in enumerate(recs) if r is None]
    warns: Counter[str] = Counter(
        str(w) for r in recs if r is not None for w in r.meta.get("warnings") or ()
    )
    t0 = time.perf_counter()
    if todo:
        n = workers or default_workers()
        n = 1 if len(todo) == 1 else n
        if log:
            log(f"simulating {len(todo)} slides ({len(jobs) - len(todo)} cached), {n} worker(s)")
        backend = make_backend(SlideWorker(str(cache.root)), workers=n)
        step = max(1, len(todo) // 10)
        try:
            for done, (i, out) in enumerate(stream(backend, ((i, jobs[i]) for i in todo)), 1):
                recs[i] = out.recording
                warns.update(out.warnings)
                if log and done % step == 0:
                    log(f"  {done}/{len(todo)} slides ({time.perf_counter() - t0:.0f} s)")
        finally:
            backend.close(cancel=True)
    sim_s = time.perf_counter() - t0 if todo else 0.0
    shapes = Counter(r.data.shape for r in recs)
    if len(shapes) > 1:
        raise ConfigError(f"simulated slides differ in shape: {dict(shapes)}")
    if log:
        for line in warning_lines(warns, len(jobs)):
            log(line)
    stats = {
        "simulate_s": sim_s,
        "slides_simulated": len(todo),
        "slides_cached": len(jobs) - len(todo),
        "sim_warnings": [f"{w} (x{c})" for w, c in warns.most_common()],
    }
    return recs, stats


def warning_lines(warns: Counter, n_slides: int) -> list[str]:
    """One line for each distinct simulation warning, with the number of slides it touched
    (most frequent first): what ``run`` and ``generate`` print."""
    return [f"warning: {w} ({c} of {n_slides} slides)" for w, c in warns.most_common()]


__all__ = [
    "BACKENDS",
    "Backend",
    "Done",
    "ProcessBackend",
    "RayBackend",
    "SerialBackend",
    "SlideOutcome",
    "default_workers",
    "make_backend",
    "run_slides",
    "stream",
    "warning_lines",
]
