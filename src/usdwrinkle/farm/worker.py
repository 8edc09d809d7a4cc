"""A chunk of a render's frames, as a farm's worker runs it (farm/: Dask's tasks).

One engine per worker process, kept across tasks: the GL context and the compiled
passes cost most of a short chunk. It is created lazily inside the first task, on the
thread that runs tasks, never in the parent before the workers start (an EGL context
does not survive a fork: moderngl issue 414), and made current on the task's thread
for each chunk.

Input errors come back as a value, not an exception: the client reports the first
one as the one-line error of a serial render, and Dask neither retries it nor logs a
remote traceback. Anything else raises, and Dask retries the chunk (``retries``).
"""
from __future__ import annotations

import os
import threading
from typing import Any

from ..engine import EngineOptions
from ..frameloop import render_frames
from ..images.aovs import exr_channels
from ..images.imagefiles import is_complete_image
from ..process.errors import UsdWrinkleError
from ..process.log import warnings_to

_lock = threading.Lock()
_cached: dict[str, Any] = {"key": None, "engine": None}


def _engine(options: EngineOptions) -> Any:
    """This process's engine for ``options`` (a new stage or options replaces it)."""
    key = (options, threading.get_ident())
    if _cached["key"] != key:
        if _cached["engine"] is not None:
            _cached["engine"].release()
            _cached["engine"] = _cached["key"] = None
        _cached["engine"] = options.create()
        _cached["key"] = key
    return _cached["engine"]


def file_identity(path: str) -> tuple[int, int] | None:
    """(device, inode) of an existing file, else None: an atomic write makes a new inode."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return (st.st_dev, st.st_ino)


def written_this_run(path: str, before: tuple[int, int] | None) -> bool:
    """True when ``path`` was written after the run took its snapshot ``before``
    (None: the file did not exist then). A retried chunk skips these frames, so that
    no frame is written twice."""
    try:
        st = os.stat(path)
    except OSError:
        return False
    return (st.st_dev, st.st_ino) != before and st.st_size > 0


def render_chunk(options: EngineOptions, request: Any, writing: Any,
                 frames: list[float | None], paths: list[str],
                 before: list[tuple[int, int] | None], skip_existing: bool) -> dict[str, Any]:
    """Render ``frames`` to ``paths`` as ``request`` (render/request.FrameRequest) and
    ``writing`` (outputs/writer.WriteOptions) say; returns {"written", "earlier",
    "skipped", "warnings", "error", "baked", "worker"}: "earlier" are frames this run
    wrote in an attempt at the chunk whose worker died, "skipped" the complete frames
    `skip_existing` kept.

    ``before``: each path's file identity when the run started (file_identity).
    """
    result: dict[str, Any] = {"written": [], "earlier": [], "skipped": [], "warnings": [],
                              "error": None, "baked": [], "worker": os.getpid()}
    previous = dict(zip(paths, before, strict=True))

    def skip(path: str) -> bool:
        if written_this_run(path, previous[path]):  # by an attempt whose worker died
            result["earlier"].append(path)
            return True
        if skip_existing and is_complete_image(path, request.width, request.height,
                                               exr_channels(request.layout.aovs)):
            result["skipped"].append(path)
            return True
        return False

    from ..render.context import create_context

    # this chunk's warnings (also those of a cached engine's later frames) go back to the
    # client, which prints each once
    with _lock, warnings_to(result["warnings"].append):
        try:
            # current on this thread for the whole chunk: the previous chunk's exit made it
            # not current, and replacing the engine (a new job on a long-running worker)
            # releases and compiles GL objects
            with create_context():
                engine = _engine(options)
                result["written"] = render_frames(engine, request, writing, frames, paths,
                                                  skip=skip)
            result["baked"] = engine.baked_paths
        except UsdWrinkleError as exc:
            result["error"] = {"what": exc.what, "prim_path": exc.prim_path,
                               "attribute": exc.attribute, "frame": exc.frame,
                               "type": type(exc).__name__}
    return result


def remove_temporaries(paths: list[str]) -> None:
    """Remove what killed workers left beside ``paths`` (their writers never reach
    atomic_path's cleanup)."""
    from ..outputs.atomic import remove_temporaries as remove

    for path in paths:
        remove(path)
