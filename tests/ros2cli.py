"""The real ROS 2 Jazzy command line and colcon, for the tests that use them as a ROS user does.

The ``ros2`` command and the launch system come from ``../shared/ros2-tools`` (wheels built
unchanged from their Jazzy sources; the Makefile's ``ros2-tools`` target puts them into the venv),
colcon from PyPI. Where they are absent (a clone outside this layout) the tests that need them skip
with the reason; with ``HOMEO_REQUIRE_ROS2_TOOLS=1`` (``.ci/run``) their absence fails instead.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tarfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent  # the venv's: ros2 and colcon are installed beside the interpreter
PACKAGE = "homeo_robot"


def require_tools() -> None:
    missing = [t for t in ("ros2", "colcon") if not (BIN / t).exists()]
    if not missing:
        return
    why = (f"the ROS 2 command line tools are not installed in {BIN.parent} ({', '.join(missing)} missing): "
           "make ros2-tools")
    if os.environ.get("HOMEO_REQUIRE_ROS2_TOOLS") == "1":
        pytest.fail(why)
    pytest.skip(why)


def repo_files() -> list[str]:
    """The repository's own files: what git tracks and would track (a clone's content)."""
    r = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=REPO, capture_output=True, text=True)
    if r.returncode == 0 and r.stdout.strip():
        return [f for f in r.stdout.splitlines() if (REPO / f).is_file()]
    skip = {".venv", ".git", "out", "build", "install", "log", "__pycache__"}
    return [str(p.relative_to(REPO)) for p in REPO.rglob("*")
            if p.is_file() and not (set(p.relative_to(REPO).parts) & skip) and not p.name.startswith(".venv")]


EXAMPLES = ("examples/homeo_rover",)  # packages of users' own robots: built beside the project, as a lab would


def build_workspace(root: Path) -> Path:
    """A colcon workspace at ``root`` with this repository cloned into ``src/`` and the example world
    packages beside it (a robot of one's own, docs/ARCHITECTURE.md "Adding a robot"), built; its root."""
    src = root / "src" / "homeo-robot"
    src.mkdir(parents=True)
    archive = root / "repo.tar"
    files = repo_files()
    with tarfile.open(archive, "w") as tar:
        for f in files:
            tar.add(REPO / f, arcname=f)
    with tarfile.open(archive) as tar:
        tar.extractall(src)
    archive.unlink()
    for example in EXAMPLES:
        shutil.copytree(src / example, root / "src" / Path(example).name)
    r = subprocess.run([str(BIN / "colcon"), "build"], cwd=root, capture_output=True, text=True, timeout=600,
                       env=env_with_venv(os.environ))
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    return root


def env_with_venv(env) -> dict:
    """``env`` with the venv's bin first on PATH (``ros2`` and the interpreter colcon builds with)."""
    env = dict(env)
    env["PATH"] = f"{BIN}{os.pathsep}{env.get('PATH', '')}"
    env.pop("HOMEO_AUTH_FILE", None)
    return env


def sourced(ws: Path, command: str) -> list[str]:
    """``command`` in a shell that sourced the workspace (what a user types after ``source``)."""
    return ["bash", "-c", f"source {ws / 'install' / 'setup.bash'} && exec {command}"]


def run(ws: Path, command: str, env: dict, timeout: float = 120.0) -> subprocess.CompletedProcess:
    return subprocess.run(sourced(ws, command), env=env, capture_output=True, text=True, timeout=timeout)


def popen(ws: Path, command: str, env: dict) -> subprocess.Popen:
    """A long-running command in a session of its own: ``os.killpg(p.pid, SIGINT)`` is a terminal's Ctrl-C."""
    return subprocess.Popen(sourced(ws, command), env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, start_new_session=True)


def stop_daemon(env: dict) -> None:
    """``ros2 daemon stop`` for ``env``'s domain: the ros2 commands start one per domain, and a test's
    domain is its own, so each test stops the one it started (no daemons left behind)."""
    subprocess.run([str(BIN / "ros2"), "daemon", "stop"], env=env, capture_output=True, timeout=60)


def cleanup(ws: Path) -> None:
    shutil.rmtree(ws, ignore_errors=True)
