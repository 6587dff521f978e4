"""The stand-in's person against the NAOqi documentation of ALEngagementZones and ALPeoplePerception.

No qi session: ``standin_person`` is pure. Every documented value comes with its page; property-based
tests check the zones for any point and limits, and that a person who walks up to the robot is in
zone 1 (and reads as near) wherever the robot stands.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pepper_bridge.mapping import PEOPLE_KEY, ZONE_KEYS, relation_from_zones
from pepper_bridge.standin_person import (DEFAULT_LIMITS, DETECTION_RANGE, IN_FRONT, PEPPER_LIFE_LIMITS, PERSON_ID,
                                          StandinPerson, ZoneLimits, engagement_zone)
from pepper_bridge.user import ScriptError, validate_script

ZONES_PAGE = "http://doc.aldebaran.com/2-8/naoqi/peopleperception/alengagementzones.html"
LIFE_PAGE = "http://doc.aldebaran.com/2-8/ref/life/extractors_management.html"


def test_the_documented_limits():
    # ZONES_PAGE, "Default values": FirstDistance = 1.5m, SecondDistance = 2.5m, LimitAngle = 90 degrees
    assert DEFAULT_LIMITS == ZoneLimits(1.5, 2.5, 90.0)
    # LIFE_PAGE, Pepper: setFirstLimitDistance 0.8, setSecondLimitDistance 0.9, setLimitAngle 90
    assert PEPPER_LIFE_LIMITS == ZoneLimits(0.8, 0.9, 90.0)
    # http://doc.aldebaran.com/2-5/naoqi/peopleperception/alpeopleperception-api.html: "3.5 meters"
    assert DETECTION_RANGE == 3.5


@pytest.mark.parametrize("limits", [DEFAULT_LIMITS, PEPPER_LIFE_LIMITS])
@pytest.mark.parametrize("dx, dy, zone", [
    (0.5, 0.0, 1),    # ZONES_PAGE: "Zone1 is near, in front"
    (-0.5, 0.0, 2),   # "Zone2 is ... also near but on the sides" (behind: no reading of LimitAngle calls it in front)
    (0.0, -0.5, 2),   # near, on the right side
    (4.0, 0.0, 3),    # "Zone3 is ... 'very far' i.e. beyond SecondDistance"
    (-4.0, 1.0, 3),
])
def test_zones_by_hand(limits, dx, dy, zone):
    assert engagement_zone(dx, dy, limits) == zone


@pytest.mark.parametrize("dx, dy", [(math.nan, 0.0), (0.0, math.inf), (-math.inf, 1.0)])
def test_a_point_that_is_not_finite_has_no_zone(dx, dy):
    with pytest.raises(ValueError, match="finite"):
        engagement_zone(dx, dy)


def test_between_the_distances():
    # DEFAULT_LIMITS: 2 m straight ahead is "far in front" (zone 2), 2 m behind "far on the side" (zone 3)
    assert engagement_zone(2.0, 0.0, DEFAULT_LIMITS) == 2
    assert engagement_zone(-2.0, 0.0, DEFAULT_LIMITS) == 3


@pytest.mark.parametrize("args", [(0.9, 0.8, 90.0), (0.0, 1.0, 90.0), (-1.0, 1.0, 90.0), (0.8, math.inf, 90.0),
                                  (0.8, math.nan, 90.0), (0.8, 0.9, 0.0), (0.8, 0.9, 361.0)])
def test_limits_outside_the_documented_ranges_are_refused(args):
    # setFirstLimitDistance: "It must be positive and smaller than the current value of SecondDistance"
    with pytest.raises(ValueError, match="engagement zone limits"):
        ZoneLimits(*args)


finite = st.floats(min_value=-50.0, max_value=50.0, allow_nan=False)
limits_st = st.builds(lambda a, b, ang: ZoneLimits(a, a + b, ang), st.floats(0.05, 5.0), st.floats(0.01, 5.0),
                      st.floats(1.0, 360.0))


@settings(max_examples=300, deadline=None)
@given(finite, finite, limits_st)
def test_every_point_has_the_zone_its_distance_and_side_give(dx, dy, limits):
    z = engagement_zone(dx, dy, limits)
    d = math.hypot(dx, dy)
    assert z in (1, 2, 3)
    if z == 1:
        assert d < limits.first  # zone 1 is near
    if d > limits.second:
        assert z == 3  # beyond SecondDistance: very far
    if dy == 0.0 and dx >= 0.0:  # straight ahead: in front under any LimitAngle
        assert z == (1 if d < limits.first else 2 if d <= limits.second else 3)


@settings(max_examples=300, deadline=None)
@given(finite, finite, finite, finite, st.sampled_from([DEFAULT_LIMITS, PEPPER_LIFE_LIMITS]))
def test_a_person_who_walks_up_is_in_zone_1_wherever_the_robot_stands(hx, hy, rx, ry, limits):
    p = StandinPerson((hx, hy), limits)
    p.walk("to_robot", (rx, ry))
    m = p.memory((rx, ry), present=True)
    # ZONES_PAGE: PeopleInZone1..3 "store the list of the IDs of the people in each zone"
    assert m == {ZONE_KEYS[0]: [PERSON_ID], ZONE_KEYS[1]: [], ZONE_KEYS[2]: [], PEOPLE_KEY: [PERSON_ID]}
    assert relation_from_zones(*(m[k] for k in (*ZONE_KEYS, PEOPLE_KEY))) == "near"
    assert p.memory((rx, ry), present=False) == {ZONE_KEYS[0]: [], ZONE_KEYS[1]: [], ZONE_KEYS[2]: [], PEOPLE_KEY: []}


@settings(max_examples=300, deadline=None)
@given(finite, finite, finite, finite, st.booleans())
def test_the_person_is_in_at_most_one_zone_and_listed_iff_in_one(px, py, rx, ry, present):
    p = StandinPerson((0.0, 0.0))
    p.x, p.y = px, py
    m = p.memory((rx, ry), present)
    in_zones = [k for k in ZONE_KEYS if m[k]]
    assert len(in_zones) <= 1
    assert (m[PEOPLE_KEY] == [PERSON_ID]) == bool(in_zones)
    seen = present and math.hypot(px - rx, py - ry) <= DETECTION_RANGE
    assert bool(in_zones) == seen


def test_at_home_the_person_stands_in_front_of_the_robots_spot_at_the_users_place():
    p = StandinPerson((0.0, 0.0))  # the shipped config's H
    assert (p.x, p.y) == (IN_FRONT, 0.0)
    assert p.zone((0.0, 0.0), True) == 1  # the robot at H: near, as the simulation reads it
    assert p.zone((3.0, 0.0), True) == 3  # at C: 2.5 m behind it
    assert p.zone((0.0, 3.0), True) == 3  # at R: 3.04 m, beyond SecondDistance, within the detection range
    p.walk("to_robot", (0.0, 3.0))
    assert p.zone((0.0, 3.0), True) == 1
    assert p.zone((3.0, 0.0), True) is None  # left behind 3.9 m away: beyond the detection range
    p.walk("home", (3.0, 0.0))
    assert (p.x, p.y) == (IN_FRONT, 0.0)
    with pytest.raises(ValueError, match="to_robot"):
        p.walk("nowhere", (0.0, 0.0))


SCRIPT = {"schema": "homeo-pepper-user", "version": 1}


@settings(max_examples=200, deadline=None)
@given(st.one_of(st.none(), st.booleans(), st.integers(), st.text(max_size=12), st.lists(st.integers(), max_size=2),
                 st.dictionaries(st.text(max_size=3), st.integers(), max_size=2)))
def test_a_script_walks_the_person_only_to_the_robot_or_home(value):
    for raw in (dict(SCRIPT, interactions=[{"walks": value}]), dict(SCRIPT, timed=[{"at": 1.0, "walks": value}])):
        if value in ("to_robot", "home"):
            validate_script(raw)
        else:
            with pytest.raises(ScriptError, match="walks must be 'to_robot' or 'home'"):
                validate_script(raw)
