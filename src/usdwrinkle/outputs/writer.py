"""Encode frame f while frame f + 1 renders: a bounded writer thread.

OpenImageIO releases the GIL while it encodes, and llvmpipe renders on its own threads,
so the encode of one frame overlaps the next frame's USD read, compute and draw. At most
``max_in_flight`` frames wait or encode at once, which bounds memory. Every write stays
atomic and complete (images.write_image). A write that fails reaches the caller as its
one-line error at the next submit or at the end; frames submitted before it are whole.
On any exit, also Ctrl-C or SIGTERM in the main thread, the frames already handed over
are finished (or their temporary files removed) before the exception goes on.
"""
from __future__ import annotations

import os
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass

#: the most writer threads (--write-threads); the automatic count stays below it too
MAX_THREADS = 64
#: the share of the available memory that frames waiting for or in encoding may hold
MEMORY_SHARE = 0.25


@dataclass(frozen=True)
class WriteOptions:
    """How a render's frames are written (the frame loop's writer, images.write_image)."""

    #: writer threads: frame f is encoded while f + 1 renders; 0 encodes in the render loop
    threads: int = 1
    #: frames that may wait or encode at once (frames_in_flight)
    in_flight: int = 2
    #: EXR compression (images.EXR_COMPRESSIONS)
    exr_compression: str = "zip"
    #: OpenEXR's own threads per EXR file (exr_threads)
    exr_threads: int = 0


def cores() -> int:
    """The CPU cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def default_threads(exr: bool = False) -> int:
    """Writer threads when none are asked for: every core but one, which renders (on a
    2-core machine 1; on a 16-core GPU node 15). Both encoders release the GIL, so the
    threads encode in parallel (docs/benchmarks.md: encoding). EXR files, whose chunks
    OpenEXR compresses on threads of its own (exr_file_threads), get the cores but one
    shared out: on a 16-core node 4 writer threads of 4 (a 24-frame chunk of 1080p frames
    then ends waiting for one file, not for 15 compressed on one core each:
    docs/benchmarks-gpu.md)."""
    per_file = exr_file_threads() if exr else 0
    if per_file > 1:
        return max(1, min(int((cores() - 1) / per_file + 0.5), MAX_THREADS))
    return max(1, min(cores() - 1, MAX_THREADS))


def exr_file_threads() -> int:
    """OpenEXR's own threads per EXR file by default: a quarter of the cores, at least 1
    and at most 4; none on 1 core. On 2 cores, 1 (24 CesiumMan frames at 1080p: 2.13 fps
    and 8% of the loop waiting for the writer, against 1.81 fps and 35% compressing in the
    writer thread; docs/benchmarks.md); on a 16-core H200 node 4 (26.0 fps against 19.0
    for the shirt)."""
    count = cores()
    return 0 if count < 2 else max(1, min(4, count // 4))


def exr_threads(chunked: bool = False) -> int:
    """OpenEXR's threads per EXR file of a render (outputs/images.py): exr_file_threads,
    0 for a farm's worker process (one of one per core), or $USDWRINKLE_EXR_THREADS
    where it is set."""
    from ..process.errors import UsdWrinkleError

    given = os.environ.get("USDWRINKLE_EXR_THREADS", "").strip()
    if not given:
        return 0 if chunked else exr_file_threads()
    if not (given.isascii() and given.isdigit()) or int(given) > MAX_THREADS:
        raise UsdWrinkleError(f"USDWRINKLE_EXR_THREADS must be in 0..{MAX_THREADS}, not "
                              f"'{given}'")
    return int(given)


def frames_in_flight(threads: int, frame_bytes: int) -> int:
    """Frames that may wait or encode at once: one per thread and one more, so that no
    thread idles while the next frame renders, and no more than MEMORY_SHARE of the
    available memory holds (at least 2: frame f encodes while f + 1 renders)."""
    from ..process.memory import available_memory

    wanted = threads + 1
    available = available_memory()
    if available is not None and frame_bytes > 0:
        wanted = min(wanted, int(available * MEMORY_SHARE) // frame_bytes)
    return max(2, wanted)


class FrameWriter:
    """``with FrameWriter(write) as writer: writer.submit(frame, path, image)``.

    ``write(path, image)`` runs on the writer thread; ``threads=0`` writes in the
    caller's thread (the serial path). ``written`` lists the frames whose files are
    complete, in order.
    """

    def __init__(self, write, threads: int = 1, max_in_flight: int = 2):
        self.write = write
        self.max_in_flight = max(1, max_in_flight)
        self.pool = ThreadPoolExecutor(threads, thread_name_prefix="usdwrinkle-writer") \
            if threads > 0 else None
        self.pending: deque[tuple[float, Future]] = deque()
        self.written: list[float | None] = []
        #: seconds the caller waited for the writer (the part of encoding not hidden)
        self.waited = 0.0

    def submit(self, frame: float | None, path: str, image) -> None:
        if self.pool is None:
            self.write(path, image)
            self.written.append(frame)
            return
        while len(self.pending) >= self.max_in_flight:
            self._finish_oldest()
        self.pending.append((frame, self.pool.submit(self.write, path, image)))

    def _finish_oldest(self) -> None:
        import time

        frame, future = self.pending.popleft()
        started = time.perf_counter()
        try:
            future.result()  # raises the writer's error here, in the caller's thread
        finally:
            self.waited += time.perf_counter() - started
        self.written.append(frame)

    def close(self) -> None:
        """Wait for every frame handed over; raise the first write error."""
        while self.pending:
            self._finish_oldest()

    def __enter__(self) -> FrameWriter:
        return self

    def shutdown(self) -> None:
        """Finish (or clean up) what was handed over, without raising its errors."""
        if self.pool is not None:
            self.pool.shutdown(wait=True)
            self.pending.clear()

    def __exit__(self, kind, value, traceback) -> None:
        try:
            if kind is None:
                self.close()
        finally:
            self.shutdown()
