"""The resolve pass (render/resolve.py) against outside oracles: GL's own multisample
resolve (a framebuffer blit) finished in numpy for the float AOVs, and numpy's float16
conversion and sRGB encode for an image file's planes and codes."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from usdwrinkle.engine import WrinkleEngine
from usdwrinkle.outputs.images import image_from_buffers, layout_for
from usdwrinkle.render.request import FrameRequest
from usdwrinkle.render.resolve import EXR_CHANNELS, HALF_CHANNELS, ImageLayout

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"


@pytest.fixture(scope="module", params=[4, 1], ids=["4 samples", "1 sample"])
def drawn(request, gl_context):
    """The shirt at frame 24, drawn; yields (engine, framebuffer, samples)."""
    engine = WrinkleEngine(str(SAMPLES / "shirt.usda"), ctx=gl_context)
    engine.render_frame(24.0, 160, 120, samples=request.param)
    yield engine, engine.debug.framebuffer, request.param
    engine.release()


def blit_resolve(ctx, fb, samples: int) -> dict[str, np.ndarray]:
    """The AOVs as GL's blit resolves the attachments, finished in numpy (the renderer's
    code before the resolve pass): divide the non-colour AOVs by the coverage, normalise
    the normals, depth inf where nothing was hit."""
    width, height = fb.size
    planes = []
    for target in fb.targets:
        if samples > 1:
            resolved = ctx.texture((width, height), 4, dtype="f4")
            source = ctx.framebuffer(color_attachments=[target])
            dest = ctx.framebuffer(color_attachments=[resolved])
            ctx.copy_framebuffer(dest, source)
            data = resolved.read()
            for obj in (source, dest, resolved):
                obj.release()
        else:
            data = target.read()
        planes.append(np.frombuffer(data, np.float32).reshape(height, width, 4))
    color, wrinkle, normal = planes
    alpha = color[..., 3:4]
    covered = alpha > 0
    inverse = np.divide(1.0, alpha, out=np.zeros_like(alpha), where=covered) \
        if samples > 1 else np.ones_like(alpha)
    normal = normal[..., :3] * inverse
    if samples > 1:
        length = np.linalg.norm(normal, axis=2, keepdims=True)
        normal = np.divide(normal, length, out=normal.copy(), where=length > 0)
    fields = wrinkle[..., :3] * inverse
    return {"color": color, "wrinkle.height": fields[..., 0:1],
            "wrinkle.amplitude": fields[..., 1:2], "normal": normal,
            "depth": np.where(covered, fields[..., 2:3], np.float32(np.inf))}


def test_float_aovs_match_the_blit_resolve(drawn):
    engine, fb, samples = drawn
    expected = blit_resolve(engine.ctx, fb, samples)
    got = fb.read()
    assert (got["color"].pixels[..., 3] > 0).mean() > 0.05  # the shirt is in the frame
    for name, pixels in expected.items():
        actual = got[name].pixels
        assert actual.shape == pixels.shape, name
        finite = np.isfinite(pixels)
        assert np.array_equal(finite, np.isfinite(actual)), name
        # the same sums in another order: a few float ulps
        np.testing.assert_allclose(actual[finite], pixels[finite], rtol=1e-5, atol=1e-6,
                                   err_msg=name)
    assert np.abs(got["wrinkle.height"].pixels).max() > 1e-3  # wrinkles were drawn


@pytest.mark.parametrize("half", [True, False], ids=["half", "float"])
def test_exr_planes_are_the_float_aovs_at_file_precision(drawn, half):
    _, fb, _ = drawn
    planes = fb.read_image(ImageLayout("exr", half=half))
    reference = image_from_buffers(fb.read(), ImageLayout("exr", half=half))
    assert list(planes.planes) == list(EXR_CHANNELS)
    assert planes.bad == reference.bad == 0
    for name in EXR_CHANNELS:
        got, want = planes.planes[name], reference.planes[name]
        assert got.dtype == (np.float16 if half and name in HALF_CHANNELS else np.float32)
        assert got.shape == want.shape == (fb.size[1], fb.size[0]) and got.flags.c_contiguous
        # numpy's float16 cast rounds to nearest even, as llvmpipe's packHalf2x16 does
        np.testing.assert_array_equal(got, want, err_msg=name)


@pytest.mark.parametrize("aovs", [("color",), ("depth",), ("wrinkle.amplitude", "normal")],
                         ids=["color", "depth", "amplitude+normal"])
def test_exr_planes_of_chosen_aovs_are_those_of_every_aov(drawn, aovs):
    """render --aovs: the planes of the AOVs asked for, and no other, each the same
    bytes as in the frame of every AOV and as numpy makes them from the float AOVs."""
    from usdwrinkle.images.aovs import exr_channels

    _, fb, _ = drawn
    everything = fb.read_image(ImageLayout("exr", half=True))
    full = {name: plane.copy() for name, plane in everything.planes.items()}
    layout = ImageLayout("exr", aovs=aovs, half=True)
    chosen = fb.read_image(layout)
    reference = image_from_buffers(fb.read(), layout)
    assert list(chosen.planes) == list(reference.planes) == list(exr_channels(aovs))
    assert chosen.bad == reference.bad == 0
    for name, plane in chosen.planes.items():
        assert plane.shape == (fb.size[1], fb.size[0]) and plane.flags.c_contiguous
        np.testing.assert_array_equal(plane, full[name], err_msg=name)
        np.testing.assert_array_equal(plane, reference.planes[name], err_msg=name)


@pytest.mark.parametrize("path", ["f.png", "f.jpg"])
def test_8bit_codes_match_numpys_srgb_encode(drawn, path):
    _, fb, _ = drawn
    layout = layout_for(path)
    codes = fb.read_image(layout).planes["RGBA"]
    want = image_from_buffers(fb.read(("color",)), layout).planes["RGBA"]
    assert codes.dtype == np.uint8 and codes.shape == want.shape
    difference = np.abs(codes.astype(int) - want)
    # GLSL's pow and numpy's differ in the last bits: a code may round the other way
    assert difference.max() <= 1 and (difference == 0).mean() > 0.999
    if layout.over_black:
        assert np.all(codes[..., 3] == 255)
    else:
        assert 0 < (codes[..., 3] == 255).mean() < 1  # straight alpha, edges partial


def test_arrays_held_by_a_writer_are_never_overwritten(drawn):
    """Frames in flight keep their pixels while later frames are resolved."""
    engine, fb, samples = drawn
    layout = ImageLayout("exr", half=True)
    request = FrameRequest(*fb.size, samples, layout=layout)
    first = engine.render(1.0, request)
    kept = {name: plane.copy() for name, plane in first.planes.items()}
    for frame in (12.0, 24.0, 6.0):
        later = engine.render(frame, request)
    for name, plane in kept.items():
        np.testing.assert_array_equal(first.planes[name], plane, err_msg=name)
    assert not np.array_equal(later.planes["R"], kept["R"])  # an overwrite would show


def test_non_finite_values_are_counted(gl_context):
    """A value that overflows half float is infinite in the file: counted, like NaN."""
    from usdwrinkle.render.buffers import Framebuffer

    fb = Framebuffer(gl_context, 8, 4, samples=1)
    try:
        colour = np.zeros((4, 8, 4), np.float32)
        colour[..., 3] = 1.0
        colour[0, 0, 0] = 1e6  # finite, beyond half float's 65504
        colour[1, 1, 1] = np.nan
        fb.targets[0].write(colour.tobytes())
        fb.targets[1].write(np.zeros((4, 8, 4), np.float32).tobytes())
        fb.targets[2].write(np.zeros((4, 8, 4), np.float32).tobytes())
        assert fb.read_image(ImageLayout("exr", half=False)).bad == 1
        assert fb.read_image(ImageLayout("exr", half=True)).bad == 2
        assert fb.read_image(ImageLayout("8bit")).bad == 1
        depth = fb.read_image(ImageLayout("exr", half=False)).planes["Z"]
        assert np.all(np.isinf(depth[colour[..., 3] == 0]))
    finally:
        fb.release()


def test_a_frame_with_non_finite_values_is_refused_and_leaves_no_file(tmp_path):
    from usdwrinkle.outputs.images import write_image
    from usdwrinkle.process.errors import UsdWrinkleError
    from usdwrinkle.render.buffers import RenderBuffer
    from usdwrinkle.render.resolve import AOVS

    buffers = {name: RenderBuffer(name, AOVS[name][2], np.zeros((4, 8, len(AOVS[name][2])),
                                                                   np.float32))
               for name in AOVS}
    buffers["normal"].pixels[2, 3, 0] = np.inf
    for name in ("f.exr", "f.png"):
        if name == "f.png":
            buffers["color"].pixels[0, 0, 0] = np.nan
        with pytest.raises(UsdWrinkleError, match="1 non-finite value"):
            write_image(str(tmp_path / name), buffers)
    assert list(tmp_path.iterdir()) == []
