"""Open, use and close a stand-in Pepper and a bridge over libqi, again and again, in one process:
what the in-process qi tests do one after another.

    .venv/bin/python -X faulthandler tools/qi_stress.py [CYCLES] [--no-collect]

Each cycle connects a bridge to a fresh stand-in, takes a step whose move the robot refuses, closes
both, then opens a second pair and reads the body. It prints ``survived N cycles`` and leaves with
``os._exit(0)``, because interpreter teardown with libqi threads alive is a separate matter.
``--no-collect`` turns ``pepper_bridge.naoqi_link.collect_closed_session`` into a no-op. That is how
the code behaved before: with qi 3.1.5 the process died with a segfault inside ``registerService``
(docs/PEPPER.md); ``-X faulthandler`` shows where.
"""

from __future__ import annotations

import copy
import os
import sys


def main(argv: list[str]) -> int:
    from homeo_msgs_py.cli_args import run_command

    return run_command("qi_stress", lambda: stress(argv))


def parse_args(argv: list[str]):
    """``cycles`` (1..1,000,000, default 150) and ``no_collect``; a bad argument is a one-line UserError."""
    from homeo_msgs_py.cli_args import Parser, int_at_least

    ap = Parser(prog="qi_stress", description="open, use and close a stand-in and a bridge CYCLES times")
    ap.add_argument("cycles", nargs="?", type=int_at_least(1, 1_000_000), default=150, help="default 150")
    ap.add_argument("--no-collect", action="store_true", help="as the code was: no collection at a session's close")
    return ap.parse_args(argv)


def stress(argv: list[str]) -> int:
    a = parse_args(argv)
    cycles = a.cycles
    if a.no_collect:  # the stand-in calls it through this module too
        from pepper_bridge import naoqi_link

        naoqi_link.collect_closed_session = lambda: None
    import qi

    from homeo_decision.scenario import load_scenario
    from pepper_bridge.bridge import PepperBridge
    from pepper_bridge.config import LinkSettings, load_config
    from pepper_bridge.environment import NotReady, PepperEnvironment
    from pepper_bridge.mapping import BATTERY_KEY
    from pepper_bridge.standin import StandinRobot

    qi.logging.setLevel(qi.logging.WARNING)
    sc, cfg = load_scenario(), load_config()
    user = {"schema": "homeo-pepper-user", "version": 1,
            "start": {"battery_percent": 40, "location": "R", "presence": "present"},
            "interactions": [{"intention": "light", "gesture": "point_up", "words": ["light"]}]}

    def pair():
        robot = StandinRobot(cfg, copy.deepcopy(user), time_scale=0.0, scenario=sc)
        bridge = PepperBridge(cfg, LinkSettings(url=robot.start()), sc)
        assert bridge.start(10.0), bridge.status()
        return robot, bridge, PepperEnvironment(bridge, quiet=0.15, window=2.0)

    for i in range(cycles):
        if i % 25 == 0:
            print(f"cycle {i}", file=sys.stderr, flush=True)
        robot, bridge, env = pair()
        env.reset()
        robot._motion = lambda x, y: False  # the robot refuses the move
        assert env.step(sc.action_index("MoveToH")).action is None
        bridge.stop()
        robot.close()
        robot, bridge, env = pair()
        robot.inject(BATTERY_KEY, "abc")  # wrongly typed: no good value yet
        try:
            env.observe()
        except NotReady:
            pass
        robot.clear_injections()
        env.observe()
        bridge.stop()
        robot.close()
    print(f"survived {cycles} cycles", flush=True)
    os._exit(0)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
