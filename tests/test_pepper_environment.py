"""The Pepper behind the environment boundary (reset / observe / step) on the stand-in over libqi,
the world side of the lockstep over it, and the config that names the scenario's drives, objects
and actions on the robot.

Hand-computed from the shipped ``scripts/pepper.json`` (places H (0,0), C (3,0), R (0,3); start at
R; NEng from the battery, NRes from the temperature status, Table 4.6) and the stand-in's body
parameters (pepper_bridge.standin_body.BodyParams: a 3 m move drains 0.2 %/s x 10 s + 0.5 %/m x 3 m).
"""

from __future__ import annotations

import ast
import copy
import json
import re
from pathlib import Path

import pytest

from pepper_bridge.config import ConfigError, config_from_dict, default_config_path, load_config

RAW = json.loads(default_config_path().read_text())
PEPPER_SRC = Path(__file__).resolve().parents[1] / "src" / "pepper_bridge"


# -- the config ----------------------------------------------------------------------------
def _bad(mutate):
    raw = copy.deepcopy(RAW)
    mutate(raw)
    return raw


@pytest.mark.parametrize("mutate,key", [
    (lambda r: r.update(version=1), "version"),
    (lambda r: r["body"].update(battery="NBat"), "body.battery"),
    (lambda r: r["body"].update(temperature="NAch"), "body.temperature"),  # an internal drive
    (lambda r: r["body"].update(temperature="NEng"), "body"),
    (lambda r: r.pop("body"), "body"),
    (lambda r: r["plug"].update(plugged="full"), "plug"),
    (lambda r: r["plug"].update(variable="dock.status"), "plug"),
    (lambda r: r["actions"].update(Fly={"say": "Up I go."}), "actions.Fly"),
    (lambda r: r["actions"].pop("Rest"), "actions"),
    (lambda r: r["actions"]["MoveToC"].update(move="K"), "actions.MoveToC.move"),
    (lambda r: r["actions"]["Play"].update(set={"player.status": "loud"}), "actions.Play.set"),
    (lambda r: r["actions"]["Play"].update(volume=3), "actions.Play.volume"),
    (lambda r: r["actions"]["Play"].pop("command"), "actions.Play.device"),
    (lambda r: r["actions"]["Stop"].update(say="Let me play some music."), "actions.Stop.say"),
    (lambda r: r["places"].update(K=[1.0, 1.0]), "places.K"),
    (lambda r: r["proposals"].update(fly="Fly"), "proposals.fly"),
    (lambda r: r["intention_cues"]["keywords"].update(sleep="nap"), "intention_cues.keywords.sleep"),
])
def test_config_errors_name_the_file_and_the_key(thesis, mutate, key):
    with pytest.raises(ConfigError) as e:
        config_from_dict(_bad(mutate), "my.json", thesis)
    msg = str(e.value)
    assert msg.startswith(f"my.json: {key}:") and "\n" not in msg, msg


def test_config_file_errors_are_one_line(tmp_path, thesis):
    f = tmp_path / "pepper.json"
    f.write_text("{not json")
    with pytest.raises(ConfigError, match=r"pepper\.json: corrupt config \(not JSON: .* at line 1\)"):
        load_config(f, scenario=thesis)
    with pytest.raises(ConfigError, match="config file not found"):
        load_config(tmp_path / "missing.json", scenario=thesis)


def test_config_meanings(thesis):
    cfg = load_config(scenario=thesis)
    assert (cfg.battery_drive, cfg.temperature_drive) == ("NEng", "NRes")
    assert cfg.plug_actions() == {"Attach": True, "Detach": False}
    assert [cfg.move_action(p) for p in ("H", "C", "R", None)] == ["MoveToH", "MoveToC", "MoveToR", None]
    assert cfg.rest_action() == "Rest"
    assert cfg.actions["LightOn"].set == {"light.status": "on"}


def _thesis_names(sc) -> set:
    names = set(sc.drive_names) | set(sc.motivation_names) | set(sc.action_names)
    return names | {o for o in sc.objects if o != "null"}


def test_no_thesis_name_in_a_string_literal_of_the_bridge(thesis):
    """Which drive, object, action the robot means lives in the config; comments and docstrings may cite them."""
    pat = re.compile(r"\b(" + "|".join(sorted(map(re.escape, _thesis_names(thesis)))) + r")\b")
    found = []
    for f in sorted(PEPPER_SRC.glob("*.py")):
        tree = ast.parse(f.read_text())
        docs = {id(n.body[0].value) for n in ast.walk(tree)
                if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and n.body
                and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
        for n in ast.walk(tree):
            if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docs and pat.search(n.value):
                found.append(f"{f.name}:{n.lineno}: {n.value!r}")
    assert not found, "\n".join(found)


# -- the environment on the stand-in -------------------------------------------------------
qi = pytest.importorskip("qi")

from homeo_decision.environment import Observation, Outcome  # noqa: E402
from pepper_bridge.bridge import PepperBridge  # noqa: E402
from pepper_bridge.config import LinkSettings  # noqa: E402
from pepper_bridge.environment import NotReady, PepperEnvironment  # noqa: E402
from pepper_bridge.mapping import BATTERY_KEY, temperature_key  # noqa: E402
from pepper_bridge.standin import StandinRobot  # noqa: E402
from pepper_bridge.world_backend import PepperWorld  # noqa: E402

qi.logging.setLevel(qi.logging.WARNING)
CFG = load_config()
USER = {"schema": "homeo-pepper-user", "version": 1,
        "start": {"battery_percent": 40, "location": "R", "presence": "present"},
        "interactions": [{"intention": "light", "gesture": "point_up", "words": ["light"]},
                         {"intention": "come", "gesture": "beckon", "words": ["come"], "patience": 2},
                         {"intention": "music", "gesture": "dance", "words": ["music"]}]}


@pytest.fixture
def world(thesis):
    """A stand-in (time frozen) with a scripted user, a connected bridge and its environment."""
    made = []

    def make(script=USER, use_cues=True):
        robot = StandinRobot(CFG, copy.deepcopy(script), time_scale=0.0, scenario=thesis)
        bridge = PepperBridge(CFG, LinkSettings(url=robot.start()), thesis)
        made.append((robot, bridge))
        assert bridge.start(10.0), bridge.status()
        return robot, bridge, PepperEnvironment(bridge, quiet=0.15, window=2.0, use_cues=use_cues)

    yield make
    for robot, bridge in made:
        bridge.stop()
        robot.close()


def view(sc, obs: Observation) -> dict:
    return sc.view(obs.code)


def test_reset_collects_the_first_expression_and_observes(world, thesis):
    sc = thesis
    robot, bridge, env = world()
    obs = env.reset(0)
    v = view(sc, obs)
    assert v["robot.location"] == "R" and v["human.presence"] == "present" and v["intention"] == "none"
    assert (v["charger.status"], v["player.status"], v["light.status"]) == ("idle", "idle", "off")
    body = dict(zip(sc.drive_names, obs.body))
    assert body["NEng"] == pytest.approx(60.0) and body["NRes"] == 0.0  # battery 40 %, status 0 (Table 4.6)
    assert obs.readings == {"battery_percent": pytest.approx(40.0), "temperature_status": 0}
    assert obs.cues == {"gesture": "point_up", "movement": None, "keyword": "light"}
    assert sc.intention_names[obs.intention] == "light"  # the config's cues name it
    assert env.observe() is obs  # within a tick the same observation


def test_step_executes_collects_the_answer_and_moves_on(world, thesis):
    sc = thesis
    robot, bridge, env = world()
    env.reset()
    out = env.step(sc.action_index("LightOn"))  # desired: a head touch
    assert isinstance(out, Outcome) and out.action == sc.action_index("LightOn") and out.failure is None
    assert (out.feedback, out.proposal, out.clarified) == (1, None, None)
    assert dict(zip(sc.drive_names, out.body))["NEng"] == pytest.approx(60.5)  # 10 s of speech at rest: 0.05 %/s
    assert env.last_row["ok"] and env.last_row["cue_intention"] == "light" and env.tick == 1
    obs = env.observe()  # the user's next expression, the light now on
    assert view(sc, obs)["light.status"] == "on" and sc.intention_names[obs.intention] == "come"
    out = env.step(sc.action_index("Chat"))  # not what the user wants: scolded, the desired action proposed
    assert out.feedback == -1 and sc.action_names[out.proposal] == "MoveToH"
    assert sc.intention_names[out.clarified] == "come"
    out = env.step(sc.action_index("MoveToH"))  # R -> H: 3 m, 10 s awake 2 % + 1.5 %; 39.5 - 0.5 (Chat) - 3.5
    assert out.feedback == 1 and view(sc, env.observe())["robot.location"] == "H"
    assert env.observe().readings["battery_percent"] == pytest.approx(35.5)
    assert [r["interaction"] for r in env.log] == [1, 2, 3]


def test_no_cues_no_intention(world):
    robot, bridge, env = world(use_cues=False)
    assert env.reset().intention is None


def _refuse(robot, how):
    def motion(x, y):
        if how == "raises":
            raise RuntimeError("ALNavigation: obstacle ahead")
        return False
    robot._motion = motion  # the stand-in's navigateTo / moveTo answer through this


@pytest.mark.parametrize("how,reason", [("false", "the robot reported failure"), ("raises", "obstacle ahead")])
def test_failed_move_is_no_effect(world, thesis, how, reason):
    sc = thesis
    robot, bridge, env = world()
    env.reset()
    _refuse(robot, how)
    out = env.step(sc.action_index("MoveToH"))
    assert out.action is None and reason in out.failure
    assert env.last_row["ok"] is False and env.last_row["action"] == "MoveToH" and reason in env.last_row["reason"]
    assert view(sc, env.observe())["robot.location"] == "R"  # the robot did not move
    from pepper_bridge.launch_support import done_note, row_line  # the printed table says so

    row = dict(env.last_row, m_dom="NEng", intention="come")
    assert done_note(row).startswith("FAILED: ") and reason in done_note(row)
    assert row_line(row).split()[3:4] == ["MoveToH"] and "FAILED" in row_line(row)
    from pepper_bridge.field import FieldResult, format_table

    table = format_table(FieldResult("robot", 0.25, 0, log=[row], user_log=[]))
    assert any("MoveToH" in ln and ln.endswith("FAILED") for ln in table)


def test_no_valid_body_reading_yet_is_not_ready(world):
    robot, bridge, env = world()
    robot.inject(BATTERY_KEY, "abc")  # wrongly typed from the start: no good value to stand in
    with pytest.raises(NotReady, match="NEng"):
        env.observe()
    robot.clear_injections()
    assert env.observe().readings["battery_percent"] == pytest.approx(40.0)


@pytest.fixture
def pepper_world(thesis):
    """The Pepper world as the world node builds it, on a stand-in (time frozen) with the scripted user."""
    robot = StandinRobot(CFG, copy.deepcopy(USER), time_scale=0.0, scenario=thesis)
    values = dict({s.name: s.default for s in PepperWorld.PARAMS}, qi_url=robot.start(), collect_window=2.0)
    side = PepperWorld(thesis, values)
    try:
        assert side.bridge.wait_connected(10.0), side.bridge.status()
        yield robot, side
    finally:
        side.close()
        robot.close()


def test_world_fields_and_log(pepper_world):
    robot, side = pepper_world
    side.start()
    w, seen = side.observe(False)
    assert w["robot"] == {"location": "R"} and w["objects"]["light"] == {"status": "off"}
    assert w["body"]["NEng"] == pytest.approx(60.0) and w["body"]["battery_percent"] == pytest.approx(40.0)
    assert seen == {"intention": "light", "gesture": "point_up", "movement": None, "keyword": "light"}
    out = side.step({"action": "LightOn", "m_dom": "Serving", "intention": "light"})
    assert out["action"] == "LightOn" and out["feedback"] == 1
    robot.inject(temperature_key("KneePitch"), 2)
    _refuse(robot, "false")
    side.observe(False)
    out = side.step({"action": "MoveToH", "m_dom": "Serving", "intention": "none"})
    assert out["action"] is None and out["body"]["NRes"] == 80.0
    failed = side.step_failed({"action": "Chat", "m_dom": "Social", "intention": "come"}, "robot dropped")
    assert failed["action"] is None and failed["feedback"] == 0
    log = side.status(False)["extra"]["log"]
    assert [(r["interaction"], r["action"], r["ok"], r["m_dom"], r["intention"]) for r in log] == [
        (1, "LightOn", True, "Serving", "light"), (2, "MoveToH", False, "Serving", None),
        (3, "Chat", False, "Social", "come")]
