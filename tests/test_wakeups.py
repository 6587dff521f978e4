"""The world node's poll timer (issue 24): every 20 ms while something needs it (the start gate, a world
whose calls block, a rate to keep, a retry, a short timeout), every 100 ms while a run only needs its
timeouts and status from it; the action wakes the node, not the timer."""

from __future__ import annotations

import types

import pytest

from homeo_msgs_py.lockstep import FINISHING, RUNNING, WAITING

world_node = pytest.importorskip("homeo_decision.world_node")  # imports rclpy


def drv(**kw):
    base = dict(state=RUNNING, rate=0.0, phase="act", timeout=5.0)
    return types.SimpleNamespace(**dict(base, **kw))


@pytest.mark.parametrize("kw, blocking, want", [
    ({}, False, world_node.IDLE_POLL_S),
    ({"phase": "step"}, False, world_node.IDLE_POLL_S),
    ({}, True, world_node.POLL_S),  # a robot or a person: the worker's result is polled
    ({"rate": 5.0}, False, world_node.POLL_S),  # the rate is kept by the timer
    ({"phase": "retry"}, False, world_node.POLL_S),
    ({"timeout": 0.5}, False, world_node.POLL_S),  # a short timeout is checked finely
    ({"state": WAITING}, False, world_node.POLL_S),  # the start gate
    ({"state": FINISHING}, False, world_node.POLL_S),
])
def test_the_poll_slows_down_only_when_a_run_needs_it_for_its_timeouts_alone(kw, blocking, want):
    assert world_node.poll_period(drv(**kw), blocking) == want
