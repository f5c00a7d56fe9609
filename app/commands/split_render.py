"""``render --scheduler ADDR`` (or ``--workers N``): one ray-traced frame split across a cluster.

The frame is cut into bands of rows; each band is a task that traces its rows at every
sample of the pixel (:func:`core.renderers.raytrace.draw.trace_tile`) on a worker, which reads the
scene from the job's bundle (:mod:`app.commands.bundle`: the scene file and every file it names,
so the worker needs only the package) and prepares it once (BVH and all) for every band it
traces. A pixel's colour depends on its own rays only, so the assembled bands are exactly the
picture one process traces (the test compares them byte for byte).

Only the ray tracer traces by tiles. ``--workers N`` starts a local cluster of N single-thread
workers only when they would have more cores than this process's tracer, whose kernels run on
``numba.get_num_threads()`` threads: by default one a core, so a local cluster would share the
same cores, pay its start (~2 s) and build the scene's BVH once more per worker, and cannot
win (measured: docs/movies.md); the output says so and the frame is traced here. With fewer
kernel threads than cores (``NUMBA_NUM_THREADS``), the cluster is started and the picture is
the same.
"""

from __future__ import annotations

import math
import os

import numpy as np

BANDS_PER_WORKER = 4
_prepared: dict = {}


def can_split(settings) -> str | None:
    """Why this frame cannot be split across a cluster, or None."""
    if settings.renderer != "raytrace":
        return f"only ray-traced frames are split across workers (this one is {settings.renderer})"
    if settings.sample_pattern == "adaptive":
        return "adaptive sampling is not split across workers"
    return None


def local_problem(workers: int) -> str | None:
    """Why ``workers`` local single-thread workers cannot beat this process's tracer, or None:
    they would run on no more cores than its kernel threads already do."""
    import numba
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    threads = min(numba.get_num_threads(), cores)
    if min(workers, cores) > threads:
        return None
    return (f"a local cluster of {workers} cannot beat this process, whose ray tracer already "
            f"runs on {threads} of the {cores} cores here (the workers would share them and "
            "pay their start)")


def bands(height: int, workers: int) -> list[tuple[int, int]]:
    """``(row0, row1)`` bands covering the image, about BANDS_PER_WORKER a worker."""
    step = max(1, math.ceil(height / (workers * BANDS_PER_WORKER)))
    return [(r, min(r + step, height)) for r in range(0, height, step)]


def trace_band(bundle, view_number: int, settings, demo, rows) -> tuple[tuple[int, int], np.ndarray]:
    """A worker's task: the rows ``[row0, row1)`` of the frame, as uint8 colours."""
    from core.renderers.raytrace.draw import trace_tile
    from core.shading.illumination import to_uint8
    setup = _setup(bundle, view_number, settings, demo)
    return rows, to_uint8(trace_tile(setup, rows[0], rows[1], 0, setup.width))


def _setup(bundle, view_number, settings, demo):
    """The traced frame's Setup, made once per worker for the same job."""
    key = (bundle.digest, view_number, settings, demo)
    if _prepared.get("key") != key:
        from app.commands.bundle import unpack
        from core.camera.film import sample_offsets
        from core.renderers.raytrace.draw import TraceOptions, prepare
        from core.scene.formats import load_scene
        from core.scene.view_numbers import index_of
        from core.texture.demo_scene import apply_demo_options
        scene = load_scene(unpack(bundle), size=settings.size)
        apply_demo_options(scene, *demo)
        view = scene.views[index_of(scene, view_number)]
        offsets = (sample_offsets(settings.samples, settings.sample_pattern, settings.seed)
                   if settings.samples > 1 else np.array([settings.pixel_offset], np.float64))
        _prepared["setup"] = prepare(scene, view, settings.projection, settings.size,
                                     TraceOptions.from_settings(settings), offsets,
                                     settings.keep_aspect)
        _prepared["key"] = key
    return _prepared["setup"]


def render_split(client, bundle, view_number: int, settings, demo, retries: int = 2,
                 workers: int = 1) -> np.ndarray:
    """The frame, traced band by band on the cluster of ``client`` and assembled here."""
    from app.commands.cluster import completed
    width, height = settings.size
    color = np.empty((height, width, 3), np.uint8)
    shipped = client.scatter(bundle, broadcast=True, hash=False)
    futures = [client.submit(trace_band, shipped, view_number, settings, demo, rows,
                             retries=retries, pure=False) for rows in bands(height, workers)]
    done, left = completed(client, futures), len(futures)
    while left:
        for future in done.next_batch(block=True):
            (row0, row1), band = future.result()
            color[row0:row1] = band
            left -= 1
    return color


def split_frame(args, settings):
    """``render``'s scale-out: ``(color, where)`` traced on the cluster, or ``(None, note)``
    when this process renders the frame itself (the note says why); ClusterError when the
    cluster cannot be used."""
    from app.commands import cluster
    from app.commands.bundle import load_recorded
    from core.scene.formats import load_scene
    why = can_split(settings)
    if why is None and args.time is not None:
        why = "--time frames are not split across workers"
    if why is None and args.course_tri:
        why = "--course-tri frames are not split across workers"
    capped = None
    if why is None and not args.scheduler:
        workers, capped = cluster.worker_cap(args.workers)
        why = local_problem(workers)
    if why is not None:
        return None, f"note: {capped + '; ' if capped else ''}{why}: rendering in this process"
    _, bundle = load_recorded(args.scene, lambda path: load_scene(path, size=args.size))
    demo = (args.bump_map, not args.no_bump)
    if not args.scheduler:
        start = cluster.LocalStart(workers, preload=(__name__,))
        try:
            start.ready.wait()
            if start.error is not None:
                raise cluster.ClusterError(f"the local cluster did not start: {start.error}")
            color = render_split(start.client, bundle, args.view, settings, demo, workers=workers)
        finally:
            start.close()
        return color, (f"traced by {workers} local workers (started in {start.seconds:.1f} s)"
                       + (f"; {capped}" if capped else ""))
    client = cluster.connect(args.scheduler)
    try:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        color = render_split(client, bundle, args.view, settings, demo, workers=workers)
    finally:
        client.close()
    return color, f"traced on the cluster at {args.scheduler} ({workers} workers)"
