"""Record frames with Storm, usdview's Hydra renderer, as usdrecord does.

Runs in a Python that has Blender's ``bpy`` wheel (OpenUSD 25.08 with UsdImagingGL,
UsdAppUtils and the Storm plugin), never in usdwrinkle's own process: the two USD builds
cannot share one. realclients/__init__.py starts it:

    python storm_client.py JOBS.json

JOBS.json: a list of {"stage", "camera" (prim path, "" for usdrecord's automatic
framing), "frame" (null: the default time), "width", "out" (.png: 8-bit sRGB as usdview
shows it; .exr: linear), "purposes" (default ["default", "proxy"], usdview's),
"camera_light" (usdview's default headlight; default true)}. Each job's image goes to
"out"; a line "ok OUT" or "failed OUT: reason" per job on stdout, and "seconds S OUT":
the time Record took.

Setup (verified here, GUIDE.md section 7): ``import bpy`` first, then its site-packages
first on sys.path; a current EGL context of the compatibility profile (a core profile
makes Storm raise harmless GL_POINT_SPRITE errors); a complete framebuffer bound; the
process ends with os._exit (Storm's C++ teardown sometimes aborts after a good image).
"""
from __future__ import annotations

import ctypes
import importlib.util
import os
import sys

EGL_PLATFORM_SURFACELESS_MESA = 0x31DD
EGL_OPENGL_API = 0x30A2
EGL_CONTEXT_MAJOR_VERSION = 0x3098
EGL_CONTEXT_MINOR_VERSION = 0x30FB
EGL_CONTEXT_OPENGL_PROFILE_MASK = 0x30FD
EGL_CONTEXT_OPENGL_COMPATIBILITY_PROFILE_BIT = 0x2
EGL_NONE = 0x3038


def import_blender_pxr():
    """Blender's pxr modules (UsdAppUtils, UsdImagingGL), importable after ``bpy``."""
    root = os.path.dirname(importlib.util.find_spec("bpy").origin)
    import bpy  # noqa: F401  (loads the libraries Blender's pxr links against)

    version = next(name for name in os.listdir(root) if name[:1].isdigit())
    sys.path.insert(0, os.path.join(root, version, "python", "lib", "python3.11",
                                    "site-packages"))


def egl_compatibility_context() -> None:
    """Make a surfaceless EGL context of the GL 4.5 compatibility profile current."""
    egl = ctypes.CDLL("libEGL.so.1")
    egl.eglGetProcAddress.restype = ctypes.c_void_p
    egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]
    get_display = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_uint, ctypes.c_void_p,
                                   ctypes.c_void_p)(
        egl.eglGetProcAddress(b"eglGetPlatformDisplayEXT"))
    display = ctypes.c_void_p(get_display(EGL_PLATFORM_SURFACELESS_MESA, None, None))
    major, minor = ctypes.c_int(), ctypes.c_int()
    if not egl.eglInitialize(display, ctypes.byref(major), ctypes.byref(minor)):
        raise RuntimeError("eglInitialize failed")
    egl.eglBindAPI(EGL_OPENGL_API)
    attributes = (ctypes.c_int * 7)(EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                    EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                    EGL_CONTEXT_OPENGL_COMPATIBILITY_PROFILE_BIT, EGL_NONE)
    egl.eglCreateContext.restype = ctypes.c_void_p
    egl.eglCreateContext.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                                     ctypes.c_void_p]
    context = egl.eglCreateContext(display, None, None, attributes)  # no-config context
    if not context:
        raise RuntimeError("eglCreateContext failed")
    egl.eglMakeCurrent.argtypes = [ctypes.c_void_p] * 4
    if not egl.eglMakeCurrent(display, None, None, context):
        raise RuntimeError("eglMakeCurrent failed")


def bind_framebuffer(width: int, height: int):
    """A complete framebuffer, bound (a surfaceless context's default one is not)."""
    import moderngl

    gl = moderngl.create_context()
    fbo = gl.framebuffer([gl.renderbuffer((width, height), 4)],
                         gl.depth_renderbuffer((width, height)))
    fbo.use()
    return gl, fbo


def record(job: dict) -> None:
    from pxr import Sdf, Usd, UsdAppUtils, UsdGeom

    stage = Usd.Stage.Open(job["stage"])
    recorder = UsdAppUtils.FrameRecorder("HdStormRendererPlugin", True)
    recorder.SetImageWidth(int(job["width"]))
    recorder.SetColorCorrectionMode("sRGB" if job["out"].endswith(".png") else "disabled")
    recorder.SetIncludedPurposes(job.get("purposes") or ["default", "proxy"])
    recorder.SetCameraLightEnabled(bool(job.get("camera_light", True)))
    camera = UsdGeom.Camera(stage.GetPrimAtPath(Sdf.Path(job["camera"]))) \
        if job.get("camera") else UsdGeom.Camera()
    time = Usd.TimeCode.Default() if job.get("frame") is None else Usd.TimeCode(job["frame"])
    if not recorder.Record(stage, camera, time, job["out"]):
        raise RuntimeError("FrameRecorder.Record returned False")


def main(jobs_path: str) -> None:
    import client_jobs

    jobs = client_jobs.load(jobs_path)
    import_blender_pxr()
    egl_compatibility_context()
    # one framebuffer as large as the largest job (FrameRecorder renders into its own
    # AOVs; the bound one only has to be complete)
    keep = bind_framebuffer(max(int(j["width"]) for j in jobs), max(int(j["width"]) for j in jobs))
    from pxr import Tf

    def failure(job, exc):
        if isinstance(exc, Tf.ErrorException):
            # Storm's GL errors are raised after the image is written; the image decides
            if os.path.isfile(job["out"]):
                return f"ok {job['out']}"
            return f"failed {job['out']}: {' '.join(str(exc).split())[:300]}"
        return None

    client_jobs.run(jobs, record, failure)
    del keep
    client_jobs.finish()

if __name__ == "__main__":
    main(sys.argv[1])
