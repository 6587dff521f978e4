"""The ALMemory keys, events and value formats the stand-in Pepper writes, each from its NAOqi documentation
page (no qi import). Written from the documentation, not taken from the bridge's ``mapping``: a key or format
the bridge gets wrong is then wrong on one side only, and the qi tests see it. Where no page in reach confirms
a value, its comment says so (docs/PEPPER.md, "NAOqi as documented", has the searches).
"""

from __future__ import annotations

# Pepper's joints and wheels, and each one's "Temperature status" key, 0..3 (Pepper actuator & sensor list:
# http://doc.aldebaran.com/2-8/family/pepper_technical/pepper_dcm/actuator_sensor_names.html; the statuses:
# http://doc.aldebaran.com/2-4/naoqi/sensors/albodytemperature.html)
JOINTS = ("HeadYaw", "HeadPitch", "LShoulderPitch", "LShoulderRoll", "LElbowYaw", "LElbowRoll", "LWristYaw", "LHand",
          "HipRoll", "HipPitch", "KneePitch", "RShoulderPitch", "RShoulderRoll", "RElbowYaw", "RElbowRoll",
          "RWristYaw", "RHand", "WheelFL", "WheelFR", "WheelB")
TEMPERATURE_KEY = "Device/SubDeviceList/{}/Temperature/Sensor/Status"
# the battery's charge, same page (Battery); the 0..1 fraction is not confirmed by a page in reach
BATTERY_KEY = "Device/SubDeviceList/Battery/Charge/Sensor/Value"
# ALBattery raises the battery's events (http://doc.aldebaran.com/2-8/naoqi/sensors/albattery.html); this one
# (a bool: on the charger) is named from the list of events, whose page is not in reach
PLUGGED_EVENT = "BatteryPowerPluggedChanged"
# the head's three touch sensors (http://doc.aldebaran.com/2-5/family/robots/contact-sensors_robot.html), raised
# on a touch and again on the release, "bistable" (http://doc.aldebaran.com/2-4/naoqi/sensors/altouch.html)
TOUCH_EVENTS = ("FrontTactilTouched", "MiddleTactilTouched", "RearTactilTouched")
TOUCHED, RELEASED = 1.0, 0.0
# [phrase_1, confidence_1, ..., phrase_n, confidence_n], most likely first
# (http://doc.aldebaran.com/2-8/naoqi/audio/alspeechrecognition.html)
WORD_EVENT = "WordRecognized"
# [[matched index, matched level], [calm, anger, joy, sorrow, laughter], excitement]; index 0 unknown, 1 calm,
# 2 anger, 3 joy, 4 sorrow; levels integers 0..5 up to NAOqi 2.4 (http://doc.aldebaran.com/2-1/naoqi/audio/
# alvoiceemotionanalysis.html, .../2-4/...), 0..10 from 2.5 (.../2-5/..., .../2-8/...); e.g. [[4,3],[0,2,1,3,0],1]
EMOTION_EVENT = "ALVoiceEmotionAnalysis/EmotionRecognized"
# the ids of the people in each engagement zone (http://doc.aldebaran.com/2-8/naoqi/peopleperception/
# alengagementzones.html) and of the people tracked (http://doc.aldebaran.com/2-5/naoqi/peopleperception/
# alpeopleperception.html)
ZONE_KEYS = ("EngagementZones/PeopleInZone1", "EngagementZones/PeopleInZone2", "EngagementZones/PeopleInZone3")
PEOPLE_KEY = "PeoplePerception/PeopleList"


def emotion_scale(version: str) -> int:
    """The top of the emotion levels for a NAOqi version ("2.5.5.5": 10; "2.4": 5); ValueError for no version."""
    try:
        release = tuple(int(p) for p in str(version).strip().split(".")[:2])
    except ValueError:
        raise ValueError(f"not a NAOqi version: {version!r} (e.g. 2.5.5.5)") from None
    if len(release) < 2:
        raise ValueError(f"not a NAOqi version: {version!r} (e.g. 2.5.5.5)")
    return 5 if release < (2, 5) else 10


def voice(scale: int, calm: int = 0, anger: int = 0, joy: int = 0, sorrow: int = 0, laughter: int = 0,
          excitement: int = 0) -> list:
    """An EmotionRecognized value in the documented shape (the stand-in's voices); the matched
    emotion is the highest of calm..sorrow (laughter is never matched; 0 = unknown when all are 0)."""
    levels = [calm, anger, joy, sorrow, laughter]
    for v in levels:
        if not 0 <= v <= scale:
            raise ValueError(f"level {v} outside 0..{scale}")
    top = max(levels[:4])
    index = levels[:4].index(top) + 1 if top > 0 else 0
    return [[index, top], levels, excitement]
