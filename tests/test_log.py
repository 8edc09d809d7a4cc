"""Warnings travel through logging (issue 25, usdwrinkle/process/log.py): one sink shows them,
the host's logging sees them too, and no function threads a ``warn`` callback."""
from __future__ import annotations

import ast
import logging
from pathlib import Path

from usdwrinkle.process import log

PACKAGE = Path(log.__file__).resolve().parent


def test_outside_any_block_a_warning_is_one_stderr_line(capsys):
    logging.getLogger("usdwrinkle.scene.stage").warning("mesh has no points;\n  skipped (/A)")
    assert capsys.readouterr().err == "usdwrinkle: warning: mesh has no points; skipped (/A)\n"


def test_the_innermost_sink_gets_it_and_stderr_does_not(capsys):
    with log.collect() as outer:
        log.warn("first")
        with log.collect() as inner:
            logging.getLogger("usdwrinkle.maps.bake").warning("second %s", "one")
        log.warn("third")
    log.warn("after")
    assert outer == ["first", "third"] and inner == ["second one"]
    assert capsys.readouterr().err == "usdwrinkle: warning: after\n"


def test_the_hosts_logging_sees_every_warning(caplog):
    with caplog.at_level(logging.WARNING, logger="usdwrinkle"), log.silenced():
        logging.getLogger("usdwrinkle.scene.lights").warning("dome texture not found")
    assert [(r.name, r.getMessage()) for r in caplog.records] == [
        ("usdwrinkle.scene.lights", "dome texture not found")]


def test_a_level_set_on_the_package_logger_silences_it(capsys):
    logger = logging.getLogger("usdwrinkle")
    saved = logger.level
    logger.setLevel(logging.ERROR)
    try:
        log.warn("not shown")
    finally:
        logger.setLevel(saved)
    assert capsys.readouterr().err == ""


def test_the_reporter_is_the_sink_while_a_command_runs(capsys):
    from usdwrinkle.cli.common import Reporter

    with Reporter() as reporter:
        for _ in range(3):  # a per-frame warning: shown once
            logging.getLogger("usdwrinkle.scene.sampling").warning("light ignored (/L)")
        reporter.warn("light ignored (/L)")
    log.warn("after the command")
    assert capsys.readouterr().err.splitlines() == [
        "usdwrinkle: warning: light ignored (/L)", "usdwrinkle: warning: after the command"]


def test_no_function_takes_a_warn_callback():
    """The warnings used to travel as ``warn`` parameters through 19 functions, with
    defaults that disagreed (printing in two places, silent in three)."""
    found = []
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                names = [a.arg for a in node.args.args + node.args.kwonlyargs]
                if {"warn", "warnings"} & set(names):
                    found.append(f"{path.relative_to(PACKAGE)}:{node.lineno} {node.name}")
            if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) \
                    and node.target.id == "warn":
                found.append(f"{path.relative_to(PACKAGE)}:{node.lineno} field warn")
    assert found == []
    assert any(PACKAGE.rglob("*.py"))


def test_progress_lines_and_warnings_each_print_once(capsys, monkeypatch):
    """Progress lines had a handler on the package logger itself: once a farm's log mode
    had shown progress, every later warning printed twice (once as 'usdwrinkle: ...')."""
    from usdwrinkle.process.progress import counter

    monkeypatch.setenv("USDWRINKLE_PROGRESS", "log")
    bar = counter(2, "render")
    bar.update(2)
    bar.close()
    log.warn("once")
    assert capsys.readouterr().err.splitlines() == [
        "usdwrinkle: render: 2/2 frame(s) (100%)", "usdwrinkle: warning: once"]
