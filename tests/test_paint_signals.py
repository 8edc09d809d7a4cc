"""The paint window obeys stop signals (issue 54, finding 4): ``usdwrinkle paint`` under
Xvfb, stopped with SIGINT, SIGTERM and SIGHUP while another process burns a CPU core.

Before, the CLI's handler raised KeyboardInterrupt inside Qt's dispatch, which swallowed
it and left the three signals ignored: only SIGKILL ended the window. Now a stop closes
the window as Ctrl+W does (the unsaved-strokes question first), and a second stop while
the question is open writes the strokes to a recovery file and ends at once. Needs the
paint-window tier (tests/conftest.py ``display``)."""
from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from pxr import Usd

from usdwrinkle.authoring import WrinkleAPI

from helpers import find_window, sheet_stage, start_window, xdotool

pytestmark = pytest.mark.slow

STOPS = {"SIGINT": (130, "interrupted"), "SIGTERM": (143, "terminated"),
         "SIGHUP": (143, "terminated")}


@pytest.fixture
def burner():
    """A process that keeps one core busy: the signals arrive on a loaded machine."""
    process = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    yield process
    process.kill()
    process.wait(10)


def ignored_signals(pid: int) -> set[str]:
    """The stop signals process ``pid`` ignores (SigIgn of /proc/PID/status)."""
    with open(f"/proc/{pid}/status") as status:
        mask = next(int(line.split()[1], 16) for line in status if line.startswith("SigIgn:"))
    return {name for name in STOPS if mask >> (int(getattr(signal, name)) - 1) & 1}


class Window:
    """``usdwrinkle paint`` on a sheet, in a process of its own."""

    def __init__(self, display: str, tmp_path: Path):
        self.display = display
        self.stage = sheet_stage(tmp_path / "sheet.usda", nx=21)
        self.out = tmp_path / "painted.usda"
        self.log_path = tmp_path / "paint.log"
        self.process, self.log, self.id = start_window(
            display, [sys.executable, "-m", "usdwrinkle", "paint", self.stage, "-o",
                      str(self.out), "--size", "800x500"], self.log_path)

    def title(self) -> str:
        return xdotool(self.display, "getwindowname", self.id, check=False).strip()

    def paint(self, timeout: float = 120) -> None:
        """Drag across the sheet until the window says it holds unsaved strokes (its
        title's '*'): the first frame may take a while on a loaded machine."""
        geometry = dict(line.split("=") for line in
                        xdotool(self.display, "getwindowgeometry", "--shell",
                                self.id).split())
        width, height = int(geometry["WIDTH"]), int(geometry["HEIGHT"])
        deadline = time.monotonic() + timeout
        while not self.title().endswith("*"):
            assert time.monotonic() < deadline, self.text()
            xdotool(self.display, "windowfocus", "--sync", self.id, check=False)
            xdotool(self.display, "mousemove", "--window", self.id, str(width // 5),
                    str(height // 2))
            xdotool(self.display, "mousedown", "1")
            for step in range(1, 13):
                xdotool(self.display, "mousemove", "--window", self.id,
                        str(width // 5 + step * (width // 3) // 12), str(height // 2))
                time.sleep(0.05)
            xdotool(self.display, "mouseup", "1")
            time.sleep(0.5)

    def question(self, timeout: float = 60) -> str:
        """The unsaved-strokes question's window, once it shows."""
        return find_window(self.display, "Unsaved strokes", self.process.pid, timeout)

    def send(self, name: str) -> None:
        self.process.send_signal(getattr(signal, name))

    def text(self) -> str:
        self.log.flush()
        return self.log_path.read_text()

    def close(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait(10)
        self.log.close()


@pytest.fixture
def window(display, tmp_path, burner):
    opened = Window(display, tmp_path)
    yield opened
    opened.close()


@pytest.mark.parametrize("name", list(STOPS))
def test_a_stop_signal_closes_a_clean_window(window, name):
    code, said = STOPS[name]
    assert ignored_signals(window.process.pid) == set()
    window.send(name)
    assert window.process.wait(60) == code, window.text()
    assert window.text().strip().splitlines()[-1] == f"usdwrinkle: {said}"


def test_a_stop_asks_about_unsaved_strokes_and_a_second_writes_them(window):
    window.paint()
    window.send("SIGTERM")
    window.question()
    assert window.process.poll() is None  # waiting for the answer
    assert ignored_signals(window.process.pid) == set()
    window.send("SIGTERM")
    assert window.process.wait(60) == 143, window.text()
    recovery = window.out.with_name("painted.recovery.usda")
    last = window.text().strip().splitlines()[-1]
    assert last == f"usdwrinkle: terminated; unsaved strokes written to {recovery}"
    assert not window.out.exists()  # never saved: the recovery file holds the strokes
    recovered = Usd.Stage.Open(str(recovery))
    q = WrinkleAPI(recovered.GetPrimAtPath("/Sheet")).get_q()
    assert (np.linalg.norm(q, axis=1) > 0).sum() >= 10


def test_cancelling_the_question_keeps_the_window_and_its_signals(window):
    window.paint()
    window.send("SIGINT")
    question = window.question()
    xdotool(window.display, "windowfocus", "--sync", question, check=False)
    xdotool(window.display, "key", "Escape")  # Cancel
    deadline = time.monotonic() + 30
    while xdotool(window.display, "search", "--all", "--onlyvisible", "--pid",
                  str(window.process.pid), "--name", "Unsaved strokes", check=False).strip():
        assert time.monotonic() < deadline, "the question stayed open"
        time.sleep(0.2)
    time.sleep(1.0)
    assert window.process.poll() is None, window.text()
    assert ignored_signals(window.process.pid) == set()
    window.send("SIGHUP")  # still obeyed: asked again
    window.question()
    window.send("SIGHUP")
    assert window.process.wait(60) == 143, window.text()
    assert window.out.with_name("painted.recovery.usda").exists()
