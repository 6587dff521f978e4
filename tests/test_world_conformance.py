"""Every registered world keeps the world contract (``homeo_decision.world_api.WorldBackend``), checked
by the importable checker (``homeo_decision.world_check``, as Gymnasium's ``check_env``), which knows no
world by name; and the checker itself catches a world that breaks a rule (each rule's own broken world)."""

from __future__ import annotations

import subprocess
import sys

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from homeo_decision.world_api import WorldConfigError, registered
from homeo_decision.world_check import check_world
from homeo_sim.world_backend import SimWorld

WORLDS = sorted(registered())


def test_the_registry_holds_the_three_shipped_worlds():
    assert {"sim", "pepper", "day"} <= set(registered(ours=True))


@pytest.mark.qi
@pytest.mark.parametrize("name", WORLDS)
def test_every_registered_world_conforms(name):
    assert check_world(name) == []


# -- the checker fails a world that breaks a rule --------------------------------------------------
class Praises(SimWorld):
    NAME = "praises"

    def step(self, action_fields):  # a praise with a proposal, whatever happened
        return dict(super().step(action_fields), feedback=1, proposal=self.sc.action_names[0])


class ActsUnasked(SimWorld):
    NAME = "acts_unasked"

    def step(self, action_fields):  # no action came, yet it did one
        return super().step(action_fields or {"action": self.sc.action_names[0]})


class Forgets(SimWorld):
    NAME = "forgets"

    def set_state(self, rng, state, tick):  # takes a state, keeps none of it
        pass


class Unseeded(SimWorld):
    NAME = "unseeded"

    def __init__(self, sc, values):
        import random

        super().__init__(sc, dict(values, seed=random.randrange(1 << 30)))


class BadMessages(SimWorld):
    NAME = "bad_messages"

    def observe(self, final):
        world, seen = super().observe(final)
        return dict(world, robot={"location": "the moon"}), seen


@pytest.mark.parametrize("cls, rule", [
    (Praises, "a praise with a proposal"), (ActsUnasked, "no action came"),
    (Forgets, "a world set to a state does not give it back"), (Unseeded, "two worlds with one seed"),
    (BadMessages, "not a valid homeo/world"),
])
def test_the_checker_fails_a_world_that_breaks_a_rule(cls, rule):
    failures = check_world(cls)
    assert any(rule in f for f in failures), failures
    assert all("\n" not in f for f in failures)


def test_the_checker_reports_a_declaration_and_a_parameter_it_cannot_use():
    class Clashing(SimWorld):
        NAME = "clashing"
        KEEPS_STATE = "yes"

    failures = check_world(Clashing, human="robot")
    assert "KEEPS_STATE must be true or false" in failures
    assert any("human must be one of sim, person" in f for f in failures), failures


def test_the_command_exits_0_for_a_world_that_conforms_and_2_for_an_unknown_one():
    r = subprocess.run([sys.executable, "-m", "homeo_decision.world_check", "day", "--param", "day=example"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and r.stdout.strip() == "day: conforms", r.stdout + r.stderr
    r = subprocess.run([sys.executable, "-m", "homeo_decision.world_check", "tiago"], capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "no world 'tiago'" in r.stderr, r.stderr
    r = subprocess.run([sys.executable, "-m", "homeo_decision.world_check", "sim", "--param", "human_timeout=-1"],
                       capture_output=True, text=True, timeout=300)  # a value its declaration refuses: usage
    assert r.returncode == 2 and "human_timeout = -1.0 is outside [0.01, 3600]" in r.stderr, r.stdout + r.stderr


def test_a_world_that_cannot_be_built_fails_once_not_in_every_check():
    class NoConfig(SimWorld):
        NAME = "no_config"

        def __init__(self, sc, values):
            raise WorldConfigError("config /nope.json: file not found")

    assert check_world(NoConfig) == ["config /nope.json: file not found"]


def test_the_command_on_the_pepper_exits_0_every_time():
    """The Pepper's check runs a libqi session on loopback, whose threads could abort the interpreter's teardown
    (exit -6 after "pepper: conforms", one run in two before ``cli_args.leave``): three runs side by side."""
    runs = [subprocess.Popen([sys.executable, "-m", "homeo_decision.world_check", "pepper"], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True) for _ in range(3)]
    for p in runs:
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0 and out.strip() == "pepper: conforms", out + err[-500:]


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=st.sampled_from(["sim", "day", "nope"]) | st.text(max_size=6),
       params=st.lists(st.tuples(st.sampled_from(["seed", "human", "human_timeout", "day", "x"]) | st.text(max_size=5),
                                 st.sampled_from(["3", "sim", "example", "0.5"]) | st.text(max_size=6)), max_size=3))
def test_any_checker_command_line_is_a_verdict_or_one_line(name, params, capsys):
    """Whatever is typed: a verdict (0 conforms, 1 with each failure on a line of its own that names the world)
    or one line and exit 2; a value quoted back stays on its line."""
    from homeo_decision.world_check import main

    code = main([name, *(a for k, v in params for a in ("--param", f"{k}={v}"))])
    out, err = capsys.readouterr()
    if code == 2:
        assert out == "" and err.count("\n") == 1 and err.startswith("world_check: "), (out, err)
    else:
        assert code in (0, 1) and err == "", (code, out, err)
        lines = out.splitlines()
        assert lines and all(ln.startswith(f"{name}: ") for ln in lines), out
        assert (code == 0) == (lines == [f"{name}: conforms"]), out
