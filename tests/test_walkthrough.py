"""The README's "play the human" walkthrough, step by step, with the real ``ros2`` command line.

Terminal 1 is ``homeo-launch sim --human person ...`` as the README gives it (two ticks instead of
twenty); terminal 2 is the person, with the ``ros2`` commands the README shows beside each
``homeo-topic`` one: a wish, a look at what the robot is doing (``homeo/last_action`` is latched:
an echo started whenever the person looks gets it), an answer, the next wish, praise, and at the end
``homeo-replay`` of the recording.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest
import yaml

import ros2cli
from rosgraph import fresh_domain

pytestmark = [pytest.mark.ros, pytest.mark.slow]


def _ros2(args: list[str], env: dict, timeout: float = 60.0) -> subprocess.CompletedProcess:
    return subprocess.run([str(ros2cli.BIN / "ros2"), *args], env=env, capture_output=True, text=True, timeout=timeout)


def _say(text: str, env: dict) -> None:
    """``ros2 topic pub --once -w 2 --keep-alive 3 /homeo/human_input std_msgs/msg/String "{data: '...'}"``.
    ``--once`` alone publishes as soon as one reader matched: with ``--record`` the wish has two (the
    world node and the recorder), and the one that matched later never got it (the topic is volatile):
    the CI lost a scold and a praise that way. ``-w 2`` waits for both (``ros2 topic info`` counts them,
    checked below). ``--keep-alive 3``: the robot may not yet have matched the publisher when the
    publisher matched it (discovery runs both ways); with the default 0.1 s the publisher is gone before
    the message is delivered again."""
    r = _ros2(["topic", "pub", "--once", "-w", "2", "--keep-alive", "3", "/homeo/human_input", "std_msgs/msg/String",
               yaml.safe_dump({"data": text})], env)
    assert r.returncode == 0, r.stderr


def _look(topic: str, env: dict, must: bool = True) -> dict | None:
    """``ros2 topic echo --once --full-length --qos-durability transient_local --qos-reliability reliable
    TOPIC`` (a latched topic): the message's JSON (None: not published yet). Without the QoS options
    echo takes the publishers' QoS only if it has discovered them when it starts, and else subscribes
    volatile and never gets the latched message (ros2topic's ``choose_qos``): slow discovery on a busy
    machine made that a 60 s wait. ``--no-lost-messages``: echo otherwise prints "A message was lost!!!"
    and its counts to stdout, ahead of the message (ros2topic's ``_message_lost_event_callback``), when
    DDS reports one lost while it joins a topic that is being published."""
    r = _ros2(["topic", "echo", "--once", "--full-length", "--no-lost-messages", "--qos-durability",
               "transient_local", "--qos-reliability", "reliable", topic], env)
    if r.returncode != 0 and not must:
        return None
    assert r.returncode == 0, r.stderr
    return json.loads(yaml.safe_load(r.stdout.split("---")[0])["data"])


def _wait_for_the_person(env: dict, proc, bound: float = 90.0) -> None:
    """Until the run waits for the person's first wish (its status: starting)."""
    end = time.monotonic() + bound
    while time.monotonic() < end:
        assert proc.poll() is None, proc.communicate()[1][-3000:]
        status = _look("/homeo/run_status", env, must=False)
        if status is not None and status["state"] == "starting":
            return
        time.sleep(0.5)
    raise AssertionError("the graph never waited for the person")


def _look_at_tick(tick: int, env: dict, bound: float = 60.0) -> dict:
    """``_look`` at ``/homeo/last_action`` again until it holds ``tick``'s action (an earlier one is latched
    until the robot acts): a person who looks late still sees it."""
    end = time.monotonic() + bound
    while True:
        seen = _look("/homeo/last_action", env, must=False)  # None: echo has not yet discovered the topic
        if (seen is not None and seen["tick"] >= tick) or time.monotonic() > end:
            assert seen is not None and seen["tick"] == tick, seen
            return seen


def _wait_for_readers(topic: str, count: int, env: dict, bound: float = 60.0) -> None:
    """Until ``ros2 topic info TOPIC`` counts ``count`` subscriptions. Discovery is eventual: the CI once
    read 1 (the daemon had not yet seen the recorder) at the moment the run said it waited for the
    person, so a single look can undercount; the README's ``-w 2`` waits the same way."""
    end = time.monotonic() + bound
    seen = ""
    while time.monotonic() < end:
        seen = _ros2(["topic", "info", topic], env).stdout
        if f"Subscription count: {count}" in seen:
            return
        time.sleep(0.5)
    raise AssertionError(f"{topic} never had {count} readers: {seen}")


def test_the_play_the_human_walkthrough_with_the_ros2_command_line(tmp_path):
    ros2cli.require_tools()
    from homeo_launch.processes import graph_env

    env = ros2cli.env_with_venv(graph_env(fresh_domain()))
    # terminal 1 (README): the robot, with you as the human
    robot = subprocess.Popen([sys.executable, "-m", "homeo_launch.cli", "sim", "--human", "person", "--intention",
                              "oracle", "--iterations", "2", "--human-timeout", "30", "--record", "runs/me", "--quiet"],
                             cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             start_new_session=True)
    try:
        _wait_for_the_person(env, robot)
        _wait_for_readers("/homeo/human_input", 2, env)  # the README's -w 2
        # terminal 2: you. A wish starts the tick; after the robot acts, answer it.
        _say('{"intention": "music"}', env)
        first = _look_at_tick(0, env)
        assert first["intention"] == "music" and "action" in first, first
        wrong = first["action"] != "Play"
        _say('{"feedback": "scold", "proposal": "Play"}' if wrong else '{"feedback": "praise"}', env)
        _say('{"intention": "music"}', env)  # next tick, same wish
        second = _look_at_tick(1, env)  # the latched tick 0 until the robot has acted again
        assert second["tick"] == 1 and second["intention"] == "music", second
        _say('{"feedback": "praise"}', env)
        out, err = robot.communicate(timeout=120)
    finally:
        if robot.poll() is None:
            os.killpg(robot.pid, signal.SIGINT)
            robot.communicate(timeout=30)
        ros2cli.stop_daemon(env)
    assert robot.returncode == 0 and "2 iterations x 1 seed" in out, err[-3000:]
    # afterwards: what happened, from the recording
    r = subprocess.run([sys.executable, "-m", "homeo_record.replay", "runs/me", "--log"], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "2 ticks, 2 with a wish" in r.stdout and "1 praised" in r.stdout, r.stdout
    assert ("1 scolded" in r.stdout) == wrong, r.stdout
