"""A small deterministic rover on a straight track, as a world of homeo-robot (``homeo-launch rover``).

The rover knows only its own names: places on its track (metres from one end), two body quantities
(``discharge`` of its battery, ``wear`` of its motors) and its devices. ``rover.json`` (the ``config``
parameter) says what the scenario's names mean on it: which place is which location, which body drive
each quantity is read as, which device command an action sends, and the routine of its person. What an
action does comes from the scenario (``sc``): its ``requires``, ``set`` and ``drives`` effects, the
objects' ``on_leave`` and the ``ongoing`` effects. Nothing is random: one config, one run.
"""

import json
import math
from importlib import resources
from pathlib import Path

from homeo_decision.codec import body_vector
from homeo_decision.environment import Outcome
from homeo_decision.world_api import WorldBackend, WorldConfigError
from homeo_msgs_py.params import ParamSpec


def load_config(sc, path):
    """``rover.json`` (or the file at ``path``), checked against the scenario: WorldConfigError, one line."""
    try:
        cfg = json.loads(Path(path).read_text() if path else resources.files(__package__).joinpath("rover.json").read_text())
        places, user = cfg["places"], cfg["user"]
        wrong = [p["location"] for p in places.values() if p["location"] not in sc.locations]
        wrong += sorted(set(sc.locations) - {p["location"] for p in places.values()})  # every location reachable
        body = {d.name for d in sc.drives if d.source == "body"}  # the drives a world reads (the others: the robot's own)
        wrong += [b["drive"] for b in cfg["body"].values() if b["drive"] not in body]
        wrong += [a for a in cfg["devices"] if a not in sc.action_names]
        wrong += [i for i, ticks in user["routine"] if i not in sc.intention_names or ticks < 1]
        wrong += [i for i in cfg["cues"]["hears"] if i not in sc.intention_names]
        wrong += [p for p in (cfg["start"], user["place"]) if p not in places]
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise WorldConfigError(f"rover config {path or 'rover.json'}: {type(e).__name__}: {e}") from None
    if wrong:
        raise WorldConfigError(f"rover config {path or 'rover.json'}: not the scenario's: {', '.join(map(str, wrong))}")
    return cfg


def holds(cond, view):
    """A scenario condition ``{variable: [values]}``, where ``"!x"`` is anything but x."""
    return all(any(view.get(k) == x or (x[0] == "!" and view.get(k) != x[1:]) for x in xs) for k, xs in cond.items())


class Rover:
    """The rover and its person, in the scenario's indices: an ``environment.Environment``."""

    STATE = ("x", "body", "objects", "turn", "waited", "tick", "count")

    def __init__(self, sc, cfg, speed, observation):
        self.sc, self.cfg, self.speed, self.make = sc, cfg, speed, observation
        self.at = {p["location"]: name for name, p in cfg["places"].items()}  # location -> place
        self.routine = cfg["user"]["routine"]
        self.reset()

    def reset(self, seed=None):  # nothing is random: the seed changes nothing
        self.x = self.cfg["places"][self.cfg["start"]]["x"]
        self.body = {q: 0.0 for q in self.cfg["body"]}
        self.objects = {o: {v: vals[0] for v, vals in s["variables"].items()} for o, s in self.sc.objects.items()}
        self.turn = self.waited = self.tick = 0
        self.count, self.sent = {"praised": 0, "scolded": 0, "metres": 0.0}, []
        return self.observe()

    def place(self):  # the rover is at the place nearest to it on its track
        return min(self.cfg["places"], key=lambda p: abs(self.cfg["places"][p]["x"] - self.x))

    def location(self):
        return self.cfg["places"][self.place()]["location"]

    def relation(self):  # the person stays at their place
        return "near" if self.place() == self.cfg["user"]["place"] else "far"

    def view(self, intention="none"):  # every variable of the world as the scenario names it
        v = {"robot.location": self.location(), "human.relation": self.relation(), "intention": intention}
        v.update({f"{o}.{k}": val for o, vs in self.objects.items() for k, val in vs.items()})
        return self.sc.view(self.sc.encode(v))

    def wish(self):
        """The person's wish this tick: the routine's when it is reasonable now, else none."""
        name = self.routine[self.turn % len(self.routine)][0]
        spec = next((i for i in self.sc.intentions if i.name == name), None)
        return name if spec and holds(spec.reasonable, self.view()) else "none"

    def change(self, drives):  # the scenario's drive effects, felt by the rover's body (0..100)
        for q, b in self.cfg["body"].items():
            self.body[q] = min(100.0, max(0.0, self.body[q] + drives.get(b["drive"], 0.0)))

    def readings(self):  # the body drives' readings
        return {b["drive"]: self.body[q] for q, b in self.cfg["body"].items()}

    def observe(self):
        wish, cues = self.wish(), self.cfg["cues"]
        heard = {"keyword": cues["hears"][wish]} if wish in cues["hears"] else {}
        return self.make(self.location(), self.relation(), objects=self.objects, body=self.readings(),
                         intention=wish, cues=dict(cues["silence"], **heard))

    def drive_to(self, place):  # at most `speed` metres a tick, through the places on the way
        goal, left = self.cfg["places"][place]["x"], self.location()
        metres = min(self.speed, abs(goal - self.x))
        self.x = goal if metres == abs(goal - self.x) else self.x + math.copysign(metres, goal - self.x)
        self.count["metres"] += metres
        self.change({b["drive"]: b["per_metre"] * metres for b in self.cfg["body"].values()})
        for o, s in self.sc.objects.items():  # leaving an object's place: its on_leave values
            if s["location"] == left != self.location():
                self.objects[o].update(s.get("on_leave", {}))

    def step(self, action):
        sc, wish, failure, done = self.sc, self.wish(), None, None
        if action is not None:
            spec, view = sc.actions[action], self.view(wish)
            if not holds(spec.requires, view):
                failure = f"{spec.name}: not possible here"
            else:
                done = action
                for effect in (e for e in spec.effects if holds(e.get("when", {}), view)):
                    for var, value in effect.get("set", {}).items():
                        if var == "robot.location":
                            self.drive_to(self.at[value])
                        else:
                            obj, key = var.split(".", 1)
                            self.objects[obj][key] = value
                    self.change(effect.get("drives", {}))
                if spec.name in self.cfg["devices"]:
                    self.sent.append(dict(self.cfg["devices"][spec.name], action=spec.name, tick=self.tick))
        self.change({b["drive"]: b["per_tick"] for b in self.cfg["body"].values()})  # time passes
        for ongoing in (o for o in sc.ongoing if holds(o["when"], self.view())):
            self.change(ongoing.get("drives", {}))
        feedback, proposal, clarified, w = 0, None, None, sc.intention_names.index(wish)
        if done is not None and wish != "none":  # the person answers what the rover did
            desired = next(i for i in sc.intentions if i.name == wish).desired
            feedback, clarified = (1 if sc.actions[done].name in desired else -1), w
            proposal = None if feedback == 1 else sc.action_index(desired[0])
            self.count["praised" if feedback == 1 else "scolded"] += 1
        self.tick, self.waited = self.tick + 1, self.waited + 1
        if feedback == 1 or self.waited >= self.routine[self.turn % len(self.routine)][1]:
            self.turn, self.waited = self.turn + 1, 0
        return Outcome(done, feedback, proposal, clarified, body=body_vector(sc, self.readings()),
                       true_intention=w, satisfied=feedback == 1, failure=failure)


class RoverWorld(WorldBackend):
    """The rover as a world: ``self.env`` does the ticks; ``state()`` holds all of it (KEEPS_STATE)."""

    NAME = "rover"
    PARAMS = (ParamSpec("config", "", "the rover's meaning of the scenario's names ('' = homeo_rover/rover.json)",
                        fixed=True),
              ParamSpec("speed", 4.0, "metres the rover drives in a tick (a place further away takes more ticks)",
                        lo=0.1, hi=100.0))
    KEEPS_STATE = True

    def __init__(self, sc, values):
        super().__init__(sc, values)
        self.env = Rover(sc, load_config(sc, values["config"]), values["speed"], self.observation)

    @classmethod
    def check(cls, sc, values):
        load_config(sc, values.get("config") or "")

    def set_param(self, name, value):  # checked by its ParamSpec already; config never gets here (fixed)
        if name == "speed":
            self.env.speed = value  # the next metres driven

    def devices(self):
        sent, self.env.sent = self.env.sent, []
        return sent

    def status(self, done):
        return {"metrics": {k: round(v, 3) for k, v in self.env.count.items()}}

    @classmethod
    def result(cls, sc, status, setting):
        return dict(super().result(sc, status, setting), **status.get("metrics", {}))

    @classmethod
    def result_text(cls, sc, result, setting):
        mine = "\nrover: praised {praised}, scolded {scolded}, drove {metres:.1f} m"
        return super().result_text(sc, result, setting) + mine.format(**{"praised": 0, "scolded": 0, "metres": 0, **result})

    def state(self):
        return None, json.loads(json.dumps({k: getattr(self.env, k) for k in Rover.STATE}))

    def set_state(self, rng, state, tick):
        if not isinstance(state, dict) or sorted(state) != sorted(Rover.STATE) \
                or not isinstance(state["x"], (int, float)) or state["tick"] != tick:
            raise ValueError(f"rover state: not one of this rover's at tick {tick}")
        for k in Rover.STATE:
            setattr(self.env, k, json.loads(json.dumps(state[k])))
