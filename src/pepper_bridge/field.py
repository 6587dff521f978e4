"""The field test of Section 4.3 without ROS: the decision core on a (stand-in) Pepper.

A Q-table learned in simulation is loaded; the robot starts nearly depleted; a dedicated
robot (DoD 0.25) and a selfish one (DoD 0) meet the same scripted user (Tables 4.7, 4.8).

The robot is ``homeo_decision.robot.Robot`` (an oracle recognition reading the intention the
config's cues name, the perception, the decision with the loaded Q-table) in a
``pepper_bridge.environment.PepperEnvironment`` on an in-process stand-in: the objects the graph's
nodes host, stepped by ``run_loop`` until the scripted user is done.
The tick count continues after the simulated training (``t0`` = 5000).

With ``--graph`` each robot runs through the node graph instead, as a user starts it: the generic
front end, ``homeo-launch pepper --standin --script S --load-q Q --dod D --json`` (a command, not an
import: the launcher is a layer above).

CLI (``homeo-pepper-field``)::

    homeo-pepper-field --script field_user.json --seeds 0 1 2 [--q-dedicated F --q-selfish F | --same-q F] [--json]
    homeo-pepper-field --graph --script field_user.json --seeds 0 ...
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from homeo_decision import checkpoint
from homeo_decision.agent import DecisionCore
from homeo_decision.robot import OracleRecognition, Robot, run_loop
from homeo_decision.scenario import Scenario, load_scenario
from homeo_msgs_py.learning import DOD
from pepper_bridge.bridge import PepperBridge
from pepper_bridge.config import LinkSettings, PepperConfig, load_config
from pepper_bridge.environment import PepperEnvironment
from pepper_bridge.naoqi_link import RobotUnavailable
from pepper_bridge.user import load_script

DODS = (("dedicated", 0.25), ("selfish", 0.0))
TRAIN_ITERATIONS = 5000


def initial_drives(sc: Scenario, given: dict | None) -> list[float]:
    """The scenario's initial drives, with the script's ``robot.drives`` over them."""
    init = dict(zip(sc.drive_names, sc.open.initial_drives))
    init.update(given or {})
    return [float(init[n]) for n in sc.drive_names]


def make_robot(sc: Scenario, dod: float, seed: int, q_table: str | Path | None) -> Robot:
    core = DecisionCore(sc, seed, dod=dod)
    if q_table:
        checkpoint.load_table(core.q, q_table)
    return Robot(sc, core, OracleRecognition(sc))


def _command(*argv: str, timeout: float = 900.0) -> str:
    """Another command of the project (the simulation, the launcher: layers this one does not import);
    its standard output, or RuntimeError with its last words."""
    import subprocess

    r = subprocess.run([sys.executable, "-m", *argv], capture_output=True, text=True, timeout=timeout)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(argv[:2])} failed ({r.returncode}): {r.stderr.strip()[-400:]}")
    return r.stdout


def train_q(path: str | Path, dod: float | None = None, seed: int = 0, iterations: int = TRAIN_ITERATIONS) -> Path:
    """The Q-table at the end of the default simulation (``homeo-sim run --seed 0 --save-q``)."""
    _command("homeo_sim.cli", "run", "--iterations", str(iterations), "--seed", str(seed), "--save-q", str(path),
             "--quiet", "--json", *(["--dod", repr(float(dod))] if dod is not None else []))
    return Path(path)


@dataclass
class FieldResult:
    label: str
    dod: float
    seed: int
    log: list = field(default_factory=list)  # one row per interaction
    user_log: list = field(default_factory=list)  # the scripted user's judgement (stand-in only)
    diagnostics: dict = field(default_factory=dict)
    roles: dict = field(default_factory=dict)  # charging roles of the actions (``charging_roles``)

    def summary(self) -> dict:
        judged = [r for r in self.user_log if r["intention"] is not None]
        wanted = {}
        for r in judged:  # one intention of the script may take several attempts
            wanted[r["item"]] = wanted.get(r["item"], False) or bool(r["satisfied"])
        acts = [r["action"] for r in self.log]
        first = lambda names: next((r["interaction"] for r in self.log if r["action"] in names), None)  # noqa: E731
        return {"label": self.label, DOD.name: self.dod, "seed": self.seed, "interactions": len(self.log),
                "intentions": len(wanted), "satisfied": sum(wanted.values()),
                "hsr": (sum(r["satisfied"] for r in judged) / len(judged)) if judged else None,
                "first_attach": first(self.roles.get("plug", ())),
                "first_to_plug": first(self.roles.get("plug", ()) + self.roles.get("to_plug", ())),
                "survival_actions": sum(a in self.roles.get("plug_object", ()) for a in acts)}


def charging_roles(cfg: PepperConfig, sc: Scenario) -> dict:
    """Which actions the field summary counts, from the config and the scenario: ``plug`` asks to
    be plugged in, ``to_plug`` moves to the plugged object's place, ``plug_object`` are that object's
    actions except unplugging (the robot looking after its battery)."""
    plugs = cfg.plug_actions()
    if not cfg.plug:
        return {}
    obj = cfg.plug["variable"].split(".")[0]
    place = sc.objects[obj]["location"]
    to = cfg.move_action(place) if place else None
    return {"plug": tuple(a for a, on in plugs.items() if on), "to_plug": (to,) if to else (),
            "plug_object": tuple(a.name for a in sc.actions if a.obj == obj and plugs.get(a.name, True))}


def run_field(script: str | Path | dict, dod: float, seed: int, q_table: str | Path | None, *, label: str = "",
              config: PepperConfig | None = None, scenario: Scenario | None = None, quiet: float = 0.15,
              window: float = 3.0, max_interactions: int = 40, t0: int = TRAIN_ITERATIONS) -> FieldResult:
    """Run one robot against an in-process stand-in with the scripted user until the script ends."""
    from pepper_bridge.standin import StandinRobot

    sc = scenario or load_scenario()
    cfg = config or load_config(scenario=sc)
    raw = script if isinstance(script, dict) else load_script(script)
    stand = StandinRobot(cfg, raw, seed=seed, time_scale=0.0, scenario=sc)
    url = stand.start()
    bridge = PepperBridge(cfg, LinkSettings(url=url), sc)
    res = FieldResult(label, dod, seed, roles=charging_roles(cfg, sc))
    try:
        if not bridge.start(10.0):
            raise RobotUnavailable(f"stand-in at {url} not reachable")
        env = PepperEnvironment(bridge, quiet=quiet, window=window, use_cues=True)
        robot = make_robot(sc, dod, seed, q_table)
        robot.restart(initial_drives(sc, raw.get("robot", {}).get("drives")))

        def row(t, p, r, a, out):  # the interaction just done, with what the decision chose it for
            res.log.append(dict(env.last_row, m_dom=sc.internal_states[p.m_dom], intention=env.last_row["cue_intention"],
                                drives=dict(zip(sc.drive_names, [round(x, 1) for x in p.drives]))))

        # the tick count continues after the simulated training; the run ends when the scripted user does
        run_loop(env, robot, max_interactions, env.reset(seed), row, t0=t0, done=lambda: stand.user.done)
        res.user_log = list(stand.user.log)
        res.diagnostics = bridge.diagnostics.snapshot()
    finally:
        bridge.stop()
        stand.close()
    return res


# -- the field test through the graph ---------------------------------------------------------
def run_graph_field(script: str, dod: float, seed: int, q_table: str, *, label: str = "", config: str | None = None,
                    scenario: Scenario | None = None) -> FieldResult:
    """One robot through the node graph, against its own stand-in with the scripted user: the launcher's
    ``homeo-launch pepper`` with ``--json``, as a user runs it."""
    sc = scenario or load_scenario()
    out = json.loads(_command("homeo_launch.cli", "pepper", "--standin", "--script", str(script), "--load-q",
                              str(q_table), "--dod", repr(float(dod)), "--seed", str(seed), "--json", "--quiet",
                              *(["--config", config] if config else [])))
    return FieldResult(label, dod, seed, log=out["log"], user_log=out.get("user_log", []),
                       roles=charging_roles(load_config(config, scenario=sc), sc))


# -- tables -------------------------------------------------------------------------
def format_table(res: FieldResult) -> list[str]:
    lines = [f"{res.label or 'robot'} (DoD {res.dod}, seed {res.seed})",
             f"{'#':>2}  {'m_dom':<10} {'intention':<9} {'action':<8} {'fb':>3}  {'proposal':<8}"]
    for r in res.log:
        fb = {1: "+", -1: "-", 0: ""}[r["feedback"]]
        failed = "" if r.get("ok", True) or r.get("action") is None else (" MISSED" if r.get("missed") else " FAILED")
        lines.append(f"{r['interaction']:>2}  {r['m_dom'] or '-':<10} {r['intention'] or '-':<9} {r['action'] or '-':<8} "
                     f"{fb:>3}  {r['proposal'] or '-':<8}{failed}")
    s = res.summary()
    lines.append(f"satisfied {s['satisfied']}/{s['intentions']}  HSR {s['hsr'] if s['hsr'] is None else round(s['hsr'], 3)}"
                 f"  first plug-in {s['first_attach'] or '-'}")
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
    ap.add_argument("--graph", action="store_true", help="each robot through the node graph (homeo-launch pepper), "
                                                         "not in-process")
    a = ap.parse_args(argv)
    qi.logging.setLevel(qi.logging.ERROR)
    sc = load_scenario()
    cfg = load_config(a.config, scenario=sc)
    with tempfile.TemporaryDirectory() as tmp:
        tables = {}
        for label, dod in DODS:
            given = a.same_q or (a.q_dedicated if label == "dedicated" else a.q_selfish)
            tables[label] = given or str(train_q(Path(tmp) / f"q_{label}.json", dod))
        out = []
        for seed in a.seeds:
            pair = [run_graph_field(a.script, dod, seed, tables[label], label=label, config=a.config, scenario=sc)
                    if a.graph else run_field(a.script, dod, seed, tables[label], label=label, config=cfg, scenario=sc)
                    for label, dod in DODS]
            out.append(pair)
            if not a.json:
                print(side_by_side(*pair))
                print()
    if a.json:
        print(json.dumps([{"seed": p[0].seed, "robots": [{"summary": r.summary(), "log": r.log} for r in p]} for p in out],
                         indent=1))
    else:
        print("first plug-in: the interaction at which the robot first asked to be plugged in (- = never)")
        print(f"{'seed':>4}  {'dedicated sat.':>14} {'selfish sat.':>12}  {'ded. attach':>11} {'self. attach':>12}")
        for p in out:
            d, s = p[0].summary(), p[1].summary()
            print(f"{d['seed']:>4}  {d['satisfied']:>8}/{d['intentions']:<5} {s['satisfied']:>6}/{s['intentions']:<5}  "
                  f"{d['first_attach'] or '-':>11} {s['first_attach'] or '-':>12}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
