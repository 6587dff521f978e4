"""Every registered world keeps the world contract (``homeo_decision.world_api.WorldBackend``), checked
by the importable checker (``homeo_decision.world_check``, as Gymnasium's ``check_env``), which knows no
world by name; and the checker itself catches a world that breaks a rule (each rule's own broken world)."""

from __future__ import annotations

import subprocess
import sys

import pytest

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
