"""Dask for ``animate`` and ``render``: a local cluster started once per job, or a running one.

- :func:`scheduler_address` checks ``--scheduler`` and :func:`probe` talks to it before Dask
  does: a server that accepts TCP but never answers ends in a handshake timeout, and one that
  answers with something else (an HTTP server, a huge length) is named for what it is not,
  instead of Dask waiting forever or allocating the length it read.
- :func:`worker_cap` holds ``--workers`` to the cores and the memory this machine has.
- :class:`LocalStart` starts a ``LocalCluster`` in the background (the caller keeps working
  meanwhile) and reports how long it took; :func:`connect` reaches a running scheduler.
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


class LocalStart:
    """A ``LocalCluster`` of ``workers`` single-threaded processes, started in a background
    thread so that the caller keeps rendering meanwhile. ``ready`` is set when the client is
    up (or the start failed: ``error``); ``seconds`` is how long the start took."""

    def __init__(self, workers: int):
        self.workers = workers
        self.client = self.cluster = self.error = None
        self.seconds = None
        self.ready = threading.Event()
        self.t0 = time.perf_counter()
        self._thread = threading.Thread(target=self._start, daemon=True)
        self._thread.start()

    def _start(self) -> None:
        try:
            dask, Client, LocalCluster = _dask()
            # one numba thread a worker: the workers are the parallelism
            self.cluster = LocalCluster(n_workers=self.workers, threads_per_worker=1,
                                        processes=True, dashboard_address=None,
                                        env={"NUMBA_NUM_THREADS": "1"})
            self.client = Client(self.cluster)
        except Exception as error:                   # noqa: BLE001 - reported by the caller
            self.error = error
        self.seconds = time.perf_counter() - self.t0
        self.ready.set()

    def close(self) -> None:
        """Close the client and the cluster (after the start, if it is still going on)."""
        self._thread.join()
        if self.client is not None:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()
        self.client = self.cluster = None
