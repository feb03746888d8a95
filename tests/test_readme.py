"""Every command the README shows runs, as written (issue 17).

The README's ``bash`` blocks are split into commands (one a line, ``&&`` chains split) and
each runs in a fresh shell, headless, in a scratch folder where ``examples/`` and
``benchmarks/`` are the repository's (so files a command writes, such as ``out.gif``, land
there). Left out: installs (``pip install``) and the test command itself, which CI runs
anyway, and the lint / type / docs commands that ``.ci/run`` runs itself (a test checks they
are there, as written). A command that starts a server (``fleet-async view``, ``fleet-async run
... --view``) is started, must answer an HTTP request at the address it prints, and is
stopped; the commands before it in its block run first, in the same folder, since it may serve
what they wrote (``fleet-async view warehouse.fatrace`` after the run that traced it).

A command too long for every CI run (a big sweep) is written with the comment
``# long: CI runs the next line`` and followed, on the next line, by a small variant of the
same command, which runs instead.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest
from docs_blocks import fenced_blocks

REPO = Path(__file__).resolve().parent.parent
README = REPO / "README.md"
CI_SCRIPT = REPO / ".ci" / "run"

INSTALLS = ("python -m pip install", "pip install")
TEST_COMMAND = "python -m pytest -q"
RUN_BY_CI_SCRIPT = ("ruff ", "mypy ", "mkdocs ")
SERVERS = ("fleet-async view",)
"""Commands that serve until stopped: started, asked for their page, stopped (and
``fleet-async run ... --view``, see :func:`is_server`)."""
LONG = "long: CI runs the next line"
_URL = re.compile(r"https?://[^\s/]+/[^\s)\]>,'\"]*")


def readme_blocks() -> list[list[str]]:
    """The commands of each of the README's bash blocks, comments removed, ``&&`` chains
    split; a line marked ``# long: CI runs the next line`` is left out (its small variant
    follows)."""
    blocks: list[list[str]] = []
    for block in fenced_blocks(README):
        if block.language not in ("bash", "sh", "shell", "console"):
            continue
        commands: list[str] = []
        for line in block.code.splitlines():
            if LONG in line:
                continue
            command: list[str] = []
            for word in [*shlex.split(line, comments=True), "&&"]:
                if word != "&&":
                    command.append(word)
                elif command:
                    commands.append(shlex.join(command))
                    command = []
        blocks.append(commands)
    return blocks


def readme_commands() -> list[str]:
    """Every command of the README's bash blocks (see :func:`readme_blocks`)."""
    return [command for block in readme_blocks() for command in block]


def runs_here(command: str) -> bool:
    """Whether the suite runs ``command`` (not an install, the test command or CI's own)."""
    return (
        not command.startswith(INSTALLS)
        and command != TEST_COMMAND
        and not command.startswith(RUN_BY_CI_SCRIPT)
    )


def is_server(command: str) -> bool:
    """Whether ``command`` serves until stopped: ``fleet-async view`` and ``fleet-async run
    ... --view`` (which keeps the live page served after the run)."""
    words = shlex.split(command)
    return command.startswith(SERVERS) or (
        words[:2] == ["fleet-async", "run"] and "--view" in words
    )


COMMANDS = readme_commands()
RUN_HERE = [c for c in COMMANDS if runs_here(c)]


def scratch(tmp_path: Path) -> Path:
    tmp_path.mkdir(parents=True, exist_ok=True)
    for name in ("examples", "benchmarks"):
        (tmp_path / name).symlink_to(REPO / name)
    return tmp_path


def shell_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(REPO), env.get("PYTHONPATH", "")]))
    # `python` and `fleet-async` are this interpreter's, as after the README's install.
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    return env


def test_the_readme_shows_commands_and_every_kind_is_handled():
    assert len(RUN_HERE) >= 5
    assert TEST_COMMAND in COMMANDS
    assert any(c.startswith(INSTALLS) for c in COMMANDS)
    assert shutil.which("fleet-async", path=shell_env()["PATH"]), "fleet-async is not installed"


def test_long_commands_have_a_small_variant_on_the_next_line():
    for block in fenced_blocks(README):
        lines = [line for line in block.code.splitlines() if line.strip()]
        for i, line in enumerate(lines):
            if LONG not in line:
                continue
            assert i + 1 < len(lines) and LONG not in lines[i + 1], line
            program = shlex.split(line, comments=True)[:2]
            assert shlex.split(lines[i + 1], comments=True)[:2] == program, (line, lines[i + 1])


def test_commands_left_to_the_ci_script_are_in_it_as_written():
    ci = CI_SCRIPT.read_text()
    for command in COMMANDS:
        if command.startswith(RUN_BY_CI_SCRIPT) or command == TEST_COMMAND:
            assert command in ci, f".ci/run does not run {command!r}"


def run_command(command: str, cwd: Path) -> None:
    """Run one command in ``cwd`` as the README's reader would; it must succeed and print."""
    result = subprocess.run(
        ["bash", "-c", command],
        cwd=cwd,
        env=shell_env(),
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, f"{command}\n{result.stdout}\n{result.stderr}"
    assert result.stdout.strip(), f"{command} printed nothing"
    assert "pybullet build time" not in result.stdout + result.stderr or not command.startswith(
        "fleet-async"
    ), "the command line must keep PyBullet's banner off the terminal"


@pytest.mark.parametrize("command", [c for c in RUN_HERE if not is_server(c)])
def test_readme_command_runs(command, tmp_path):
    run_command(command, scratch(tmp_path))


SERVER_COMMANDS = [
    (block[:i], command)
    for block in readme_blocks()
    for i, command in enumerate(block)
    if runs_here(command) and is_server(command)
]


def test_the_readme_shows_server_commands():
    assert {command.split()[1] for _, command in SERVER_COMMANDS} >= {"view", "run"}


@pytest.mark.parametrize(
    ("before", "command"), SERVER_COMMANDS, ids=[c for _, c in SERVER_COMMANDS]
)
def test_readme_server_command_serves_and_stops(before, command, tmp_path):
    cwd = scratch(tmp_path)
    for earlier in before:  # what the server may serve: the block's commands before it
        if runs_here(earlier) and not is_server(earlier):
            run_command(earlier, cwd)
    serve_and_stop(command, cwd, shell_env())


def serve_and_stop(command: str, cwd: Path, env: dict[str, str], wait: float = 60.0) -> str:
    """Start ``command``, wait for the http:// address it prints, fetch it, stop it.

    Returns:
        The page's text.
    """
    process = subprocess.Popen(
        ["bash", "-c", f"exec {command}"],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    try:
        assert process.stdout is not None
        deadline = time.monotonic() + wait
        seen: list[str] = []
        url = None
        while url is None and time.monotonic() < deadline:
            line = process.stdout.readline()
            if not line:
                break
            seen.append(line)
            match = _URL.search(line)
            url = match[0].replace("0.0.0.0", "127.0.0.1") if match else None
        assert url is not None, f"{command} printed no http:// address:\n{''.join(seen)}"
        with urllib.request.urlopen(url, timeout=10) as response:
            assert response.status == 200
            return response.read().decode("utf-8", errors="replace")
    finally:
        os.killpg(process.pid, signal.SIGTERM)
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()


def test_the_server_helper_serves_and_stops(tmp_path):
    page = tmp_path / "index.html"
    page.write_text("<p>fleet</p>")
    command = f"{shlex.quote(sys.executable)} -u -m http.server 0 --bind 127.0.0.1"
    assert "<p>fleet</p>" in serve_and_stop(command, tmp_path, shell_env())
