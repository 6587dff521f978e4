"""A world nobody in the project wrote: the example package ``examples/homeo_rover``, written from
docs/ARCHITECTURE.md ("Adding a robot") alone, installed beside the project with no change to it (into a
folder of its own on PYTHONPATH), passes the checker, runs through ``homeo-launch`` with its flags, writes its
parameters file, and passes its own tests; ``ros2 launch ... world.launch.py world:=rover`` in a colcon
workspace is tests/test_ros2_workspace.py's. And the section and the package are kept in step: each step's
file exists, the registration is the section's, and every hook of the contract is named in the section."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "homeo_rover"


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    """The environment of a user who installed the example (pip --target, then PYTHONPATH)."""
    tmp = tmp_path_factory.mktemp("rover")
    shutil.copytree(EXAMPLE, tmp / "src", ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    r = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--no-build-isolation",
                        "--disable-pip-version-check", "--target", str(tmp / "site"), str(tmp / "src")],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp / "site"), os.environ.get("PYTHONPATH", "")]))


def _run(env, *args, timeout=300):
    return subprocess.run([sys.executable, *args], env=env, capture_output=True, text=True, timeout=timeout)


def test_the_checker_holds_it_to_the_contract(env):
    r = _run(env, "-m", "homeo_decision.world_check", "rover")
    assert r.returncode == 0 and r.stdout.strip() == "rover: conforms", r.stdout + r.stderr


def test_its_own_tests_pass(env):
    r = _run(env, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(EXAMPLE / "tests"))
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-2000:]


@pytest.mark.ros
def test_homeo_launch_lists_its_flags_and_runs_it(env):
    from homeo_launch.processes import graph_env
    from rosgraph import fresh_domain

    r = _run(env, "-m", "homeo_launch.cli", "rover", "--help")
    assert r.returncode == 0 and "--speed SPEED" in r.stdout and "--config CONFIG" in r.stdout, r.stdout + r.stderr
    e = dict(graph_env(fresh_domain()), PYTHONPATH=env["PYTHONPATH"])
    r = _run(e, "-m", "homeo_launch.cli", "rover", "--iterations", "100", "--speed", "2", "--quiet")
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr[-3000:]
    assert "100 ticks, 0 missed" in r.stdout, r.stdout
    r = _run(env, "-m", "homeo_launch.cli", "rover", "--speed", "0")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "speed = 0.0 is outside" in r.stderr, r.stderr


@pytest.mark.ros
def test_its_parameters_file(env):
    import yaml

    from homeo_launch.processes import graph_env
    from rosgraph import fresh_domain

    r = _run(dict(graph_env(fresh_domain()), PYTHONPATH=env["PYTHONPATH"]), "-m", "homeo_launch.params_yaml", "rover")
    assert r.returncode == 0, r.stderr
    world = yaml.safe_load(r.stdout)["/homeo_world"]["ros__parameters"]
    assert world["world"] == "rover" and {"speed", "config"} <= set(world), world


# -- the section and the package, in step ------------------------------------------------------------------
def _section() -> str:
    text = (REPO / "docs" / "ARCHITECTURE.md").read_text()
    return text[text.index("## Adding a robot"):text.index("### The parameters, generated from their declarations")]


def test_every_file_the_section_names_is_the_example_s_and_its_registration_is_the_section_s():
    sec = _section()
    named = re.findall(r"the example's `([^`]+)`", sec) + re.findall(r"`(homeo_rover/[^`]+|resource/homeo_rover)`", sec)
    assert len(set(named)) >= 6, named
    missing = [f for f in set(named) if not (EXAMPLE / f).exists()]
    assert not missing, missing
    toml = re.search(r"```toml\n(.*?)```", sec, re.S).group(1).strip()
    assert toml in (EXAMPLE / "pyproject.toml").read_text()


def test_every_hook_of_the_contract_is_named_in_the_section_and_every_name_it_uses_exists():
    """A hook added to ``WorldBackend`` without a word in the section fails here, and so does a name the
    section gives (a module, a class, a function) that the code no longer has."""
    import importlib

    from homeo_decision.world_api import WorldBackend

    sec = _section()
    hooks = [n for n in vars(WorldBackend) if not n.startswith("_")]
    assert [h for h in hooks if f"`{h}" not in sec and f" {h}" not in sec] == []
    for dotted in set(re.findall(r"`((?:homeo_\w+|pepper_bridge)(?:\.\w+)+)", sec)):
        parts = dotted.split(".")
        for cut in range(len(parts), 0, -1):  # the longest importable module, then its attributes
            try:
                obj = importlib.import_module(".".join(parts[:cut]))
            except ImportError:
                continue
            for attr in parts[cut:]:
                assert hasattr(obj, attr), dotted
                obj = getattr(obj, attr)
            break
        else:
            raise AssertionError(f"{dotted}: no such module")
