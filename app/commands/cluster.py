"""Dask for ``animate`` and ``render``: a local cluster started once per job, or a running one.

- :func:`scheduler_address` checks ``--scheduler`` and :func:`probe` talks to it before Dask
  does: a server that accepts TCP but never answers ends in a handshake timeout, and one that
  answers with something else (an HTTP server, a huge length) is named for what it is not,
  instead of Dask waiting forever or allocating the length it read.
- :func:`worker_cap` holds ``--workers`` to the cores and the memory this machine has.
- :class:`LocalStart` starts local workers in the background (the caller keeps working
  meanwhile) and reports how long it took; :func:`connect` reaches a running scheduler.
  Local workers are a plain process pool (:class:`LocalPool`) with the part of Dask's
  client the callers use: on this two-core machine a Dask ``LocalCluster`` cost ~2 s of CPU
  to reach its first frame (its import in two processes, its scheduler and nanny) against
  ~1.2 s for a process that imports the package and loads the kernel cache, and a job of a
  few seconds on two cores cannot pay the difference.
- The workers' logs are quiet (errors only): a failing task is reported once, by the caller,
  in one line, not by every worker as a traceback.

Why Dask rather than Ray: Dask's wheels are pure Python (Ray's are a ~70 MB C++ core per
platform and Python version, which lag new Pythons), a local cluster starts in a few seconds,
and ``submit(..., retries=)`` and ``as_completed`` are exactly the retry-a-task and
collect-as-they-complete this needs.
"""

from __future__ import annotations

import os
import re
import socket
import struct
import threading
import time

HANDSHAKE_TIMEOUT = 10.0             # seconds a scheduler may take to send its handshake
MAX_HANDSHAKE_BYTES = 1 << 20        # a Dask handshake is a few hundred bytes
WORKER_MEMORY = 400 * (1 << 20)      # what one worker process needs for our frames (measured
                                     # 100-250 MB at 500 x 500; with room to spare)
_ADDRESS = re.compile(r"(?:tcp://)?(\[[0-9a-fA-F:.]+\]|[A-Za-z0-9._-]+):([0-9]{1,5})")


class ClusterError(RuntimeError):
    """The cluster cannot be used; the message says why, in one line."""


def scheduler_address(text: str) -> tuple[str, str, int]:
    """``(address, host, port)`` of ``--scheduler`` text (``tcp://HOST:PORT`` or
    ``HOST:PORT``), or ClusterError."""
    match = _ADDRESS.fullmatch(text.strip())
    shown = text if len(text) <= 60 else text[:60] + "..."
    if not match or not 0 < int(match.group(2)) < 65536:
        raise ClusterError(f"--scheduler {shown!r}: expected a Dask scheduler's address, "
                           "tcp://HOST:PORT (e.g. tcp://127.0.0.1:8786)")
    host, port = match.group(1).strip("[]"), int(match.group(2))
    return f"tcp://{match.group(1)}:{port}", host, port


def probe(text: str, timeout: float | None = None) -> str:
    """Connect to the scheduler at ``text`` and read its handshake's length; return the
    address for Dask, or ClusterError saying what the server is not."""
    timeout = HANDSHAKE_TIMEOUT if timeout is None else timeout
    address, host, port = scheduler_address(text)
    try:
        conn = socket.create_connection((host, port), timeout=timeout)
    except socket.gaierror as error:
        raise ClusterError(f"--scheduler {address}: unknown host {host!r} ({error.strerror})") from None
    except OSError as error:
        why = "timed out" if isinstance(error, TimeoutError) else (error.strerror or str(error))
        raise ClusterError(f"cannot reach the Dask scheduler at {address}: {why}") from None
    with conn:
        head = _read(conn, 8, timeout)
        if len(head) < 8:
            if head:
                raise ClusterError(f"--scheduler {address} is not a Dask scheduler: it sent "
                                   f"{len(head)} bytes and closed the connection")
            if _speaks_http(conn):
                raise ClusterError(f"--scheduler {address} is an HTTP server, not a Dask "
                                   "scheduler (the scheduler's port is 8786 by default; 8787 "
                                   "is its dashboard)")
            raise ClusterError(f"--scheduler {address} is not a Dask scheduler: it accepted the "
                               f"connection but sent no handshake within {timeout:g} s")
        if head.startswith(b"HTTP/"):
            raise ClusterError(f"--scheduler {address} is an HTTP server, not a Dask scheduler")
        (length,) = struct.unpack("<Q", head)
        if not 0 < length <= MAX_HANDSHAKE_BYTES:
            raise ClusterError(f"--scheduler {address} is not a Dask scheduler: its first "
                               f"message claims {length} bytes (a handshake is a few hundred)")
    return address


def _read(conn: socket.socket, n: int, timeout: float) -> bytes:
    """Up to ``n`` bytes, waiting at most ``timeout`` seconds in all."""
    data = b""
    deadline = time.monotonic() + timeout
    while len(data) < n:
        left = deadline - time.monotonic()
        if left <= 0:
            break
        conn.settimeout(left)
        try:
            chunk = conn.recv(n - len(data))
        except (TimeoutError, OSError):
            break
        if not chunk:
            break
        data += chunk
    return data


def _speaks_http(conn: socket.socket) -> bool:
    """Does a silent server answer an HTTP request (a web server given the wrong port)?"""
    try:
        conn.sendall(b"HEAD / HTTP/1.0\r\n\r\n")
    except OSError:
        return False
    return _read(conn, 5, 2.0) == b"HTTP/"


def worker_cap(asked: int) -> tuple[int, str | None]:
    """``(workers, why fewer)``: at most one worker a core, and as many as the available
    memory holds at ``WORKER_MEMORY`` each (never fewer than one)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    try:
        available = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        available = asked * WORKER_MEMORY
    by_memory = max(1, available // WORKER_MEMORY)
    used = max(1, min(asked, cores, by_memory))
    if used == asked:
        return used, None
    reasons = []
    if cores < asked:
        reasons.append(f"{cores} cores")
    if by_memory < asked:
        reasons.append(f"{available / (1 << 30):.1f} GiB of memory free, "
                       f"~{WORKER_MEMORY >> 20} MB a worker")
    return used, f"--workers {asked}: using {used} ({' and '.join(reasons)} here)"


def quiet_dask() -> None:
    """Workers log errors only (their processes inherit this environment): a failed task is
    reported once by the caller, not as a traceback from every worker. Their statistical
    profiler (a stack sample every 10 ms, for a dashboard nobody opens) is off."""
    os.environ.setdefault("DASK_LOGGING__DISTRIBUTED", "critical")   # its children inherit it
    os.environ.setdefault("DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED", "False")
    import dask
    dask.config.set({"distributed.worker.profile.enabled": False})
    import logging
    for name in ("distributed", "distributed.worker", "distributed.scheduler",
                 "distributed.nanny", "distributed.client", "distributed.core"):
        logging.getLogger(name).setLevel(logging.CRITICAL)


def _dask():
    try:
        quiet_dask()
        import dask
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise ClusterError("--workers and --scheduler need Dask: "
                           "pip install 'fvd-viewer[anim]'") from None
    return dask, Client, LocalCluster


def connect(text: str):
    """A Client on the running scheduler at ``text`` (probed first)."""
    address = probe(text)
    dask, Client, _ = _dask()
    try:
        with dask.config.set({"distributed.comm.timeouts.connect": f"{HANDSHAKE_TIMEOUT}s"}):
            return Client(address, timeout=HANDSHAKE_TIMEOUT)
    except (OSError, TimeoutError) as error:
        raise ClusterError(f"cannot reach the Dask scheduler at {address}: {error}") from None


def completed(client, futures=()):
    """Dask's ``as_completed`` for ``client``'s futures (``add``, ``has_ready``,
    ``next_batch``), whichever kind of client it is."""
    if isinstance(client, LocalPool):
        done = _Completed()
    else:
        from dask.distributed import as_completed
        done = as_completed()
    for future in futures:
        done.add(future)
    return done


def _one_thread_worker(preload: tuple[str, ...]) -> None:
    """A local worker's start: one kernel thread (the workers are the parallelism), and the
    modules its tasks need imported now rather than by its first task."""
    import importlib

    import numba
    numba.set_num_threads(1)
    for name in preload:
        importlib.import_module(name)


def _started() -> int:
    return os.getpid()


def _retrying(fn, retries: int, *args):
    """``fn(*args)``, tried again up to ``retries`` times when it raises (Dask's ``retries=``)."""
    for attempt in range(retries + 1):
        try:
            return fn(*args)
        except Exception:                            # noqa: BLE001 - the last one is raised
            if attempt == retries:
                raise


class LocalPool:
    """``workers`` single-thread worker processes on this machine (spawned: each imports the
    package and loads the kernel cache once), with the part of a Dask client that
    ``animate`` and ``render`` use: ``scatter``, ``submit(..., retries=)`` and
    :func:`completed`. ``preload`` names the modules each worker imports as it starts."""

    def __init__(self, workers: int, preload: tuple[str, ...] = ()):
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor
        self.workers = workers
        self.executor = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"),
                                            initializer=_one_thread_worker, initargs=(preload,))

    def scatter(self, data, **_):
        return data                                  # sent with each task, by pickle

    def submit(self, fn, *args, retries: int = 0, pure=None):
        return self.executor.submit(_retrying, fn, retries, *args)

    def close(self) -> None:
        self.executor.shutdown(wait=True, cancel_futures=True)


class _Completed:
    """Futures as they complete, for :class:`LocalPool` (Dask's ``as_completed`` subset)."""

    def __init__(self):
        import queue
        self.queue = queue.SimpleQueue()

    def add(self, future) -> None:
        future.add_done_callback(self.queue.put)

    def has_ready(self) -> bool:
        return not self.queue.empty()

    def next_batch(self, block: bool = True) -> list:
        import queue
        batch = [self.queue.get()] if block else []
        while True:
            try:
                batch.append(self.queue.get_nowait())
            except queue.Empty:
                return batch


class LocalStart:
    """A :class:`LocalPool` of ``workers`` processes, started in the background so that the
    caller keeps rendering meanwhile. ``ready`` is set when every worker has started (or the
    start failed: ``error``); ``seconds`` is how long the start took."""

    def __init__(self, workers: int, preload: tuple[str, ...] = ()):
        self.workers = workers
        self.error = None
        self.seconds = None
        self.ready = threading.Event()
        self.t0 = time.perf_counter()
        self.client = LocalPool(workers, preload)
        self._waiting = workers
        self._lock = threading.Lock()
        for _ in range(workers):                     # spawns them (a pool starts on demand)
            self.client.executor.submit(_started).add_done_callback(self._one_started)

    def _one_started(self, future) -> None:
        with self._lock:
            if future.exception() is not None and self.error is None:
                self.error = future.exception()
            self._waiting -= 1
            if self._waiting == 0 or self.error is not None:
                self.seconds = time.perf_counter() - self.t0
                self.ready.set()

    def close(self) -> None:
        """Stop the workers (after the start, if it is still going on)."""
        if self.client is not None:
            self.client.close()
        self.client = None
