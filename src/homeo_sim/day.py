"""A scripted day: the simulated home with a person whose day is written down (no rclpy).

The third world of the graph, next to the simulation (``world_backend.SimWorld``) and the Pepper
(``pepper_bridge.world_backend.PepperWorld``): it needs no node and no launcher code of its own,
only this module and its entry in the ``homeo_robot.worlds`` registry. The world and the body
are the thesis's simulation; the human follows a JSON script of its day instead of Algorithm 2's
draws: a list of moments, each so many ticks long, with the person at home or out and one wish
(an intention of the scenario, or "none"). A wish is held until the robot satisfies it or its
moment ends, and answered as Algorithm 2 answers (lines 8-19: praise for a desired action, else
a scolding with a proposal, always the first desired action). What the robot sees of the person
(gesture, movement, keyword) is drawn from the scenario's habits, as for the simulated human.

    {"schema": "homeo-day", "version": 1, "description": "...", "repeat": false,
     "moments": [{"ticks": 30, "wish": "music"}, {"ticks": 20, "wish": "none", "present": false}, ...]}

With ``repeat`` the day starts over after its last moment; without, the world is finished then
(the run ends with the day).
"""

from __future__ import annotations

from pathlib import Path

from homeo_decision.scenario import NONE_INTENTION, Scenario
from homeo_decision.world_api import WorldConfigError
from homeo_msgs_py.params import ParamSpec, checked

from .human import SimHuman
from .world_backend import SimWorld

SCHEMA, VERSION = "homeo-day", 1
DAYS_DIR = Path(__file__).resolve().parent / "days"
MAX_TICKS = 10**6  # of one moment
MAX_MOMENTS = 10_000
MAX_BYTES = 1 << 20


class DayScriptError(WorldConfigError):
    """A day script that cannot be used: one line."""


def load_day(path: str | None, sc: Scenario) -> dict:
    """The checked day script at ``path`` ('' or None: the shipped ``days/example.json``; a bare name:
    a shipped day). Raises DayScriptError (one line)."""
    from homeo_decision.jsonfile import read, shipped

    p = shipped(path or "example", DAYS_DIR)
    raw = read(p, DayScriptError, "day script", limit=MAX_BYTES)
    return check_day(raw, sc, str(p))


def check_day(raw, sc: Scenario, where: str = "<memory>") -> dict:
    if not isinstance(raw, dict) or raw.get("schema") != SCHEMA or raw.get("version") != VERSION:
        raise DayScriptError(f"{where}: not a day script (schema {SCHEMA!r}, version {VERSION})")
    unknown = set(raw) - {"schema", "version", "description", "repeat", "moments"}
    if unknown:
        raise DayScriptError(f"{where}: unknown key {sorted(unknown)[0]!r}")
    if type(raw.get("repeat", False)) is not bool:
        raise DayScriptError(f"{where}: repeat must be true or false")
    moments = raw.get("moments")
    if not isinstance(moments, list) or not 1 <= len(moments) <= MAX_MOMENTS:
        raise DayScriptError(f"{where}: moments must be a list of 1..{MAX_MOMENTS} moments")
    names = sc.intention_names
    out = []
    for i, m in enumerate(moments):
        ctx = f"{where}: moments[{i}]"
        if not isinstance(m, dict) or set(m) - {"ticks", "wish", "present"}:
            raise DayScriptError(f"{ctx} must be an object of ticks, wish and present")
        ticks, wish, present = m.get("ticks"), m.get("wish", NONE_INTENTION), m.get("present", True)
        checked(ticks, f"{ctx}: ticks", 1, MAX_TICKS, int, DayScriptError)
        if not isinstance(wish, str) or wish not in names:
            raise DayScriptError(f"{ctx}: wish {str(wish)[:40]!r} is not one of {', '.join(names)}")
        if type(present) is not bool:
            raise DayScriptError(f"{ctx}: present must be true or false")
        if not present and wish != NONE_INTENTION:
            raise DayScriptError(f"{ctx}: a person who is out wishes nothing")
        out.append((ticks, names.index(wish), present))
    return {"repeat": raw.get("repeat", False), "moments": tuple(out)}


class DayHuman(SimHuman):
    """Algorithm 2's answers, with the wishes and the presence of a written day."""

    def __init__(self, sc: Scenario, day: dict, seed: int = 0):
        self.day = day
        super().__init__(sc, seed)

    def reset(self, seed: int | None = None) -> None:
        super().reset(seed)
        self.t = -1  # the tick whose wish was last decided (advance comes first, before tick 0)
        self.done = False

    def moment(self, t: int) -> tuple | None:
        """The moment of tick ``t`` and its first tick; None after the day (no repeat)."""
        moments = self.day["moments"]
        length = sum(m[0] for m in moments)
        if t >= length and not self.day["repeat"]:
            return None
        t %= length
        start = 0
        for m in moments:
            if t < start + m[0]:
                return m, start
            start += m[0]
        raise AssertionError("unreachable")

    def advance(self, code: int) -> None:
        self.t += 1
        now = self.moment(self.t)
        if now is None:  # the day is over: the person is home and wishes nothing
            self.done, self.present, self.intention = True, True, 0
            return
        (_, wish, present), start = now
        self.present = present
        length = sum(m[0] for m in self.day["moments"])
        if self.t % length == start:  # a new moment: its wish
            self.intention, self.satisfied = wish, False
        elif self.satisfied:  # granted: nothing more until the next moment
            self.intention, self.satisfied = 0, False

    def proposal(self, it: int) -> int:
        """A written person always says what it meant: the first desired action."""
        return self.desired_order[it][0]

    def state(self) -> dict:
        return dict(super().state(), t=self.t, done=self.done)

    def set_state(self, st) -> None:
        t, done = st.get("t") if isinstance(st, dict) else None, st.get("done") if isinstance(st, dict) else None
        if type(t) is not int or t < -1 or type(done) is not bool:
            raise ValueError("a day's human needs t (an integer >= -1) and done (true or false)")
        super().set_state(st)
        self.t, self.done = t, done


class DayWorld(SimWorld):
    """The simulated home through a scripted day (homeo_sim/days); its result: the day's metrics."""

    NAME = "day"
    PARAMS = (ParamSpec("day", "", "the day script: a file, or the name of a shipped day ('' = days/example.json)",
                        fixed=True),)

    @classmethod
    def check(cls, sc: Scenario, values: dict) -> None:
        load_day(values.get("day"), sc)

    def __init__(self, sc: Scenario, values: dict):
        self.human = DayHuman(sc, load_day(values.get("day"), sc), values.get("seed", 0))
        super().__init__(sc, values, human=self.human)

    def finished(self) -> bool:
        return self.human.done

    def run_config(self) -> dict:
        return dict(super().run_config(), human="day", day=repr(self.human.day))
