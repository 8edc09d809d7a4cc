"""The README's Python example runs as it stands (issue 27): authoring with WrinkleAPI,
then usdwrinkle.api's bake and render, in a folder with a copy of the sample shirt."""
from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
from pxr import Sdf, Usd

ROOT = Path(__file__).resolve().parents[1]


def readme_python_example() -> str:
    text = (ROOT / "README.md").read_text()
    section = text[text.index("### Python"):]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_the_readme_python_example_runs(tmp_path):
    code = readme_python_example()
    assert len([line for line in code.splitlines() if line.strip()]) <= 14
    shutil.copy(ROOT / "sample_stages" / "shirt.usda", tmp_path)
    shutil.copytree(ROOT / "sample_stages" / "textures", tmp_path / "textures")
    result = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                            text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-2000:]
    # what the lines say they do: authored, baked, rendered
    stage = Usd.Stage.Open(str(tmp_path / "shirt.usda"))
    sleeve = stage.GetPrimAtPath("/World/Arm/Sleeve")
    assert list(sleeve.GetAttribute("primvars:wrinkle:width").Get()) == [0.25]
    q = np.asarray(sleeve.GetAttribute("primvars:wrinkle:q").Get())
    assert q.shape == (455, 3) and np.allclose(q[:, 2], 0.4)
    layer = Sdf.Layer.FindOrOpen(str(tmp_path / "shirt_wrinkles.usdc"))
    phase = layer.GetAttributeAtPath("/World/Arm/Sleeve.primvars:wrinkle:phase")
    assert len(layer.ListTimeSamplesForPath(phase.path)) == 24
    frames = sorted((tmp_path / "out").glob("shirt.*.png"))
    assert [f.name for f in frames] == [f"shirt.{i:04d}.png" for i in range(1, 25)]


def test_the_readme_job_example_runs(tmp_path):
    """The second example (the jobs themselves) runs as it stands and renders two frames
    of the size it asks for."""
    text = (ROOT / "README.md").read_text()
    section = text[text.index("### Python"):]
    code = re.findall(r"```python\n(.*?)```", section, re.S)[1]
    assert "RenderJob" in code
    shutil.copy(ROOT / "sample_stages" / "shirt.usda", tmp_path)
    shutil.copytree(ROOT / "sample_stages" / "textures", tmp_path / "textures")
    result = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                            text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.split()[:2] == ["[23.0,", "24.0]"]
    assert result.stdout.split()[2:4] == ["96", "64"]
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["job.0023.png",
                                                                   "job.0024.png"]
