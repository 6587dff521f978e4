"""The stand-in's person, as ALPeoplePerception and ALEngagementZones report a person (no qi import).

What a Pepper writes into ALMemory about the people around it, from the NAOqi documentation (each
value cites its page; "2-8" pages say the same as 2-4 and 2-1 for these keys):

- ``EngagementZones/PeopleInZone1``, ``...2``, ``...3``: "store the list of the IDs of the people in
  each zone" (http://doc.aldebaran.com/2-8/naoqi/peopleperception/alengagementzones.html, "UseCases").
- The zones, from a person's position relative to the robot and three limits (same page, "Zone
  definition"): "Zone1 is near, in front", "Zone2 is far in front and also near but on the sides",
  "Zone3 is far on the side and also 'very far' i.e. beyond SecondDistance"; FirstDistance defines
  "near", SecondDistance "farther", LimitAngle "in front".
- ``PeoplePerception/PeopleList``: the ids of the people tracked
  (http://doc.aldebaran.com/2-5/naoqi/peopleperception/alpeopleperception.html, "People list"); people are
  tracked up to ``getMaximumDetectionRange()``, "the default value is 3.5 meters"
  (http://doc.aldebaran.com/2-5/naoqi/peopleperception/alpeopleperception-api.html).
- Positions are in FRAME_ROBOT, whose "x axis is always forwards" (http://doc.aldebaran.com/2-8/glossary.html);
  the stand-in's robot keeps its heading along the map's x axis.

The page's diagram of the zones is an image the corpus does not hold: LimitAngle is read here as the
opening of the front sector (90 degrees: 45 on each side). The stand-in's person only ever stands
straight in front of a robot's spot or behind / beyond SecondDistance, where both readings agree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .standin_naoqi import PEOPLE_KEY, ZONE_KEYS

PERSON_ID = 17  # an id as ALPeoplePerception gives one (an integer of the population)


@dataclass(frozen=True)
class ZoneLimits:
    """ALEngagementZones' parameters: FirstDistance and SecondDistance (metres), LimitAngle (degrees)."""

    first: float
    second: float
    angle: float

    def __post_init__(self):
        # setFirstLimitDistance: "It must be positive and smaller than the current value of SecondDistance"
        # (http://doc.aldebaran.com/2-4/naoqi/peopleperception/alengagementzones-api.html)
        if not (0.0 < self.first < self.second and math.isfinite(self.second)) or not 0.0 < self.angle <= 360.0:
            raise ValueError(f"engagement zone limits must be 0 < first < second (metres) and 0 < angle <= 360 "
                             f"(degrees), got {self.first!r}, {self.second!r}, {self.angle!r}")


# "Default values: FirstDistance = 1.5m, SecondDistance = 2.5m and LimitAngle = 90 degrees" (alengagementzones.html)
DEFAULT_LIMITS = ZoneLimits(1.5, 2.5, 90.0)
# Autonomous Life on a Pepper sets FirstLimitDistance 0.8, SecondLimitDistance 0.9, LimitAngle 90
# (http://doc.aldebaran.com/2-8/ref/life/extractors_management.html): a Pepper as it ships
PEPPER_LIFE_LIMITS = ZoneLimits(0.8, 0.9, 90.0)
DETECTION_RANGE = 3.5  # metres: ALPeoplePerception's default maximum detection range (alpeopleperception-api.html)
# where the person stands when with the robot: half a metre straight ahead, inside zone 1 under both limit sets
IN_FRONT = 0.5


def engagement_zone(dx: float, dy: float, limits: ZoneLimits = PEPPER_LIFE_LIMITS) -> int:
    """The zone (1, 2, 3) of a point ``(dx, dy)`` metres from the robot in FRAME_ROBOT (x forwards);
    ValueError for a point that is not finite."""
    if not (math.isfinite(dx) and math.isfinite(dy)):
        raise ValueError(f"a position must be finite metres, got ({dx!r}, {dy!r})")
    d = math.hypot(dx, dy)
    if d > limits.second:
        return 3  # "very far", beyond SecondDistance
    front = d == 0.0 or abs(math.degrees(math.atan2(dy, dx))) <= limits.angle / 2.0
    if d < limits.first:
        return 1 if front else 2  # near: "in front" zone 1, "on the sides" zone 2
    return 2 if front else 3  # far: "in front" zone 2, "on the side" zone 3


@dataclass
class StandinPerson:
    """Where the scripted user stands (map metres): at home, in front of the robot's spot at the user's
    place, until the script has them walk up to the robot (wherever it is) or back home."""

    home: tuple
    limits: ZoneLimits = PEPPER_LIFE_LIMITS
    detection_range: float = DETECTION_RANGE

    def __post_init__(self):
        self.home = (float(self.home[0]) + IN_FRONT, float(self.home[1]))
        self.x, self.y = self.home

    def walk(self, where: str, robot: tuple) -> None:
        """``"to_robot"``: stand half a metre in front of the robot at ``robot``; ``"home"``: go back."""
        if where == "to_robot":
            self.x, self.y = float(robot[0]) + IN_FRONT, float(robot[1])
        elif where == "home":
            self.x, self.y = self.home
        else:
            raise ValueError(f"a person walks 'to_robot' or 'home', not {where!r}")

    def zone(self, robot: tuple, present: bool) -> int | None:
        """The person's engagement zone seen from ``robot`` (None: absent, or beyond the detection range)."""
        dx, dy = self.x - float(robot[0]), self.y - float(robot[1])
        if not present or math.hypot(dx, dy) > self.detection_range:
            return None
        return engagement_zone(dx, dy, self.limits)

    def memory(self, robot: tuple, present: bool) -> dict:
        """The ALMemory keys of the people around the robot: the zones' lists and the people list."""
        z = self.zone(robot, present)
        out = {key: [PERSON_ID] if z == k else [] for k, key in enumerate(ZONE_KEYS, start=1)}
        out[PEOPLE_KEY] = [PERSON_ID] if z is not None else []
        return out
