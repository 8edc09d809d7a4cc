"""The README's gallery is what its command renders (issue 27: the curtain image no longer
matched the renderer). Each image is rendered again with the command the README gives
for it and compared on llvmpipe, the reference rasteriser of the goldens; a change that
alters them must regenerate them with that command."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from usdwrinkle.cli.main import main

ROOT = Path(__file__).resolve().parents[1]


def gallery_command() -> list[str]:
    """The README's command for the sample images, NAME in place of each sample."""
    text = (ROOT / "README.md").read_text()
    match = re.search(r"`(usdwrinkle render sample_stages/NAME\.usda docs/images/NAME\.####\.png"
                      r"[^`]*)`", " ".join(text.split()))
    assert match, "the README no longer states the gallery's command"
    return match.group(1).split()


@pytest.mark.parametrize("name", ["shirt", "zeppelin", "curtain", "pillow", "pull"])
def test_the_readme_gallery_is_what_its_command_renders(gl_context, tmp_path, name):
    if "llvmpipe" not in gl_context.info.get("GL_RENDERER", ""):
        pytest.skip("the README's images are made on Mesa llvmpipe (as the goldens)")
    argv = [word.replace("NAME", name) for word in gallery_command()[1:]]
    argv[1] = str(ROOT / argv[1])
    argv[2] = str(tmp_path / Path(argv[2]).name)
    assert main(argv + ["--quiet"]) == 0
    ours = oiio.ImageBuf(str(tmp_path / f"{name}.0024.png")).get_pixels(oiio.FLOAT)
    committed = oiio.ImageBuf(str(ROOT / "docs" / "images" / f"{name}.0024.png")).get_pixels(
        oiio.FLOAT)
    assert ours.shape == committed.shape
    changed = float((np.abs(ours - committed).max(axis=2) > 0.05).mean())
    assert changed <= 0.002, (f"{changed:.1%} of docs/images/{name}.0024.png differs from "
                              "what the README's command renders: regenerate it")
