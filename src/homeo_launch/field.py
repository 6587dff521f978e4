"""The field test of Section 4.3 without ROS: the decision core on a (stand-in) Pepper.

A Q-table learned in simulation is loaded; the robot starts nearly depleted; a dedicated
robot (DoD 0.25) and a selfish one (DoD 0) meet the same scripted user (Tables 4.7, 4.8).

:class:`Interaction` is the per-interaction logic the ROS node reuses: given the world dict
and the recognised intention it perceives, learns the previous transition, and selects;
given the outcome it moves the internal drives. :class:`IntentionCues` stands in for the
Bayesian intention recogniser (keywords and gestures looked up in the config). ``run_field``
wires both to a :class:`~pepper_bridge.bridge.PepperBridge` and an in-process stand-in.

CLI (``homeo-pepper-field``)::

    homeo-pepper-field --script field_user.json --seeds 0 1 2 [--q-dedicated F --q-selfish F | --same-q F] [--json]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from homeo_decision import qtable_io
from homeo_decision.agent import DecisionCore, Percept
from homeo_decision.drives import DriveModel
from homeo_decision.scenario import NONE_INTENTION, Scenario, load_scenario

from .bridge import PepperBridge
from .config import LinkSettings, PepperConfig, load_config
from .events import FEEDBACK, PROPOSAL, STATUS
from .naoqi_link import RobotUnavailable
from .user import load_script

DODS = (("dedicated", 0.25), ("selfish", 0.0))
TRAIN_ITERATIONS = 5000


class IntentionCues:
    """Keyword / gesture -> intention, from the config's ``intention_cues`` (keyword first)."""

    def __init__(self, cues: dict, intentions):
        self.kw = dict(cues.get("keywords", {}))
        self.gest = dict(cues.get("gestures", {}))
        known = set(intentions)
        for name in list(self.kw.values()) + list(self.gest.values()):
            if name not in known:
                raise ValueError(f"intention cue names unknown intention {name!r}")

    def __call__(self, obs: dict) -> str | None:
        if obs.get("keyword") in self.kw:
            return self.kw[obs["keyword"]]
        if obs.get("gesture") in self.gest:
            return self.gest[obs["gesture"]]
        return None


def world_code(sc: Scenario, world: dict, intention: str | None) -> int:
    """The scenario's world code of a bridge ``world`` dict and a recognised intention."""
    values = {"robot.location": world["robot"]["location"], "human.presence": world["human"]["presence"],
              "intention": intention or NONE_INTENTION}
    for obj, d in world["objects"].items():
        values[f"{obj}.status"] = d["status"]
    return sc.encode(values)


def body_drives(sc: Scenario, body: dict) -> list:
    """The body drives (indexed like all drives) from a bridge ``body`` dict."""
    return [float(body.get(d.name) or 0.0) if d.source == "body" else 0.0 for d in sc.drives]


@dataclass
class Interaction:
    """One robot in the field: drives + decision core, stepped once per interaction."""

    sc: Scenario
    robot: DecisionCore
    drives: DriveModel
    t0: int = TRAIN_ITERATIONS  # the schedule continues after the simulated training
    learn: bool = True
    k: int = 0
    pending: tuple | None = None  # (percept, action, feedback, proposal) awaiting s'
    last: Percept | None = None

    def decide(self, world: dict, intention: str | None) -> tuple[Percept, str]:
        """Perceive (body drives from the world dict), learn the previous step, select an action."""
        body = world["body"]
        prev = list(self.drives.values)
        bd = body_drives(self.sc, {d.name: (body.get(d.name) if body.get(d.name) is not None else prev[i])
                                   for i, d in enumerate(self.sc.drives)})
        self.drives.set_body(bd)
        code = world_code(self.sc, world, intention)
        p = self.robot.perceive(self.drives.values, code)
        if self.pending is not None and self.learn:
            pp, a, fb, prop = self.pending
            self.robot.learn(pp, a, p.drives, fb, prop, p, self.t0 + self.k - 1)
        self.pending = None
        a = self.robot.select(p, self.t0 + self.k)
        self.last = p
        return p, self.sc.actions[a].name

    def conclude(self, p: Percept, action: str, outcome: dict) -> None:
        """Internal drives after the action, the feedback and the time step; the transition waits for s'."""
        a = self.sc.action_index(action)
        expressed = self.sc.c.intention_of[p.code] != 0
        self.drives.apply_action(p.code, a)
        self.drives.apply_feedback(outcome["feedback"])
        self.drives.apply_time(expressed, outcome["feedback"] > 0)
        prop = outcome.get("proposal")
        self.pending = (p, a, outcome["feedback"], self.sc.action_index(prop) if prop else None)
        self.k += 1


def make_robot(sc: Scenario, dod: float, seed: int, q_table: str | Path | None, initial: dict | None) -> Interaction:
    core = DecisionCore(sc, seed, dod=dod)
    if q_table:
        qtable_io.load(core.q, q_table)
    drives = DriveModel(sc)
    init = dict(zip(sc.drive_names, (sc.open["initial_drives"][n] for n in sc.drive_names))) \
        if isinstance(sc.open["initial_drives"], dict) else dict(zip(sc.drive_names, sc.open["initial_drives"]))
    init.update(initial or {})
    drives.reset([float(init[n]) for n in sc.drive_names])
    return Interaction(sc, core, drives)


def train_q(path: str | Path, dod: float | None = None, seed: int = 0, iterations: int = TRAIN_ITERATIONS) -> Path:
    """The Q-table at the end of the default simulation (``homeo-sim run --seed 0 --save-q``)."""
    from homeo_sim.runner import RunConfig, run_episode

    run_episode(RunConfig(iterations=iterations, seed=seed, dod=dod, save_q=str(path)))
    return Path(path)


@dataclass
class FieldResult:
    label: str
    dod: float
    seed: int
    log: list = field(default_factory=list)  # one row per interaction
    user_log: list = field(default_factory=list)  # the scripted user's judgement (stand-in only)
    diagnostics: dict = field(default_factory=dict)

    def summary(self) -> dict:
        judged = [r for r in self.user_log if r["intention"] is not None]
        wanted = {}
        for r in judged:  # one intention of the script may take several attempts
            wanted[r["item"]] = wanted.get(r["item"], False) or bool(r["satisfied"])
        acts = [r["action"] for r in self.log]
        first = lambda names: next((r["interaction"] for r in self.log if r["action"] in names), None)  # noqa: E731
        return {"label": self.label, "dod": self.dod, "seed": self.seed, "interactions": len(self.log),
                "intentions": len(wanted), "satisfied": sum(wanted.values()),
                "hsr": (sum(r["satisfied"] for r in judged) / len(judged)) if judged else None,
                "first_attach": first(("Attach",)), "first_charger": first(("MoveToC", "Attach")),
                "survival_actions": sum(a in ("MoveToC", "Attach", "Stay") for a in acts)}


def run_interaction(bridge: PepperBridge, robot: Interaction, cues: IntentionCues, carry: list,
                    quiet: float, window: float) -> tuple[dict, list]:
    """One interaction: observe, decide, act, collect the answer. ``carry`` holds the events seen
    since the last action (the user's expression); returns the log row and the events that follow."""
    obs = bridge.observation(carry)
    intention = cues(obs)
    world = bridge.read_world()
    p, action = robot.decide(world, intention)
    done = bridge.execute(action)
    after = bridge.collect(quiet, window)
    answer = [e for e in after if e.kind in (FEEDBACK, PROPOSAL)]
    outcome = bridge.outcome(action, answer)
    robot.conclude(p, action, outcome)
    sc = robot.sc
    row = {"interaction": robot.k, "m_dom": sc.motivation_names[p.m_dom], "intention": intention, "action": action,
           "feedback": outcome["feedback"], "proposal": outcome["proposal"], "ok": done["ok"],
           "drives": dict(zip(sc.drive_names, [round(x, 1) for x in p.drives])),
           "location": world["robot"]["location"], "battery_percent": world["body"]["battery_percent"],
           "observation": obs}
    return row, [e for e in after if e.kind not in (FEEDBACK, PROPOSAL, STATUS)]


def run_field(script: str | Path | dict, dod: float, seed: int, q_table: str | Path | None, *, label: str = "",
              config: PepperConfig | None = None, scenario: Scenario | None = None, quiet: float = 0.15,
              window: float = 3.0, max_interactions: int = 40) -> FieldResult:
    """Run one robot against an in-process stand-in with the scripted user until the script ends."""
    from .standin import StandinRobot

    sc = scenario or load_scenario()
    cfg = config or load_config(actions=tuple(sc.action_names))
    raw = script if isinstance(script, dict) else load_script(script)
    desired = {i.name: tuple(i.desired) for i in sc.intentions}
    stand = StandinRobot(cfg, raw, seed=seed, time_scale=0.0, desired=desired)
    url = stand.start()
    bridge = PepperBridge(cfg, LinkSettings(url=url), sc)
    res = FieldResult(label, dod, seed)
    try:
        if not bridge.start(10.0):
            raise RobotUnavailable(f"stand-in at {url} not reachable")
        robot = make_robot(sc, dod, seed, q_table, raw.get("robot", {}).get("drives"))
        cues = IntentionCues(cfg.intention_cues, sc.intention_names[1:])
        carry = bridge.collect(quiet, window)
        while not stand.user.done and robot.k < max_interactions:
            row, carry = run_interaction(bridge, robot, cues, carry, quiet, window)
            res.log.append(row)
        res.user_log = list(stand.user.log)
        res.diagnostics = bridge.diagnostics.snapshot()
    finally:
        bridge.stop()
        stand.close()
    return res


# -- tables -------------------------------------------------------------------------
def format_table(res: FieldResult) -> list[str]:
    lines = [f"{res.label or 'robot'} (DoD {res.dod}, seed {res.seed})",
             f"{'#':>2}  {'m_dom':<10} {'intention':<9} {'action':<8} {'fb':>3}  {'proposal':<8}"]
    for r in res.log:
        fb = {1: "+", -1: "-", 0: ""}[r["feedback"]]
        lines.append(f"{r['interaction']:>2}  {r['m_dom']:<10} {r['intention'] or '-':<9} {r['action']:<8} {fb:>3}  "
                     f"{r['proposal'] or '-':<8}")
    s = res.summary()
    lines.append(f"satisfied {s['satisfied']}/{s['intentions']}  HSR {s['hsr'] if s['hsr'] is None else round(s['hsr'], 3)}"
                 f"  first Attach {s['first_attach'] or '-'}")
    return lines


def side_by_side(a: FieldResult, b: FieldResult, gap: int = 4) -> str:
    la, lb = format_table(a), format_table(b)
    w = max(len(x) for x in la)
    n = max(len(la), len(lb))
    la += [""] * (n - len(la))
    lb += [""] * (n - len(lb))
    return "\n".join(f"{x:<{w}}{' ' * gap}{y}".rstrip() for x, y in zip(la, lb))


def main(argv=None) -> int:
    import qi

    ap = argparse.ArgumentParser(prog="homeo-pepper-field",
                                 description="Field test (thesis Section 4.3): dedicated (DoD 0.25) vs selfish (DoD 0) "
                                             "robots meet the same scripted user on a stand-in Pepper.")
    ap.add_argument("--script", default="field_dedicated.json", help="scripted user (a path, or a file of scripts/)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--q-dedicated", help="Q-table of the dedicated robot (default: trained in-process, "
                                          "homeo-sim run --iterations 5000 --seed 0)")
    ap.add_argument("--q-selfish", help="Q-table of the selfish robot (default: trained in-process at DoD 0, "
                                        "homeo-sim run --iterations 5000 --seed 0 --dod 0)")
    ap.add_argument("--same-q", metavar="FILE", help="one Q-table for both robots (only the DoD of their reward differs)")
    ap.add_argument("--config", help="places/phrases file (default scripts/pepper.json)")
    ap.add_argument("--json", action="store_true", help="print the interaction logs and summaries as JSON")
    a = ap.parse_args(argv)
    qi.logging.setLevel(qi.logging.ERROR)
    sc = load_scenario()
    cfg = load_config(a.config, actions=tuple(sc.action_names))
    with tempfile.TemporaryDirectory() as tmp:
        tables = {}
        for label, dod in DODS:
            given = a.same_q or (a.q_dedicated if label == "dedicated" else a.q_selfish)
            tables[label] = given or str(train_q(Path(tmp) / f"q_{label}.json", dod))
        out = []
        for seed in a.seeds:
            pair = [run_field(a.script, dod, seed, tables[label], label=label, config=cfg, scenario=sc)
                    for label, dod in DODS]
            out.append(pair)
            if not a.json:
                print(side_by_side(*pair))
                print()
    if a.json:
        print(json.dumps([{"seed": p[0].seed, "robots": [{"summary": r.summary(), "log": r.log} for r in p]} for p in out],
                         indent=1))
    else:
        print("first Attach: the interaction at which the robot first asked to be plugged in (- = never)")
        print(f"{'seed':>4}  {'dedicated sat.':>14} {'selfish sat.':>12}  {'ded. attach':>11} {'self. attach':>12}")
        for p in out:
            d, s = p[0].summary(), p[1].summary()
            print(f"{d['seed']:>4}  {d['satisfied']:>8}/{d['intentions']:<5} {s['satisfied']:>6}/{s['intentions']:<5}  "
                  f"{d['first_attach'] or '-':>11} {s['first_attach'] or '-':>12}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
