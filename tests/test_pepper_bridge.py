"""The bridge against the stand-in Pepper over real libqi sessions on loopback (no mocks of qi).

Every expectation is hand-computed from the thesis (Table 4.6, Section 4.3.1), the shipped
``scripts/pepper.json`` (places H (0,0), C (3,0), R (0,3); start at R) and the stand-in's body
parameters (pepper_bridge.standin_body.BodyParams).
"""

from __future__ import annotations

import subprocess
import sys
import time

import pytest

qi = pytest.importorskip("qi")

from pepper_bridge import events as ev  # noqa: E402
from pepper_bridge.bridge import PepperBridge  # noqa: E402
from pepper_bridge.config import LinkSettings, load_config  # noqa: E402
from pepper_bridge.mapping import (BATTERY_KEY, EMOTION_EVENT, PEPPER_JOINTS, WORD_EVENT, Rejected,  # noqa: E402
                                   temperature_key, temperature_status)
from pepper_bridge.standin import StandinRobot  # noqa: E402

pytestmark = pytest.mark.qi
qi.logging.setLevel(qi.logging.WARNING)
CFG = load_config()


# ALVoiceEmotionAnalysis/EmotionRecognized as documented for NAOqi 2.5 / 2.8 (levels 0..10):
# http://doc.aldebaran.com/2-5/naoqi/audio/alvoiceemotionanalysis.html
DOC_EXAMPLE = [[4, 3], [0, 2, 1, 3, 0], 1]  # the page's own example: sorrow 3
ANGRY = [[2, 8], [1, 8, 0, 0, 0], 7]
CALM = [[1, 6], [6, 1, 0, 0, 0], 1]


def emotion(anger: int) -> list:
    return [[2, anger], [1, anger, 0, 0, 0], 7]


@pytest.fixture
def pair(thesis):
    """A stand-in (time frozen, battery 50%) and a connected bridge; both closed afterwards."""
    made = []

    def make(battery=50.0, refuse_subscriber=False, settings=None, config=None, device_callback=None, script=None):
        robot = StandinRobot(config or CFG, script, battery=battery, time_scale=0.0, refuse_subscriber=refuse_subscriber)
        url = robot.start()
        s = settings or LinkSettings()
        s.url = url
        bridge = PepperBridge(config or CFG, s, thesis, device_callback=device_callback)
        made.append((robot, bridge))
        assert bridge.start(10.0), bridge.status()
        bridge.collect(0.05, 1.0)  # the connection's status events
        return robot, bridge

    yield make
    for robot, bridge in made:
        bridge.stop()
        robot.close()


def wait_for(bridge, pred, timeout=5.0) -> list:
    """Events until one satisfies ``pred`` (bounded)."""
    got, end = [], time.monotonic() + timeout
    while time.monotonic() < end:
        got += bridge.poll_events(0.05)
        if any(pred(e) for e in got):
            return got
    raise AssertionError(f"no matching event within {timeout} s; got {got}")


# -- body: battery and temperature --------------------------------------------------
@pytest.mark.parametrize("percent", [0, 1, 12.5, 35, 50, 87, 100])
def test_battery_fraction_maps_to_neng(pair, percent):
    robot, bridge = pair()
    robot.inject(BATTERY_KEY, percent / 100.0)
    body = bridge.read_body()
    assert body["battery_percent"] == pytest.approx(percent)
    assert body["NEng"] == pytest.approx(100 - percent)


@pytest.mark.parametrize("percent", [0, 7, 50, 93, 100])
def test_albattery_percent_maps_to_neng(pair, percent):
    robot, bridge = pair(settings=LinkSettings(battery_source="albattery"))
    robot.battery_override = percent
    assert bridge.read_body()["NEng"] == pytest.approx(100 - percent)
    assert ("ALBattery", "getBatteryCharge", []) in robot.calls()


@pytest.mark.parametrize("status,nres", [(0, 0.0), (1, 50.0), (2, 80.0), (3, 100.0)])
def test_temperature_status_maps_to_nres(pair, status, nres):
    robot, bridge = pair()
    robot.inject(temperature_key("KneePitch"), status)
    body = bridge.read_body()
    assert body["temperature_status"] == status
    assert body["NRes"] == nres


def test_nres_uses_the_hottest_joint(pair):
    robot, bridge = pair()
    robot.inject(temperature_key("HeadYaw"), 1)
    robot.inject(temperature_key("RWristYaw"), 2)
    robot.inject(temperature_key("WheelB"), 1)
    assert bridge.read_body()["NRes"] == 80.0


def test_body_simulation_drains_charges_heats_and_cools(pair):
    robot, bridge = pair(battery=50.0)
    # R -> H is 3 m: awake drain 0.2 %/s x 10 s + 0.5 %/m x 3 m = 3.5 %; heat 0.12 x 3 + 0.005 x 10 = 0.41
    assert bridge.execute("MoveToH")["ok"]
    assert robot.battery == pytest.approx(46.5)
    assert robot.heat == pytest.approx(0.41)
    # H -> C is 3 m: 46.5 - 3.5 = 43.0; heat 0.82
    bridge.execute("MoveToC")
    assert robot.battery == pytest.approx(43.0)
    # asked for help at the charger, the user plugs the robot in; the 10 s of Attach charge 2 %/s = +20 %
    bridge.execute("Attach")
    assert robot.plugged and robot.battery == pytest.approx(63.0)
    w = bridge.read_world()
    assert w["objects"]["charger"]["status"] == "charging" and w["body"]["NEng"] == pytest.approx(37.0)
    for _ in range(3):  # +20 % each while plugged
        bridge.execute("Stay")
    assert robot.battery == pytest.approx(100.0)  # 63 + 3 x 20, capped
    robot.heat = 2.5  # hot: status 2 on the motion joints
    assert bridge.read_body()["NRes"] == 80.0
    bridge.execute("Rest")  # 10 s at rest cool 0.05 /s: 2.5 -> 2.0
    assert robot.heat == pytest.approx(2.0) and not robot.awake
    bridge.execute("Rest")  # -> 1.5: status 1
    assert bridge.read_body() == {"battery_percent": pytest.approx(100.0), "temperature_status": 1, "NEng": pytest.approx(0.0),
                                  "NRes": 50.0}


# -- feedback, proposals, keywords --------------------------------------------------
@pytest.mark.parametrize("sensor", ["FrontTactilTouched", "MiddleTactilTouched", "RearTactilTouched"])
def test_head_touch_is_positive_feedback(pair, sensor):
    robot, bridge = pair()
    robot.raise_event(sensor, 1.0)
    robot.raise_event(sensor, 0.0)  # the release is not a second praise
    got = wait_for(bridge, lambda e: e.kind == ev.FEEDBACK)
    got += bridge.collect(0.2, 1.0)
    assert [e.value for e in got if e.kind == ev.FEEDBACK] == [1]
    assert bridge.outcome("LightOn", got) == {"action": "LightOn", "feedback": 1, "proposal": None,
                                              "clarified_intention": None}


def test_anger_above_threshold_is_negative_feedback(pair):
    robot, bridge = pair()
    # the shipped config asks the robot; the stand-in answers 2.5.5.5: levels 0..10, threshold 5
    assert (CFG.naoqi_version, bridge.naoqi()["version"], CFG.emotion_scale, CFG.anger_level) == ("auto", "2.5.5.5", 10, 5)
    robot.raise_event(EMOTION_EVENT, emotion(3))  # below: nothing
    robot.raise_event(EMOTION_EVENT, emotion(5))  # at the threshold: not above
    robot.raise_event(EMOTION_EVENT, DOC_EXAMPLE)  # a sad voice: not a scolding
    robot.raise_event(EMOTION_EVENT, CALM)  # a calm voice: not a scolding
    robot.raise_event(EMOTION_EVENT, ANGRY)
    got = wait_for(bridge, lambda e: e.kind == ev.FEEDBACK)
    got += bridge.collect(0.2, 1.0)
    assert [(e.kind, e.value) for e in got] == [(ev.FEEDBACK, -1)]


def test_spoken_proposal_with_anger(pair):
    robot, bridge = pair()
    robot.raise_event(EMOTION_EVENT, ANGRY)
    robot.raise_event(WORD_EVENT, ["Play", 0.7])
    got = wait_for(bridge, lambda e: e.kind == ev.PROPOSAL)
    got += bridge.collect(0.2, 1.0)
    assert bridge.outcome("Chat", got) == {"action": "Chat", "feedback": -1, "proposal": "Play",
                                           "clarified_intention": "music"}


@pytest.mark.parametrize("words,kind,value", [
    (["turn on the light", 0.6], ev.PROPOSAL, "LightOn"),  # a configured phrase
    (["movetoc", 0.6], ev.PROPOSAL, "MoveToC"),  # an action name, any case
    (["Fly", 0.9], ev.KEYWORD, "fly"),  # not an action of the scenario: a keyword, not a proposal
    (["music", 0.9, "Play", 0.5], ev.KEYWORD, "music"),  # the best hypothesis only
    (["light", 0.45], ev.KEYWORD, "light"),
])
def test_words_become_proposals_or_keywords(pair, words, kind, value):
    robot, bridge = pair()
    robot.raise_event(WORD_EVENT, words)
    got = wait_for(bridge, lambda e: e.kind in (ev.PROPOSAL, ev.KEYWORD))
    got += bridge.collect(0.2, 1.0)
    assert [(e.kind, e.value) for e in got] == [(kind, value)]


def test_low_confidence_words_are_ignored_and_gestures_observed(pair):
    robot, bridge = pair()
    robot.raise_event(WORD_EVENT, ["Play", 0.3])  # below word_confidence 0.4
    robot.raise_event(CFG.gesture_event, "point_up")
    got = wait_for(bridge, lambda e: e.kind == ev.GESTURE)
    got += bridge.collect(0.2, 1.0)
    assert [(e.kind, e.value) for e in got] == [(ev.GESTURE, "point_up")]
    assert bridge.observation(got) == {"gesture": "point_up", "movement": None, "keyword": None}


# -- actions ------------------------------------------------------------------------
def robot_calls(robot):
    return [c for c in robot.calls() if c[0] != "ALMemory"]


def test_moves_wake_up_first_and_navigate_to_the_place(pair):
    robot, bridge = pair()
    robot.clear_calls()
    r = bridge.execute("MoveToH")  # R (0,3) -> H (0,0)
    assert r["ok"] and robot_calls(robot) == [("ALMotion", "robotIsWakeUp", []), ("ALMotion", "wakeUp", []),
                                             ("ALNavigation", "navigateTo", [0.0, -3.0])]
    robot.clear_calls()
    bridge.execute("MoveToC")  # H (0,0) -> C (3,0), already awake
    assert robot_calls(robot) == [("ALMotion", "robotIsWakeUp", []), ("ALNavigation", "navigateTo", [3.0, 0.0])]
    assert robot.location == "C" and bridge.read_world()["robot"]["location"] == "C"
    robot.clear_calls()
    bridge.execute("MoveToR")  # C (3,0) -> R (0,3)
    assert robot_calls(robot)[-1] == ("ALNavigation", "navigateTo", [-3.0, 3.0])


def test_moves_with_almotion_moveto(pair):
    from dataclasses import replace

    robot, bridge = pair(config=replace(CFG, navigation="ALMotion"))
    robot.clear_calls()
    bridge.execute("MoveToC")  # R (0,3) -> C (3,0)
    assert robot_calls(robot) == [("ALMotion", "robotIsWakeUp", []), ("ALMotion", "wakeUp", []),
                                  ("ALMotion", "moveTo", [3.0, -3.0, 0.0])]
    assert robot.location == "C"


def test_speech_rest_help_and_device_actions(pair):
    devices = []
    robot, bridge = pair(device_callback=lambda d, c: devices.append((d, c)))
    say = {name: a.say for name, a in CFG.actions.items()}
    expected = {
        "Chat": [("ALTextToSpeech", "say", [say["Chat"][0]])],
        "Rest": [("ALMotion", "rest", [])],
        **{a: [("ALTextToSpeech", "say", [say[a][0]])] for a in ("Play", "Stop", "LightOn", "LightOff", "Attach", "Stay",
                                                                  "Detach")},
    }
    for action, calls in expected.items():
        robot.clear_calls()
        assert bridge.execute(action)["ok"], action
        assert robot_calls(robot) == calls, action
    assert devices == [("player", "play"), ("player", "stop"), ("light", "on"), ("light", "off")]
    bridge.execute("Chat")  # the chat phrases take turns
    assert robot_calls(robot)[-1] == ("ALTextToSpeech", "say", [say["Chat"][1]])


def test_world_follows_actions(pair):
    robot, bridge = pair()
    w = bridge.read_world()
    assert w["robot"] == {"location": "R"} and w["human"] == {"presence": "present", "relation": "far"}
    bridge.execute("MoveToH")
    bridge.execute("Play")
    bridge.execute("LightOn")
    w = bridge.read_world()
    assert w["human"] == {"presence": "present", "relation": "near"}
    assert w["objects"] == {"charger": {"status": "idle"}, "player": {"status": "playing"}, "light": {"status": "on"}}
    bridge.execute("Attach")  # not at the charger: the user cannot help
    assert bridge.read_world()["objects"]["charger"]["status"] == "idle"
    with robot.lock:
        robot.user.present = False
    assert bridge.read_world()["human"] == {"presence": "absent", "relation": "absent"}


# -- the robot drops and comes back ---------------------------------------------------
def test_robot_disappearing_and_coming_back_is_survived(pair):
    robot, bridge = pair()
    robot.drop()
    wait_for(bridge, lambda e: e.kind == ev.STATUS and e.value["state"] == "disconnected")
    r = bridge.execute("Chat")
    assert not r["ok"] and "not connected" in r["reason"]
    assert bridge.diagnostics.snapshot()["incidents"]["link_down"] >= 1
    time.sleep(0.5)  # a few failed attempts with back-off
    robot.restart()
    assert bridge.wait_connected(10.0), bridge.status()
    st = bridge.status()
    assert st["connects"] == 2 and st["drops"] == 1
    assert bridge.read_body()["NEng"] == pytest.approx(50.0)
    bridge.poll_events()
    robot.raise_event("RearTactilTouched", 1.0)  # the subscribers were re-created
    wait_for(bridge, lambda e: e.kind == ev.FEEDBACK and e.value == 1)
    assert bridge.execute("Chat")["ok"]


def test_robot_dropping_itself_through_its_control_service(pair):
    robot, bridge = pair()
    ctl = qi.Session()
    ctl.connect(robot.url)
    ctl.service("HomeoStandin").dropFor(0.6)
    ctl.close()
    wait_for(bridge, lambda e: e.kind == ev.STATUS and e.value["state"] == "disconnected")
    assert bridge.wait_connected(10.0)
    assert bridge.read_world()["body"]["NEng"] == pytest.approx(50.0)


def test_refused_subscriber_falls_back_to_polling(pair):
    robot, bridge = pair(refuse_subscriber=True)
    assert set(bridge.status()["polled_keys"]) == set(bridge.parser.keys)
    robot.raise_event("FrontTactilTouched", 1.0)
    wait_for(bridge, lambda e: e.kind == ev.FEEDBACK and e.value == 1)
    robot.raise_event(WORD_EVENT, ["LightOff", 0.9])
    wait_for(bridge, lambda e: e.kind == ev.PROPOSAL and e.value == "LightOff")


# -- wrongly typed values ---------------------------------------------------------------
@pytest.mark.parametrize("key,value,reason", [
    (BATTERY_KEY, "abc", "expected a number"),
    (BATTERY_KEY, 1.7, "outside 0..1"),
    (temperature_key("HipPitch"), 7, "outside 0..3"),
    (temperature_key("HipPitch"), "hot", "expected a number"),
    (temperature_key("HipPitch"), 1.5, "integer"),
])
def test_wrongly_typed_reading_is_rejected_and_the_bridge_keeps_running(pair, key, value, reason):
    robot, bridge = pair()
    good = bridge.read_body()
    robot.inject(key, value)
    body = bridge.read_body()
    assert body == good  # the last good values stand in
    snap = bridge.diagnostics.snapshot()
    assert snap["rejected_by_source"] == {key: 1}
    assert reason in snap["recent"][-1]["reason"]
    got = bridge.poll_events()
    assert [e.value["source"] for e in got if e.kind == ev.REJECTED] == [key]
    robot.clear_injections()
    robot.battery = 20.0
    assert bridge.read_body()["NEng"] == pytest.approx(80.0)
    assert bridge.execute("Chat")["ok"]


def test_wrongly_typed_albattery_value_is_rejected(pair):
    robot, bridge = pair(settings=LinkSettings(battery_source="albattery"))
    assert bridge.read_body()["NEng"] == pytest.approx(50.0)
    robot.battery_override = "abc"
    assert bridge.read_body()["NEng"] == pytest.approx(50.0)
    assert bridge.diagnostics.snapshot()["rejected_by_source"] == {"ALBattery.getBatteryCharge": 1}


@pytest.mark.parametrize("key,value", [
    (EMOTION_EVENT, "furious"),
    (EMOTION_EVENT, [[2, 0.9], [0.1, 0.9, 0, 0, 0], 0.5]),  # the 0..1 shape of no NAOqi version
    (EMOTION_EVENT, [[2, 11], [1, 11, 0, 0, 0], 7]),  # above 2.5's 0..10
    (EMOTION_EVENT, [[2, 8], [1, 8, 0, 0], 7]),  # four levels
    (WORD_EVENT, ["Play"]),
    (WORD_EVENT, [42, 0.9]),
    ("FrontTactilTouched", "yes"),
    (CFG.gesture_event, 5),
])
def test_wrongly_typed_event_is_rejected_and_events_keep_flowing(pair, key, value):
    robot, bridge = pair()
    robot.raise_event(key, value)
    got = wait_for(bridge, lambda e: e.kind == ev.REJECTED)
    assert [e.value["source"] for e in got if e.kind == ev.REJECTED] == [key]
    assert bridge.diagnostics.rejected_total == 1
    robot.raise_event("MiddleTactilTouched", 1.0)
    wait_for(bridge, lambda e: e.kind == ev.FEEDBACK and e.value == 1)


def test_zone_list_of_wrong_type_is_rejected(pair):
    robot, bridge = pair()
    assert bridge.read_world()["human"]["relation"] == "far"
    robot.inject("EngagementZones/PeopleInZone1", "everyone")
    assert bridge.read_world()["human"]["relation"] == "far"  # the last good reading
    assert bridge.diagnostics.snapshot()["rejected_by_source"] == {"EngagementZones/PeopleInZone1": 1}


def test_status_validation_by_hand():
    assert [temperature_status(v) for v in (0, 1, 2, 3, 2.0)] == [0, 1, 2, 3, 2]
    for bad in (7, -1, True, None, "2"):
        with pytest.raises(Rejected):
            temperature_status(bad)


# -- the stand-in as a program ----------------------------------------------------------
def test_standin_cli_prints_its_url_first_and_serves(thesis):
    proc = subprocess.Popen([sys.executable, "-m", "pepper_bridge.standin", "--listen", "tcp://127.0.0.1:0",
                             "--battery", "12", "--time-scale", "0", "--seed", "3"],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        url = proc.stdout.readline().strip()
        assert url.startswith("tcp://127.0.0.1:") and not url.endswith(":0")
        bridge = PepperBridge(CFG, LinkSettings(url=url), thesis)
        try:
            assert bridge.start(10.0)
            assert bridge.read_body()["NEng"] == pytest.approx(88.0)
        finally:
            bridge.stop()
    finally:
        proc.terminate()
        assert proc.wait(timeout=10) == 0


def test_standin_cli_refuses_non_loopback():
    r = subprocess.run([sys.executable, "-m", "pepper_bridge.standin", "--listen", "tcp://0.0.0.0:0"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode != 0 and "loopback" in r.stderr


def test_all_joints_are_read_in_one_call(pair):
    robot, bridge = pair()
    robot._calls.clear()
    bridge.read_body()
    lists = [c for c in robot.calls(exclude_memory_reads=False) if c[1] == "getListData"]
    assert lists == [("ALMemory", "getListData", [[temperature_key(j) for j in PEPPER_JOINTS]])]
