"""What the robot senses is what the decision sees (issue 22, item 3): a person in engagement zone 1
reads as near wherever the robot stands, through the bridge, the environment, the messages and the
robot's parts, on the stand-in Pepper over libqi.

The stand-in's person follows the NAOqi documentation (``pepper_bridge.standin_person``), cited beside
each value here:

- ZONES: http://doc.aldebaran.com/2-8/naoqi/peopleperception/alengagementzones.html: "Zone1 is near, in
  front"; ``EngagementZones/PeopleInZone1..3`` "store the list of the IDs of the people in each zone".
- LIFE: http://doc.aldebaran.com/2-8/ref/life/extractors_management.html: a Pepper's limits under
  Autonomous Life, FirstLimitDistance 0.8, SecondLimitDistance 0.9, LimitAngle 90.
- API: http://doc.aldebaran.com/2-4/naoqi/peopleperception/alengagementzones-api.html:
  ``computeEngagementZone(x, y, z)`` of a point in FRAME_ROBOT returns its zone; the limits' getters.
- PEOPLE: http://doc.aldebaran.com/2-5/naoqi/peopleperception/alpeopleperception.html:
  ``PeoplePerception/PeopleList``, the people tracked.

The shipped config puts the places at H (0, 0), C (3, 0), R (0, 3); the scenario's human location is H.
"""

from __future__ import annotations

import time

import pytest

qi = pytest.importorskip("qi")

from homeo_decision import codec  # noqa: E402
from homeo_decision.agent import DecisionCore  # noqa: E402
from homeo_decision.hosts import DecisionHost, PerceptionHost  # noqa: E402
from homeo_decision.robot import OracleRecognition, Robot  # noqa: E402
from homeo_intention.recognition import RecognitionHost  # noqa: E402
from homeo_msgs_py.graph import ORACLE, TOPICS  # noqa: E402
from homeo_msgs_py.schemas import decode, encode  # noqa: E402
from pepper_bridge.bridge import PepperBridge  # noqa: E402
from pepper_bridge.config import LinkSettings, load_config  # noqa: E402
from pepper_bridge.environment import PepperEnvironment  # noqa: E402
from pepper_bridge.mapping import PEOPLE_KEY, ZONE_KEYS, relation_from_zones  # noqa: E402
from pepper_bridge.standin import StandinRobot  # noqa: E402
from pepper_bridge.standin_person import PERSON_ID  # noqa: E402

pytestmark = pytest.mark.qi
qi.logging.setLevel(qi.logging.WARNING)
CFG = load_config()
NOBODY_ELSE = []  # ZONES: a zone's list holds the ids of the people in it; our one person is elsewhere
# the person walks up to the robot as it arrives at each place, then goes home (the user's place, H)
WALKING_UP = {"schema": "homeo-pepper-user", "version": 1, "start": {"battery_percent": 80, "location": "R"},
              "interactions": [{"intention": None, "walks": "to_robot"}] * 3 + [{"intention": None, "walks": "home"}]}


@pytest.fixture
def session(thesis):
    robot = StandinRobot(CFG, WALKING_UP, time_scale=0.0, scenario=thesis)
    bridge = PepperBridge(CFG, LinkSettings(url=robot.start()), thesis)
    try:
        assert bridge.start(10.0), bridge.status()
        end = time.monotonic() + 10.0
        while not robot.user.started and time.monotonic() < end:  # the user starts once the robot listens
            time.sleep(0.02)
        assert robot.user.started
        yield robot, bridge, PepperEnvironment(bridge, quiet=0.05, window=0.5, use_cues=True)
    finally:
        bridge.stop()
        robot.close()


def memory(bridge, key):
    return bridge.link.call("ALMemory", "getData", key)


def decision_sees(sc, obs):
    """The code the decision perceives the observation in: through the graph's messages (the world node's
    ``homeo/world`` and ``homeo/observation`` -> intention node -> drives node -> decision node, each
    message encoded and decoded at the boundary), and in-process (``Robot.step``)."""
    voc = codec.vocabulary(sc)

    def message(key, fields):
        return decode(encode(TOPICS[key].schema, 0, fields), voc, TOPICS[key].schema)

    world, seen = codec.observation_messages(sc, obs)
    recognition, drives, decision = RecognitionHost(sc, ORACLE), PerceptionHost(sc), DecisionHost(sc, DecisionCore(sc, 0))
    [(_, intention)] = recognition.stage.put("observation", message("observation", seen))
    assert drives.stage.put("world", message("world", world)) == []
    [(_, drives_fields)] = drives.stage.put("intention", message("intention", intention))
    [(_, action)] = decision.stage.put("drives", message("drives", drives_fields))
    assert action["action"] in sc.action_names
    robot = Robot(sc, DecisionCore(sc, 0), OracleRecognition(sc))
    robot.step(0, obs, None)
    assert robot.percept.code == decision.decision.prev.code  # the graph and the in-process robot agree
    return drives_fields["world"]["human"], decision.decision.prev.code


def test_a_person_in_zone_1_reads_as_near_wherever_the_robot_stands(session, thesis):
    sc = thesis
    robot, bridge, env = session
    chat, rest = sc.action_index("Chat"), sc.action_index("Rest")
    for place, move in (("R", None), ("C", "MoveToC"), ("H", "MoveToH")):
        if move is not None:
            out = env.step(sc.action_index(move))  # the person walks up as the robot arrives
            assert out.failure is None
        # API: the stand-in answers its own limits (LIFE: 0.8 / 0.9 / 90) and zones
        ez = bridge.link.call
        assert [round(ez("ALEngagementZones", m), 6) for m in
                ("getFirstLimitDistance", "getSecondLimitDistance", "getLimitAngle")] == [0.8, 0.9, 90.0]
        assert ez("ALEngagementZones", "computeEngagementZone", 0.5, 0.0, 0.0) == 1  # ZONES: near, in front
        # ZONES: the person's id in zone 1's list; PEOPLE: tracked
        assert memory(bridge, ZONE_KEYS[0]) == [PERSON_ID], place
        assert memory(bridge, ZONE_KEYS[1]) == NOBODY_ELSE and memory(bridge, ZONE_KEYS[2]) == NOBODY_ELSE
        assert memory(bridge, PEOPLE_KEY) == [PERSON_ID]
        # the bridge reads near; the environment's world code holds it
        assert bridge.read_world()["human"] == {"presence": "present", "relation": "near"}, place
        obs = env.observe()
        v = sc.view(obs.code)
        assert (v["robot.location"], v["human.relation"]) == (place, "near")
        # the decision sees it: S_hum's relation (Eq 3.9), Chat allowed and Rest not (Table 3.3)
        human, code = decision_sees(sc, obs)
        assert human == {"presence": "present", "relation": "near"}
        assert sc.c.relation_of[code] == 0 and chat in sc.c.valid[code] and rest not in sc.c.valid[code], place
    # back home at H while the robot goes to R: 3.04 m away, beyond SecondDistance (zone 3): far
    env.step(sc.action_index("MoveToR"))
    assert memory(bridge, ZONE_KEYS[2]) == [PERSON_ID] and memory(bridge, ZONE_KEYS[0]) == NOBODY_ELSE
    obs = env.observe()
    assert sc.view(obs.code)["human.relation"] == "far"
    human, code = decision_sees(sc, obs)
    assert human["relation"] == "far" and chat not in sc.c.valid[code]


def test_the_simulations_person_stays_home(thesis):
    """Without ``walks`` (every shipped script) the person stays at the user's place: near only with the
    robot at H, as the simulation derives it (Section 4.2.1), so the field test reads what it read."""
    robot = StandinRobot(CFG, {"schema": "homeo-pepper-user", "version": 1}, time_scale=0.0, scenario=thesis)
    read = lambda: relation_from_zones(*(robot.people()[k] for k in (*ZONE_KEYS, PEOPLE_KEY)))  # the bridge's reading
    try:
        rel = {}
        for place, (x, y) in CFG.places.items():
            robot.x, robot.y = x, y
            rel[place] = read()
        assert rel == {"H": "near", "C": "far", "R": "far"}
        robot.user.present = False
        assert read() == "absent"
    finally:
        robot.close()
