"""Step 4 of "Adding a robot": the rover keeps the world contract, and does what rover.json says."""

import json
from importlib import resources
from pathlib import Path

import pytest
from homeo_decision.scenario import load_scenario
from homeo_decision.world_api import WorldConfigError
from homeo_decision.world_check import check_world

from homeo_rover.world import RoverWorld

SHIPPED = json.loads(resources.files("homeo_rover").joinpath("rover.json").read_text())


def test_the_rover_keeps_the_contract():
    assert check_world("rover") == []


def test_a_slow_rover_with_a_config_of_its_own_keeps_it_too(tmp_path):
    mine = dict(SHIPPED, user=dict(SHIPPED["user"], place=SHIPPED["start"]))  # the person sits where it starts
    (tmp_path / "mine.json").write_text(json.dumps(mine))
    assert check_world("rover", speed=1.5, config=str(tmp_path / "mine.json")) == []


def test_the_same_rover_keeps_it_in_another_scenario_with_another_config():
    garden = Path(__file__).resolve().parent.parent / "garden.json"
    assert check_world("rover", scenario=load_scenario("garden"), config=str(garden)) == []


def test_a_config_that_is_not_the_scenarios_is_refused_in_one_line(tmp_path):
    bad = dict(SHIPPED, devices={"Fly": {"device": "rotor", "command": "spin"}})
    (tmp_path / "bad.json").write_text(json.dumps(bad))
    with pytest.raises(WorldConfigError, match="not the scenario's: Fly$"):
        RoverWorld.check(load_scenario(), {"config": str(tmp_path / "bad.json")})


@pytest.mark.parametrize("speed, xs", [(6.0, [0.0]), (4.0, [2.0, 0.0]), (2.5, [3.5, 1.0, 0.0])])
def test_the_rover_drives_speed_metres_a_tick_and_is_at_the_nearest_place(speed, xs):
    sc = load_scenario()
    world = RoverWorld(sc, {"seed": 0, "config": "", "speed": speed})
    rover, places, goal = world.env, SHIPPED["places"], SHIPPED["user"]["place"]
    go = next(i for i, a in enumerate(sc.actions)  # the scenario's action that moves the robot there
              if any(e.get("set", {}).get("robot.location") == places[goal]["location"] for e in a.effects))
    assert (places[SHIPPED["start"]]["x"], places[goal]["x"]) == (6.0, 0.0)
    assert rover.relation() == "far"
    for x in xs:
        assert rover.step(go).action == go and rover.x == x
        assert rover.place() == min(places, key=lambda p: abs(places[p]["x"] - x))
    assert rover.place() == goal and rover.relation() == "near"
    assert world.devices() == [] and rover.count["metres"] == 6.0


def test_every_action_with_a_device_sends_its_command():
    sc = load_scenario()
    world = RoverWorld(sc, {"seed": 0, "config": "", "speed": 4.0})
    for name, command in SHIPPED["devices"].items():
        world.reset(None)
        out = world.env.step(sc.action_index(name))
        sent = world.devices()
        assert sent == ([dict(command, action=name, tick=0)] if out.action is not None else [])
