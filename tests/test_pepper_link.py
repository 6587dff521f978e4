"""A robot that fails loudly: every call bounded, a frozen robot reported, bad URLs refused.

Real libqi sessions on loopback (the stand-in), no mocks of qi; every wait has a bound.
"""

from __future__ import annotations

import socket
import subprocess
import sys
import time

import pytest

qi = pytest.importorskip("qi")

from pepper_bridge.bridge import PepperBridge  # noqa: E402
from pepper_bridge.config import LinkSettings, load_config  # noqa: E402
from pepper_bridge.environment import PepperEnvironment  # noqa: E402
from pepper_bridge.mapping import emotion_scale  # noqa: E402
from pepper_bridge.naoqi_link import RobotUnavailable  # noqa: E402
from pepper_bridge.standin import NotNaoqiPort, StandinRobot  # noqa: E402

pytestmark = pytest.mark.qi
qi.logging.setLevel(qi.logging.ERROR)
CFG = load_config()
FAST = dict(call_timeout=1.0, action_timeout=3.0, heartbeat_period=0.3, heartbeat_timeout=1.0)


@pytest.fixture
def pair(thesis):
    made = []

    def make(**link):
        robot = StandinRobot(CFG, None, battery=50.0, time_scale=0.0)
        s = LinkSettings(url=robot.start(), **dict(FAST, **link))
        bridge = PepperBridge(CFG, s, thesis)
        made.append((robot, bridge))
        assert bridge.start(10.0), bridge.status()
        settle(robot)
        return robot, bridge

    yield make
    for robot, bridge in made:
        robot._thawed.set()
        bridge.stop()
        robot.close()


def settle(robot, quiet=0.3, timeout=5.0):
    """Until the bridge's set-up calls (subscriptions, vocabulary) are over: no new call for ``quiet`` s."""
    end, n, since = time.monotonic() + timeout, -1, time.monotonic()
    while time.monotonic() < end:
        m = len(robot.calls())
        if m != n:
            n, since = m, time.monotonic()
        elif time.monotonic() - since >= quiet:
            return
        time.sleep(0.05)


def wait_state(bridge, state, timeout):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if bridge.status()["state"] == state:
            return time.monotonic()
        time.sleep(0.05)
    raise AssertionError(f"state {bridge.status()['state']!r}, not {state!r} within {timeout} s")


def test_frozen_robot_is_reported_while_frozen_and_comes_back(pair):
    robot, bridge = pair()
    robot.freeze_for(12.0)
    wait_state(bridge, "unresponsive", 12.0)
    assert robot.frozen  # the heartbeat found it, not the thaw
    assert not bridge.link.connected
    assert bridge.diagnostics.snapshot()["incidents"].get("robot_unresponsive") == 1
    with pytest.raises(RobotUnavailable, match="robot not connected"):  # while frozen a call fails at once
        bridge.read_body()
    assert robot.frozen
    robot._thawed.set()  # thaw now rather than wait the freeze out
    wait_state(bridge, "connected", 20.0)
    assert bridge.status()["freezes"] == 1 and bridge.status()["drops"] == 0
    assert bridge.read_body()["battery_percent"] == pytest.approx(50.0)


def test_a_call_the_robot_never_answers_ends_at_its_timeout(pair):
    robot, bridge = pair(heartbeat_period=30.0)  # no heartbeat: the call's own bound must hold
    robot.freeze_for(30.0)
    t = time.monotonic()
    with pytest.raises(RobotUnavailable, match="did not answer ALMemory.getData within 1 s"):
        bridge.read_battery()
    assert 0.9 < time.monotonic() - t and robot.frozen  # it waited its bound, not the 30 s freeze
    assert bridge.status()["state"] == "unresponsive"


def test_a_move_on_a_frozen_robot_fails_as_soon_as_the_freeze_is_found(pair):
    robot, bridge = pair(action_timeout=30.0)
    robot.freeze_for(30.0)
    res = bridge.execute("MoveToH")
    assert res["ok"] is False and "robot" in res["reason"]
    assert robot.frozen  # the heartbeat found the freeze long before the 30 s action bound or the thaw
    assert bridge.location == "R"  # nothing happened


def test_frozen_step_is_a_failed_step_and_the_next_observation_is_held(pair, thesis):
    robot, bridge = pair()
    env = PepperEnvironment(bridge, quiet=0.05, window=0.3)
    env.observe()
    robot.freeze_for(30.0)
    out = env.step(thesis.action_index("MoveToH"))
    assert out.action is None and out.failure
    assert env.log[-1]["ok"] is False
    with pytest.raises(RobotUnavailable):
        env.observe()  # held: the driver retries until the robot answers
    robot._thawed.set()
    wait_state(bridge, "connected", 20.0)
    assert env.observe() is not None


def test_not_naoqi_port_and_closed_port_never_connect(thesis):
    for mode in ("silent", "http"):
        with NotNaoqiPort(mode) as port:
            bridge = PepperBridge(CFG, LinkSettings(url=port.url, connect_timeout=1.0, **FAST), thesis)
            assert not bridge.start(2.5)
            status = bridge.status()  # before stop(), which says "stopped"
            bridge.stop()
            assert status["state"] == "disconnected" and status["reason"].startswith("connect failed"), status


def _closed_port() -> int:
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()  # nobody listens there now
    return port


@pytest.mark.parametrize("what", ["closed", "silent", "http", "port9"])
def test_launcher_exits_2_with_one_line_within_the_bound(what):
    port = None
    if what == "closed":
        url = f"tcp://127.0.0.1:{_closed_port()}"
    elif what == "port9":
        url = "tcp://127.0.0.1:9"
    else:
        port = NotNaoqiPort(what)
        url = port.url
    try:
        t = time.monotonic()
        p = subprocess.run([sys.executable, "-m", "homeo_launch.cli", "pepper", "--qi-url", url, "--connect-bound", "4"],
                           capture_output=True, text=True, timeout=30)
        took = time.monotonic() - t
    finally:
        if port is not None:
            port.close()
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode == 2, p.stderr
    assert len(lines) == 1, p.stderr
    assert url in lines[0] and "robot" in lines[0]
    assert took < 4 + 6  # the bound, plus the interpreter's start


def test_probe_names_an_unknown_host_without_asking_a_name_server(monkeypatch):
    from pepper_bridge import launch_support as launcher

    def no_such_host(*a, **k):
        raise socket.gaierror(socket.EAI_NONAME, "Name or service not known")

    monkeypatch.setattr(socket, "getaddrinfo", no_such_host)
    with pytest.raises(launcher.WorldConfigError, match="unknown host 'pepper.invalid'"):
        launcher.probe_robot("tcp://pepper.invalid:9559", 3.0)


def test_probe_accepts_the_standin():
    from pepper_bridge import launch_support as launcher

    robot = StandinRobot(CFG, None, time_scale=0.0)
    try:
        launcher.probe_robot(robot.start(), 5.0)
    finally:
        robot.close()


# -- what the bridge sets up on the robot -----------------------------------------------------
def test_extractors_and_speech_are_subscribed_and_unsubscribed(thesis):
    robot = StandinRobot(CFG, None, battery=50.0, time_scale=0.0)
    bridge = PepperBridge(CFG, LinkSettings(url=robot.start(), **FAST), thesis)
    try:
        assert bridge.start(10.0)
        settle(robot)
        calls = [(s, m, a) for s, m, a in robot.calls() if m in ("subscribe", "setLanguage", "setVocabulary")]
        name = bridge.subscriber
        assert name == "homeo_pepper_bridge_1"
        assert [(s, m) for s, m, _ in calls] == [("ALPeoplePerception", "subscribe"), ("ALEngagementZones", "subscribe"),
                                                 ("ALSpeechRecognition", "setLanguage"),
                                                 ("ALSpeechRecognition", "setVocabulary"),
                                                 ("ALSpeechRecognition", "subscribe"),
                                                 ("ALVoiceEmotionAnalysis", "subscribe")]
        assert calls[2][2] == ["English"]
        vocab = calls[3][2][0]
        assert "turn on the light" in vocab and "play music" in vocab
        assert not set(vocab) & {a.lower() for a in thesis.action_names}  # words people say, no action ids
        # after a drop: subscribed again under a fresh name
        robot.drop_for(0.5)
        wait_state(bridge, "disconnected", 5.0)
        wait_state(bridge, "connected", 10.0)
        settle(robot)
        subs = [a[0] for s, m, a in robot.calls() if s == "ALSpeechRecognition" and m == "subscribe"]
        assert subs == ["homeo_pepper_bridge_1", "homeo_pepper_bridge_2"]
    finally:
        bridge.stop()
        unsubs = [(s, a[0]) for s, m, a in robot.calls() if m == "unsubscribe"]
        robot.close()
    assert unsubs == [(s, "homeo_pepper_bridge_2") for s in ("ALVoiceEmotionAnalysis", "ALSpeechRecognition",
                                                              "ALEngagementZones", "ALPeoplePerception")]


def test_a_spoken_phrase_is_a_proposal(pair):
    from pepper_bridge import events as ev
    from pepper_bridge.mapping import WORD_EVENT

    robot, bridge = pair()
    robot.raise_event(WORD_EVENT, ["play music", 0.8, "stop the music", 0.3])
    got = bridge.collect(0.3, 2.0)
    assert [(e.kind, e.value) for e in got if e.kind == ev.PROPOSAL] == [(ev.PROPOSAL, "Play")]


# -- the NAOqi version: asked of the robot, the config overrides -------------------------------
# EmotionRecognized levels are 0..10 on NAOqi 2.5/2.8 and 0..5 on 2.1/2.4
# (http://doc.aldebaran.com/2-5/naoqi/audio/alvoiceemotionanalysis.html, .../2-4/...)
ANGRY_24 = [[2, 4], [1, 4, 0, 0, 0], 5]  # anger 4 of 5: above the threshold 5 of 10 = 2.5 of 5
ANGRY_25 = [[2, 8], [1, 8, 0, 0, 0], 7]  # the documented scale of 2.5: 8 of 10, impossible on 0..5


def feedback_of(robot, bridge, value) -> tuple[list, int]:
    from pepper_bridge import events as ev
    from pepper_bridge.mapping import EMOTION_EVENT

    robot.raise_event(EMOTION_EVENT, value)
    got = bridge.collect(0.3, 2.0)
    return [e.value for e in got if e.kind == ev.FEEDBACK], sum(1 for e in got if e.kind == ev.REJECTED)


@pytest.mark.parametrize("robot_version, configured, scale, scolded_by, rejects", [
    ("2.4.3.28", "auto", 5, ANGRY_24, ANGRY_25),  # asked: a 2.4 robot's 4 of 5 scolds, an 8 is off its scale
    ("2.5.5.5", "auto", 10, ANGRY_25, None),  # asked: 2.5's 0..10; 4 of 10 is not a scolding
    ("2.4.3.28", "2.5", 10, ANGRY_25, None),  # the config overrides what the robot says
])
def test_the_emotion_scale_follows_the_version_the_robot_reports(thesis, robot_version, configured, scale,
                                                                  scolded_by, rejects):
    import dataclasses

    cfg = dataclasses.replace(CFG, naoqi_version=configured, robot_version=None)
    robot = StandinRobot(cfg, None, battery=50.0, time_scale=0.0, naoqi_version=robot_version)
    bridge = PepperBridge(cfg, LinkSettings(url=robot.start(), **FAST), thesis)
    try:
        assert bridge.start(10.0)
        settle(robot)
        asked = [c for c in robot.calls("ALSystem") if c[1] == "systemVersion"]
        assert len(asked) == (1 if configured == "auto" else 0)
        n = bridge.naoqi()
        assert (n["emotion_scale"], n["source"]) == (scale, "robot" if configured == "auto" else "config")
        assert robot.emotion_scale == emotion_scale(robot_version)  # the stand-in speaks its own version
        assert feedback_of(robot, bridge, scolded_by) == ([-1], 0)
        if scale == 10:
            assert feedback_of(robot, bridge, ANGRY_24) == ([], 0)  # 4 of 10: not above 5
        if rejects is not None:
            assert feedback_of(robot, bridge, rejects) == ([], 1)
    finally:
        bridge.stop()
        robot.close()


def test_a_version_without_a_known_scale_keeps_the_default_and_says_so(thesis):
    import dataclasses

    cfg = dataclasses.replace(CFG, naoqi_version="auto", robot_version=None)
    robot = StandinRobot(cfg, None, battery=50.0, time_scale=0.0)
    robot.naoqi_version = "9.1.0"  # a version no page documents
    bridge = PepperBridge(cfg, LinkSettings(url=robot.start(), **FAST), thesis)
    try:
        assert bridge.start(10.0)
        settle(robot)
        assert bridge.naoqi()["source"] == "default" and bridge.naoqi()["emotion_scale"] == 10
        snap = bridge.diagnostics.snapshot()
        assert snap["incidents"].get("naoqi_version unknown") == 1
        assert any("9.1.0" in r["reason"] for r in snap["recent"])
    finally:
        bridge.stop()
        robot.close()
