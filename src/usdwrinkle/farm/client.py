"""``usdwrinkle render --dask``: bake once, render chunks on a Dask cluster, gather.

Flow:

1. Check everything a serial render checks, here, once, without a GL context: the
   stage, the WrinkleAPI values, the camera, the frames and the outputs.
2. Start a LocalCluster (worker processes, one thread each), or connect to a running
   scheduler (``tcp://host:port``).
3. Unless the stage already holds baked wave fields for every wrinkled mesh and frame,
   bake them: one sequential, compute-only pass in this process (the phase history runs
   in time order), written atomically to ``usdwrinkle_bake/STAGE_NAME.wrinkles.usdc``
   beside the outputs. The workers start as spawned processes before this process makes its GL
   context, so no context crosses a fork.
4. Submit chunks of ``--chunk`` frames (``retries``: a chunk whose worker dies runs
   again, and skips the frames that its first run finished); show one progress bar.
5. On any error or interruption: cancel the futures, shut a local cluster down, and
   remove the temporary files that killed workers may have left beside the outputs.
"""
from __future__ import annotations

import contextlib
import logging
import math
import os
import shutil
import tempfile
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..process.errors import UsdWrinkleError
from .worker import file_identity, remove_temporaries, render_chunk

_log = logging.getLogger(__name__)

#: how often Dask reruns a chunk whose worker died
RETRIES = 2
#: frames per chunk at most, when --chunk is not given
DEFAULT_CHUNK = 10


def _import_dask():
    try:
        import distributed
    except ImportError:
        raise UsdWrinkleError("`dask` needs Dask's distributed scheduler: "
                              "pip install 'usdwrinkle[farm]'") from None
    return distributed


def check_farm_options(scheduler: str | None, workers: int | None,
                       chunk: int | None) -> None:
    """Refuse farm options out of range, before any stage is read."""
    from ..process.limits import LOCAL_WORKERS_PER_CORE

    if scheduler is not None and not isinstance(scheduler, str):
        raise UsdWrinkleError(f"`dask`={scheduler!r} must be 'local' or a scheduler's address")
    chunk = _count(chunk, "chunk")
    workers = _count(workers, "workers")
    if chunk is not None and chunk < 1:
        raise UsdWrinkleError("`chunk` must be at least 1")
    if workers is not None:
        cores = os.cpu_count() or 1
        most = LOCAL_WORKERS_PER_CORE * cores
        if not 1 <= workers <= most:
            raise UsdWrinkleError(f"`workers` must be in 1..{most} ({LOCAL_WORKERS_PER_CORE} "
                                  f"worker processes per CPU core, {cores} here: each holds "
                                  "its own GL context)")


def _count(value, name: str) -> int | None:
    """An integer option (numpy's too); never a bool (``workers=True`` started one worker)
    nor a text."""
    import numbers

    if value is None:
        return None
    if isinstance(value, bool) or type(value).__name__ == "bool_" or \
            not isinstance(value, numbers.Integral):
        raise UsdWrinkleError(f"`{name}`={value!r} must be an integer")
    return int(value)


def default_chunk(frames: int, workers: int) -> int:
    """At most DEFAULT_CHUNK frames, and at least two chunks per worker where the shot
    allows, so that a short shot still spreads over every worker."""
    return max(1, min(DEFAULT_CHUNK, math.ceil(frames / (2 * max(workers, 1)))))


#: the folder beside the outputs that holds the farm's bake: every worker must reach it,
#: and the outputs' folder is what the farm shares, but it is not one of the frames
BAKE_FOLDER = "usdwrinkle_bake"


def bake_path(output_pattern: str, stage_path: str) -> str:
    """Where the farm bakes the wave fields: in BAKE_FOLDER beside the outputs (not among
    the frames), named after the stage."""
    folder = os.path.dirname(os.path.abspath(output_pattern))
    stem = os.path.splitext(os.path.basename(stage_path))[0]
    return os.path.join(folder, BAKE_FOLDER, f"{stem}.wrinkles.usdc")


def _has_bokeh() -> bool:
    import importlib.util
    return importlib.util.find_spec("bokeh") is not None


#: the Dask comm protocols a scheduler address may name (ucx needs ucx-py, inproc is
#: in-process only)
DASK_SCHEMES = ("tcp", "tls", "ws", "wss")


def _connect(distributed, address: str, workers: int | None):
    """(client, cluster or None, worker count)."""
    if address == "local":
        count = workers or os.cpu_count() or 1
        dashboard = ":0" if _has_bokeh() else None
        # CRITICAL: a local worker's "failed to communicate with scheduler during
        # heartbeat" when the machine is loaded, or at shutdown, is not the user's error
        # (task errors reach the user as the one-line error, not through these logs)
        # the workers' spill folder: a temporary folder of ours, not dask-scratch-space in
        # the user's working folder (removed with the cluster, _close)
        scratch = tempfile.mkdtemp(prefix="usdwrinkle-dask-")
        import dask

        # the scheduler's own scratch folder too (Dask's default: TMPDIR/dask-scratch-space,
        # which it leaves behind)
        with dask.config.set({"temporary-directory": scratch}):
            cluster = distributed.LocalCluster(
                n_workers=count, threads_per_worker=1, processes=True,
                silence_logs=logging.CRITICAL, dashboard_address=dashboard,
                local_directory=scratch)
        cluster.usdwrinkle_scratch = scratch
        return distributed.Client(cluster), cluster, count
    scheme = address.split("://", 1)[0].lower() if "://" in address else "tcp"
    if scheme not in DASK_SCHEMES:
        raise UsdWrinkleError(f"`dask` {address}: the '{scheme}' protocol is not supported "
                              f"(use {', '.join(s + '://' for s in DASK_SCHEMES)} HOST:PORT "
                              "or 'local')")
    try:
        client = distributed.Client(address, timeout="20s")
    except (OSError, TimeoutError, ValueError, TypeError, ImportError) as exc:
        raise UsdWrinkleError(f"cannot reach the Dask scheduler at '{address}' "
                              f"({type(exc).__name__}: {exc})") from None
    try:
        client.wait_for_workers(1, timeout=60)
    except (TimeoutError, OSError):
        client.close()
        raise UsdWrinkleError(f"the Dask scheduler at '{address}' has no workers "
                              "(start some with 'dask worker ADDRESS')") from None
    return client, None, len(client.scheduler_info()["workers"])


def _no_progress(items: list[Any], _what: str) -> list[Any]:
    return items


@dataclass(frozen=True)
class FarmRender:
    """A render job spread on Dask (app/render.RenderJob.run with ``dask``): the job,
    checked and planned by its ``prepare``, and how to spread it.

    The job gives what the farm asks of it: ``plan_chunks(plan)`` (the frame request and
    write options, and whether to bake), ``check_output(path)``, ``bake_fields(layer,
    frame_spec)`` and ``chunk_engine(stage, baked)``; ``output`` and ``shot.path``."""

    job: Any
    plan: Any
    #: the frames as the user wrote them (recorded in the bake's layer), or None
    frame_spec: str | None = None
    #: "local" (a LocalCluster) or a scheduler's address
    scheduler: str = "local"
    workers: int | None = None
    chunk: int | None = None
    #: wraps a list of frames in a progress bar (advanced as chunks finish)
    progress: Callable[[list[Any], str], Any] = _no_progress
    #: prints a status line (where it renders, the bake's time); None: silent
    say: Callable[[str], None] | None = None
    #: called once the workers are up, before the bake (the command's header line)
    on_start: Callable[[], None] | None = None


@dataclass(frozen=True)
class FarmResult:
    """What a farm render did: the frames written, meshes whose wave fields were baked,
    the image size, the wall time, and how the frames were spread."""

    written: list
    baked: list
    width: int
    height: int
    elapsed: float
    workers: int
    chunk: int
    #: frames --skip-existing found complete
    skipped: int = 0


def render_on_dask(request: FarmRender) -> FarmResult:
    """Run a farm render; warnings are logged (usdwrinkle/process/log.py), the workers' too."""
    distributed = _import_dask()
    job, plan = request.job, request.plan
    say = request.say
    frames, outputs = list(plan.frames), list(plan.outputs)
    # the checks of a serial render, once, here (no GL context)
    chunks = job.plan_chunks(plan)
    layer = bake_path(job.output, job.shot.path) if chunks.needs_bake else None
    if layer is not None:
        job.check_output(layer)
    width, height = chunks.request.width, chunks.request.height

    started = time.perf_counter()
    client = cluster = None
    futures = []
    try:
        client, cluster, workers = _connect(distributed, request.scheduler, request.workers)
        # the run's header (version, stage, this process's GL, which bakes), as a serial
        # render's log starts: made once the workers are spawned, so no context precedes them
        if request.on_start is not None:
            request.on_start()
        if say is not None:
            where = "a local cluster" if cluster is not None else request.scheduler
            dashboard = client.dashboard_link if cluster is None or _has_bokeh() \
                else "none (pip install bokeh for Dask's dashboard)"
            say(f"usdwrinkle: rendering on {where}, {workers} worker(s); "
                f"dashboard: {dashboard}")
        render_stage = job.shot.path
        if layer is not None:
            bake_started = time.perf_counter()
            os.makedirs(os.path.dirname(layer), exist_ok=True)
            job.bake_fields(layer, request.frame_spec)
            if say is not None:
                say(f"usdwrinkle: baked wave fields to {layer} in "
                    f"{time.perf_counter() - bake_started:.1f} s")
            render_stage = layer
        engine_options = job.chunk_engine(render_stage, baked=layer is not None)
        chunk = request.chunk or default_chunk(len(frames), workers)
        before = [file_identity(p) for p in outputs]
        run_id = uuid.uuid4().hex[:8]
        for index, start in enumerate(range(0, len(frames), chunk)):
            part = slice(start, start + chunk)
            futures.append(client.submit(
                render_chunk, engine_options, chunks.request, chunks.writing, frames[part],
                outputs[part], before[part], job.options.skip_existing, retries=RETRIES,
                pure=False, key=f"usdwrinkle-{run_id}-chunk-{index:05d}"))
        written, baked, skipped = _gather(distributed, futures, plan, request.progress)
        return FarmResult(written, baked, width, height, time.perf_counter() - started,
                          workers, chunk, skipped)
    finally:
        for future in futures:
            future.cancel()
        if client is not None:
            with contextlib.suppress(Exception):  # closing must not mask the error
                client.close()
        if cluster is not None:
            with contextlib.suppress(Exception):
                cluster.close()
            shutil.rmtree(cluster.usdwrinkle_scratch, ignore_errors=True)
        remove_temporaries(outputs)  # killed workers never reach atomic_path's cleanup


def _gather(distributed, futures, plan: Any,
            progress: Callable[[list[Any], str], Any]) -> tuple[list, list[str], int]:
    """Wait for every chunk; returns (the frames written, in the plan's order, the baked
    meshes, the frames skipped). The first input error raises as the serial one would.
    ``progress`` wraps the plan's frames, one step a frame as its chunk finishes."""
    frame_of = dict(zip(plan.outputs, plan.frames, strict=True))
    done: set = set()
    skipped = 0
    baked: set[str] = set()
    ticks = iter(progress(list(plan.frames), "render"))
    try:
        for future in distributed.as_completed(futures):
            try:
                result = future.result()
            except distributed.client.FutureCancelledError:
                continue
            except distributed.KilledWorker as exc:
                raise UsdWrinkleError(
                    f"Dask workers died {RETRIES + 1} times while rendering one chunk "
                    f"({exc}); see the workers' logs") from None
            for message in result["warnings"]:
                _log.warning("%s", message)
            if result["error"] is not None:
                error = result["error"]
                raise UsdWrinkleError(error["what"], error["prim_path"], error["attribute"],
                                      error["frame"])
            finished = list(result["written"]) + [frame_of[p] for p in result["earlier"]]
            done.update(finished)
            skipped += len(result["skipped"])
            baked.update(result["baked"])
            for _ in range(len(finished) + len(result["skipped"])):
                next(ticks, None)
        for _ in ticks:  # the bar's end
            pass
    finally:
        close = getattr(ticks, "close", None)
        if close is not None:
            close()
    return [f for f in plan.frames if f in done], sorted(baked), skipped
