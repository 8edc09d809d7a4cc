"""The installed wheel works on its own: schemas, shaders and samples come from the package."""
from __future__ import annotations

import os
import subprocess
import sys
import zipfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def test_wheel_ships_its_data_and_runs(tmp_path, gl_context):
    wheels = tmp_path / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", "-w",
                    str(wheels), str(REPO)], check=True, timeout=600)
    wheel = next(wheels.glob("usdwrinkle-*.whl"))
    names = set(zipfile.ZipFile(wheel).namelist())
    for required in ("usdwrinkle/schemas/plugInfo.json", "usdwrinkle/schemas/generatedSchema.usda",
                     "usdwrinkle/shaders/skin.glsl", "usdwrinkle/shaders/include/common.glsl",
                     "usdwrinkle/sample_stages/shirt.usda",
                     "usdwrinkle/sample_stages/textures/plaid.png",
                     "usdwrinkle/usdview/plugInfo.json",
                     "usdwrinkle/blender/usdwrinkle_blender.py"):
        assert required in names, required
    # development tools stay in the checkout: the benchmarks and the sample generator
    assert not [n for n in names if n.startswith("benchmarks/") or n.endswith("generate.py")]
    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--quiet", "--target",
                    str(target), str(wheel)], check=True, timeout=600)
    env = dict(os.environ, PYTHONPATH=str(target))
    env.pop("PXR_PLUGINPATH_NAME", None)
    code = ("import usdwrinkle, sys; from usdwrinkle.cli.main import main; "
            "print('FROM', usdwrinkle.__file__); "
            "sys.exit(main(['demo', sys.argv[1], '--width', '64', '--quiet']))")
    run = subprocess.run([sys.executable, "-c", code, str(tmp_path / "demo")], cwd=tmp_path,
                         env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert f"FROM {target}" in run.stdout
    assert len(list((tmp_path / "demo").glob("shirt.*.png"))) == 24
    # the Blender add-on is found in the installed package
    code = "import sys; from usdwrinkle.cli.main import main; sys.exit(main(['blender-addon']))"
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == str(target / "usdwrinkle" / "blender" / "usdwrinkle_blender.py")
