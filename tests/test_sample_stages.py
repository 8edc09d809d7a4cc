"""The committed sample stages are what sample_stages/generate.py makes: the script runs
on the package as it is (a rename once broke its imports unseen) and reproduces every
.usda and the plaid texture byte for byte."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "sample_stages"


def test_generate_reproduces_the_committed_stages(tmp_path):
    done = subprocess.run([sys.executable, str(SAMPLES / "generate.py"), str(tmp_path)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    made = sorted(p.name for p in tmp_path.glob("*.usda"))
    assert made == sorted(p.name for p in SAMPLES.glob("*.usda"))
    for name in made:
        assert (tmp_path / name).read_bytes() == (SAMPLES / name).read_bytes(), name
    texture = Path("textures") / "plaid.png"
    assert (tmp_path / texture).read_bytes() == (SAMPLES / texture).read_bytes()
