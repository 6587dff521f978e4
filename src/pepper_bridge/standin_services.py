"""The NAOqi services of the stand-in Pepper, by NAOqi's method names, each call recorded:

- ``ALMemory``: getData, getListData, insertData, raiseEvent, subscriber(key) (an object with a ``signal``),
  declareEvent, getDataList, getEventList.
- ``ALBattery``: getBatteryCharge (percent).
- ``ALMotion``: wakeUp, rest, robotIsWakeUp, moveTo(x, y, theta).
- ``ALNavigation``: navigateTo(x, y).
- ``ALTextToSpeech``: say(text).
- ``ALSpeechRecognition``: setLanguage, setVocabulary, pause, subscribe, unsubscribe.
- ``ALVoiceEmotionAnalysis``, ``ALPeoplePerception``: subscribe, unsubscribe (extractors).
- ``ALEngagementZones``: the extractor's, and the zones' limits and computeEngagementZone(x, y, z).
- ``ALSystem``: systemVersion (``naoqi_version``, e.g. "2.5.5.5"; the user's voices are on its scale), robotName.
- ``HomeoStandin`` (not NAOqi; for tests and the CLI): calls, clearCalls, inject, clearInjections,
  setBatteryOverride, dropFor, freezeFor, state, userLog.
"""

from __future__ import annotations

import threading

import qi

from .standin_naoqi import EMOTION_EVENT, PLUGGED_EVENT, TOUCH_EVENTS, WORD_EVENT
from .standin_person import engagement_zone


class _Sub:
    """What ``ALMemory.subscriber(key)`` returns: an object with a ``signal``."""

    def __init__(self):
        self.signal = qi.Signal("m")


def naoqi_services(robot) -> dict:
    """The services ``robot`` (a ``StandinRobot``) offers, by name (registered on each session it opens)."""

    def service(name: str, recorded: bool = True, **methods):
        """A service: method -> (return type, argument types, what it does with the arguments, or None). A NAOqi
        call is recorded first (where a frozen robot holds it); ``HomeoStandin``'s are not (it always answers)."""
        def bind(method, ret, args, does):
            @qi.bind(ret, args)
            def call(self, *a):
                if recorded:
                    robot.record(name, method, *a)
                return does(*a) if does else None
            return call
        return type(name, (), {m: bind(m, *spec) for m, spec in methods.items()})()

    def read(keys):  # getData (one key) and getListData, the body and presence brought up to now
        with robot.lock:
            robot._advance()
            robot._publish()
            if isinstance(keys, str) and keys not in robot.data:
                raise RuntimeError(f"ALMemory::getData: data not found: {keys}")
            return robot.data[keys] if isinstance(keys, str) else [robot.data.get(k) for k in keys]

    def insert(key, value):
        with robot.lock:
            robot.data[key] = value

    def subscriber(key):
        if robot.refuse_subscriber:
            raise RuntimeError("ALMemory::subscriber: refused by this robot")
        with robot.lock:
            return robot.subs.setdefault(key, _Sub())

    def data_list(filt):
        with robot.lock:
            robot._publish()
            return sorted(k for k in robot.data if filt in k)

    def battery_charge():
        with robot.lock:
            if robot.battery_override is not None:
                return robot.battery_override
            robot._advance()
            return int(round(robot.battery))

    def wake_up():
        with robot.lock:
            robot.awake = True

    def rest():
        robot.script_fault()
        with robot.lock:
            robot._advance()
            robot.awake = False
            robot._act()
            emits = robot._user_saw(robot.cfg.rest_action())
        robot.emit(emits)

    def say(text):
        robot.script_fault()
        with robot.lock:
            robot._advance()
            emits = robot._user_saw(robot.phrases.get(text))  # e.g. plugged in when asked for help
            robot._act()
            robot._publish()
        robot.emit(emits)

    def battery_override(value):
        with robot.lock:
            robot.battery_override = value

    S, F, V, B, D = qi.String, qi.Float, qi.Void, qi.Bool, qi.Dynamic
    # an extractor (ALExtractor API): subscribe / unsubscribe
    extractor = {"subscribe": (V, [S], None), "unsubscribe": (V, [S], None)}
    events = lambda: sorted(set(TOUCH_EVENTS) | {EMOTION_EVENT, WORD_EVENT, PLUGGED_EVENT, robot.cfg.gesture_event,  # noqa: E731
                                                 robot.cfg.movement_event} | robot.events_declared)
    limits = robot.person.limits
    return {
        "ALMemory": service(
            "ALMemory", getData=(D, [S], read), getListData=(D, [qi.List(S)], read), insertData=(V, [S, D], insert),
            raiseEvent=(V, [S, D], lambda k, v: robot.emit([(k, v)])),
            declareEvent=(V, [S], robot.events_declared.add), subscriber=(qi.Object, [S], subscriber),
            getDataList=(qi.List(S), [S], data_list), getEventList=(qi.List(S), [], events)),
        "ALBattery": service("ALBattery", getBatteryCharge=(D, [], battery_charge)),
        "ALMotion": service("ALMotion", wakeUp=(V, [], wake_up), rest=(V, [], rest),
                            robotIsWakeUp=(B, [], lambda: robot.awake),
                            moveTo=(B, [F, F, F], lambda x, y, theta: robot._motion(x, y))),
        "ALNavigation": service("ALNavigation", navigateTo=(B, [F, F], lambda x, y: robot._motion(x, y))),
        "ALTextToSpeech": service("ALTextToSpeech", say=(V, [S], say)),
        "ALSpeechRecognition": service(
            "ALSpeechRecognition", setLanguage=(V, [S], None), setVocabulary=(V, [qi.List(S), B], None),
            pause=(V, [B], None), subscribe=(V, [S], lambda name: robot.start_user()),  # the user talks once it listens
            unsubscribe=(V, [S], None)),
        # EmotionRecognized values come from user.angry_voice / calm_voice, on the version's documented scale
        "ALVoiceEmotionAnalysis": service("ALVoiceEmotionAnalysis", **extractor),
        "ALPeoplePerception": service("ALPeoplePerception", **extractor),
        # the zones' limits and computeEngagementZone(x, y, z) (a point in FRAME_ROBOT -> its zone)
        # (http://doc.aldebaran.com/2-4/naoqi/peopleperception/alengagementzones-api.html)
        "ALEngagementZones": service(
            "ALEngagementZones", **extractor, getFirstLimitDistance=(F, [], lambda: limits.first),
            getSecondLimitDistance=(F, [], lambda: limits.second), getLimitAngle=(F, [], lambda: limits.angle),
            computeEngagementZone=(qi.Int32, [F, F, F], lambda x, y, z: engagement_zone(float(x), float(y), limits))),
        # NAOqi SDK ALSystemProxy: std::string systemVersion() "running system version"
        "ALSystem": service("ALSystem", systemVersion=(S, [], lambda: robot.naoqi_version),
                            robotName=(S, [], lambda: "standin")),
        "HomeoStandin": service(
            "HomeoStandin", False, calls=(D, [], lambda: [[s, m, a] for s, m, a in robot.calls()]),
            clearCalls=(V, [], robot.clear_calls), inject=(V, [S, D], robot.inject),
            clearInjections=(V, [], robot.clear_injections), setBatteryOverride=(V, [D], battery_override),
            dropFor=(V, [F], lambda seconds: threading.Timer(0.05, robot.drop_for, args=(seconds,)).start()),
            freezeFor=(V, [F], robot.freeze_for), state=(D, [], robot.state), userLog=(D, [], lambda: list(robot.user.log))),
    }
