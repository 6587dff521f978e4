"""``homeo-launch pepper``: the graph with the Pepper world (``pepper_bridge.world_backend.PepperWorld``).

    homeo-launch pepper [--qi-url URL [--user U --password P] | --standin [--script FILE]]
                        [--q-table FILE] [--dod X] [--interactions N] [--seed S] [--json]
    homeo-launch pepper --field [--script FILE] [--q-dedicated FILE --q-selfish FILE | --q-table FILE] [--seed S]

The one launcher (``launch.run_graph``) with ``world: pepper`` and, with ``--standin``, a stand-in
Pepper as its own process on loopback; each interaction is printed as it happens and at the end
the interaction log (m_dom, intention, action, feedback, proposal) as a table or, with ``--json``,
as JSON. With a Q-table the decision node loads it and keeps learning in the last phase of the
scenario's schedule (alpha 0.1, tau 2.0: the robot continues after its simulated training;
``--fresh-schedule`` starts the schedule over). The script's ``robot.drives`` become the drives
node's initial drives. ``--field`` is the field test through the graph (``field.py``).
"""

from __future__ import annotations

import copy
import json
import os
import sys
import tempfile
from pathlib import Path

from homeo_msgs_py import graph as G
from homeo_msgs_py.cli_args import UserError, float_in, int_at_least, user_path
from homeo_msgs_py.learning import DOD, add_learning_flags
from homeo_msgs_py.params import add_flag

from .launch import PROG, GraphOptions, new_session, run_graph
from .options import add_run_options, check_files, close_sinks, durable_options, open_sinks

# --intention -> the intention node's mode: the config's cues name the intention (read by the oracle)
INTENTION_MODES = {"cues": G.ORACLE, G.BAYES: G.BAYES}
OWN_FLAGS = ("qi_url", "intention_cues", "end_with_script")  # world parameters this front end sets itself
DEFAULTS = {"collect_window": " (default 3 with the stand-in, 8 on a robot)",
            "collect_quiet": " (default 0.15 with the stand-in; on a robot the whole window)",
            "naoqi_version": "; e.g. 2.4: voice emotion levels 0..5"}


def scenario_file(path: str | None, out_dir: Path, continue_schedule: bool) -> str:
    """The scenario the nodes load: the given (or thesis) one; with ``continue_schedule`` its
    learning schedule is reduced to the last phase (the robot continues after its training)."""
    from homeo_decision.scenarios import default_scenario_path

    if not continue_schedule:
        return os.path.abspath(path) if path else ""
    src = Path(path) if path else default_scenario_path()
    raw = copy.deepcopy(json.loads(src.read_text()))
    raw["learning"]["schedule"] = [dict(raw["learning"]["schedule"][-1], **{"from": 0})]
    dst = out_dir / "scenario.json"
    dst.write_text(json.dumps(raw))
    return str(dst)


def run_robot(a, label: str, dod: float | None, q_table: str | None, log_dir: Path, on_row=None,
              last: dict | None = None, sinks=()) -> dict:
    """One graph run (with its own stand-in when asked); returns the label, the DoD, the status and the user log."""
    from pepper_bridge.launch_support import StandinProcess, check_standin

    script, overrides = None, {}
    if a.script:
        script = _script_path(a.script)
        drives = script_drives(script)
        if drives:
            overrides["initial_drives"] = dict(drives)
    standin = None
    shown = [0]

    def on_status(tick, fields):  # each interaction once, by number: a restarted world's log goes on
        for r in (fields.get("extra") or {}).get("log") or []:
            k = r.get("interaction") if isinstance(r, dict) else None
            if type(k) is int and k > shown[0]:
                shown[0] = k
                if on_row is not None:
                    on_row(r)
    try:
        url = a.qi_url
        if a.standin:
            standin = StandinProcess(str(script) if script else None, a.seed, a.time_scale, log_dir / "standin.log",
                                     a.config)
            url = standin.url
        durable = dict(a.durable, session=new_session())
        if durable["checkpoint_dir"] and label != "robot":  # the field test's two robots: one folder each
            durable["checkpoint_dir"] = os.path.join(durable["checkpoint_dir"], label)
        world = {s: getattr(a, s) for s in a.world_flags if getattr(a, s) is not None}
        world.update(iterations=a.interactions, action_timeout=float(a.action_timeout), qi_url=url,
                     config=os.path.abspath(a.config) if a.config else "", intention_cues=a.intention == "cues",
                     end_with_script=bool(a.standin and script))
        o = GraphOptions(world="pepper", world_params=world, seed=a.seed,
                         learning={} if dod is None else {DOD.name: float(dod)}, intention=INTENTION_MODES[a.intention],
                         scenario=scenario_file(a.scenario, log_dir, bool(q_table) and not a.fresh_schedule),
                         overrides=tuple(overrides.items()), load_q=q_table, data_dir=a.data_dir,
                         namespace=a.namespace, auth=not a.no_auth, **durable)
        status = run_graph(o, quiet=getattr(a, "quiet", False), log_dir=str(log_dir), on_status=on_status, last=last,
                           sinks=sinks, check=lambda: check_standin(standin))
        return {"label": label, DOD.name: dod, "status": status,
                "user_log": standin.user_log() if standin is not None else []}
    finally:
        if standin is not None:
            standin.stop()


def script_drives(path) -> dict | None:
    """The scripted user's ``robot.drives`` (None: not given): the drives node's initial drives;
    ``ros2 launch ... standin:=true script:=FILE`` reads them too (``ros_launch.py``)."""
    from pepper_bridge.user import load_script

    return (load_script(path).get("robot") or {}).get("drives")


def _script_path(s: str) -> Path:
    from pepper_bridge.config import SCRIPTS_DIR

    p = Path(s)
    if not p.exists() and not p.is_absolute() and (SCRIPTS_DIR / p).exists():
        p = SCRIPTS_DIR / p
    if not p.is_file():
        raise UserError(f"user script not found: {s}")
    return p.resolve()


# -- command line ------------------------------------------------------------------------------
def add_parser(subparsers) -> None:
    from pepper_bridge.world_backend import PepperWorld

    p = subparsers.add_parser("pepper", help="the graph with the Pepper world (a real robot or the stand-in)",
                              description="The node graph with the Pepper world in the world node.")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--qi-url", default="tcp://127.0.0.1:9559", help="the robot's NAOqi URL "
                     "(default tcp://127.0.0.1:9559; tcps://ROBOT:9503 with --user/--password)")
    src.add_argument("--standin", action="store_true", help="start a stand-in Pepper on loopback (its own process)")
    p.add_argument("--connect-bound", type=float_in(0.5, 600.0), default=15.0,
                   help="seconds to wait for the robot at --qi-url before giving up with exit code 2 (default 15)")
    p.add_argument("--script", metavar="FILE", type=user_path, help="the stand-in's scripted user (a path or a file of "
                   "pepper_bridge/scripts/); its robot.drives are the initial drives")
    p.add_argument("--q-table", metavar="FILE", type=user_path, help="the decision node loads this Q-table at start "
                   "(with --field: one table for both robots)")
    add_learning_flags(p, (DOD,), help_extra=" (default: the scenario's)")
    p.add_argument("--intention", choices=tuple(INTENTION_MODES), default="cues",
                   help="cues (default): the config's keyword/gesture cues name the intention (the intention node in "
                        "oracle mode; as homeo-pepper-field); bayes: the Bayesian recogniser on the raw cues")
    p.add_argument("--interactions", type=int_at_least(0, G.TICKS_MAX), default=0,
                   help="interactions (0 = until the script ends, or Ctrl-C on a robot)")
    p.add_argument("--time-scale", type=float_in(0.0, 1000.0), default=0.0,
                   help="stand-in: simulated seconds per wall second (default 0: each action lasts 10 s, reproducible)")
    flags = [s for s in PepperWorld.PARAMS if s.name not in OWN_FLAGS]
    for spec in flags:  # the world's parameters (default: the node's, but where DEFAULTS says otherwise)
        add_flag(p, spec, help_extra=DEFAULTS.get(spec.name, ""))
    p.add_argument("--fresh-schedule", action="store_true", help="with a Q-table: start the learning schedule over "
                   "(default: continue in its last phase)")
    p.add_argument("--field", action="store_true", help="the field test: a dedicated (DoD 0.25) and a selfish (DoD 0) "
                   "robot meet the same scripted user on stand-ins; both tables side by side")
    p.add_argument("--q-dedicated", metavar="FILE", type=user_path, help="--field: the dedicated robot's Q-table (default: trained, "
                   "homeo-sim run --iterations 5000 --seed 0)")
    p.add_argument("--q-selfish", metavar="FILE", type=user_path, help="--field: the selfish robot's Q-table (default: trained at DoD 0)")
    add_run_options(p, "pepper", seed_help="seed of the decision node and the stand-in")
    p.set_defaults(world_flags=tuple(s.name for s in flags))


def _check_args(a) -> None:
    if a.field:
        a.standin = True
        a.script = a.script or "field_user.json"
        if a.dod is not None:
            raise UserError("--field runs DoD 0.25 and DoD 0; leave out --dod")
    if a.script and not a.standin:
        raise UserError("--script needs --standin (a real robot has a real user)")
    if a.field and (getattr(a, "record", None) or getattr(a, "foxglove", None)):
        raise UserError("--record and --foxglove watch one robot: leave out --field")
    if getattr(a, "record", None):
        from .record import check_new_bag

        check_new_bag(a.record)
    if (a.q_dedicated or a.q_selfish) and not a.field:
        raise UserError("--q-dedicated / --q-selfish go with --field")
    if a.script:
        _script_path(a.script)
    if a.config and not os.path.isfile(a.config):
        raise UserError(f"config file not found: {a.config}")
    if a.naoqi_version and a.naoqi_version != "auto":
        from pepper_bridge.mapping import emotion_scale

        try:
            emotion_scale(a.naoqi_version)
        except ValueError as exc:
            raise UserError(f"--naoqi-version: {exc} or 'auto'") from None
    if a.collect_window is None:
        a.collect_window = 3.0 if a.standin else 8.0
    if a.collect_quiet is None:
        a.collect_quiet = 0.15 if a.standin else a.collect_window
    from homeo_decision.scenario import load_scenario
    from pepper_bridge.config import load_config

    # a bad scenario, config or Q-table is a one-line error here, not in four nodes
    sc = load_scenario(a.scenario)
    load_config(a.config, scenario=sc)
    check_files(a, tables=[("--q-table", a.q_table), ("--q-dedicated", a.q_dedicated), ("--q-selfish", a.q_selfish)],
                sc=sc)
    if a.resume and (a.field or a.q_table):
        raise UserError("--resume continues one robot from its checkpoint: leave out --field and --q-table")
    a.durable = durable_options(a, "pepper", sc, a.intention == "bayes")


def row_line(r: dict) -> str:
    fb = {1: "+", -1: "-", 0: ""}.get(r["feedback"], "?")
    return (f"{r['interaction']:>3}  {r['m_dom'] or '-':<10} {r['intention'] or '-':<9} {r['action'] or '-':<8} "
            f"{fb:>3}  {r['proposal'] or '-':<8}  {done_note(r)}").rstrip()


def done_note(r: dict) -> str:
    """What became of the action: '' when done; 'FAILED: reason' (refused: no effect) or
    'MISSED: reason' (robot away or unresponsive)."""
    if r.get("ok", True) or r.get("action") is None:
        return ""
    why = (r.get("reason") or "").splitlines()[0][:60] if r.get("reason") else "no reason given"
    return f"{'MISSED' if r.get('missed') else 'FAILED'}: {why}"


HEADER = f"{'#':>3}  {'m_dom':<10} {'intention':<9} {'action':<8} {'fb':>3}  {'proposal':<8}  done"


def print_log_table(log: list, missed: int, table: list[str] | None = None) -> None:
    """The end of a run's text output: ``table`` (default: HEADER and a row per interaction of
    ``log``), then the count line; ``homeo-launch watch`` prints the same (``watch.print_log``)."""
    print("\n".join(table if table is not None else [HEADER, *map(row_line, log)]))
    print(f"{len(log)} interactions, {missed} missed")


def cmd_pepper(a) -> int:
    from homeo_decision.qtable_io import QTableError
    from pepper_bridge.config import ConfigError
    from pepper_bridge.launch_support import StandinError, probe_robot
    from pepper_bridge.user import ScriptError

    from .monitor import GraphError

    try:
        _check_args(a)
    except (ConfigError, ScriptError) as exc:
        raise UserError(str(exc)) from None
    if not a.standin:
        try:
            # one line and exit 2, not a silent wait; the bound is the whole command's: keep ~1 s for the
            # interpreter's start and exit
            probe_robot(a.qi_url, max(0.5, a.connect_bound - 1.0), a.user, a.password, shown=a.connect_bound)
        except UserError as exc:
            # libqi's threads may abort the interpreter's teardown after a failed session (exit -6):
            # say it in one line and leave at once
            print(f"{PROG}: error: {exc}", file=sys.stderr, flush=True)
            sys.stdout.flush()
            os._exit(2)
    with tempfile.TemporaryDirectory(prefix="homeo-pepper-") as tmp:
        base = Path(a.log_dir or tmp)
        base.mkdir(parents=True, exist_ok=True)
        try:
            if a.field:
                from .field import cmd_field_graph

                return cmd_field_graph(a, base, run_robot)
            return _cmd_one(a, base)
        except (ConfigError, ScriptError, QTableError) as exc:
            raise UserError(str(exc)) from None
        except StandinError as exc:
            raise GraphError(str(exc)) from None


def _cmd_one(a, base: Path) -> int:
    from homeo_decision.scenario import load_scenario

    from .field import field_result, format_table

    show = not a.json and not a.quiet
    if show:
        print(HEADER, file=sys.stderr)
    last: dict = {}
    sinks = open_sinks(a, "pepper", a.interactions, a.seed, load_scenario(a.scenario), {})
    try:
        run = run_robot(a, "robot", a.dod, a.q_table, base, on_row=(lambda r: print(row_line(r), file=sys.stderr))
                        if show else None, last=last, sinks=sinks)
        code = 0
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted; all nodes stopped", file=sys.stderr)
        run = {"label": "robot", DOD.name: a.dod, "status": dict(last), "user_log": []}
        code = 0 if a.interactions == 0 and not a.script else 130  # an unbounded run ends with Ctrl-C
        if not (last.get("extra") or {}).get("log"):
            return 130
    finally:
        close_sinks(sinks)
    res = field_result(run, a.seed, float(load_scenario(a.scenario).learning[DOD.name]), a)
    st = run["status"]
    if a.json:
        out = {"seed": a.seed, DOD.name: res.dod, "url": (st.get("extra") or {}).get("robot", {}).get("url"),
               "interactions": len(res.log), "missed": st.get("missed", 0), "log": res.log}
        if res.user_log:
            out["summary"] = res.summary()
            out["user_log"] = res.user_log
        if st.get("restarts"):
            out["restarts"] = st["restarts"]
        print(json.dumps(out, indent=1))
        return code
    print_log_table(res.log, st.get("missed", 0), format_table(res) if res.user_log else None)
    if st.get("restarts"):
        print("restarts: " + ", ".join(f"{n} {k}" for n, k in sorted(st["restarts"].items())))
    return code
