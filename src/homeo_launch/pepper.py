"""``homeo-launch pepper``: the node graph with the Pepper bridge in place of ``homeo_sim``.

    homeo-launch pepper [--qi-url URL [--user U --password P] | --standin [--script FILE]]
                        [--q-table FILE] [--dod X] [--interactions N] [--seed S] [--json]
    homeo-launch pepper --field [--script FILE] [--q-dedicated FILE --q-selfish FILE | --q-table FILE] [--seed S]

Starts ``pepper_bridge``, ``homeo_intention``, ``homeo_drives`` and ``homeo_decision`` as
processes (and, with ``--standin``, a stand-in Pepper as its own process on loopback), waits
until all are up, prints each interaction as it happens and at the end the interaction log
(m_dom, intention, action, feedback, proposal) as a table or, with ``--json``, as JSON.

With a Q-table the decision node loads it and keeps learning in the last phase of the
scenario's schedule (alpha 0.1, tau 2.0: the robot continues after its simulated training,
as ``homeo-pepper-field`` does; ``--fresh-schedule`` starts the schedule over). The script's
``robot.drives`` (e.g. NAch 70, NSoc 55) become the drives node's initial drives.

``--field`` runs the field test through the graph: a dedicated (DoD 0.25) and a selfish
(DoD 0) robot, each with its own stand-in, meet the same scripted user; both tables are
printed side by side (``homeo_launch.field.side_by_side``); each table is row for row the one
of ``homeo-pepper-field`` (the same robot and environment objects, split across the nodes).
"""

from __future__ import annotations

import copy
import json
import os
import select
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from homeo_msgs_py import graph as G
from homeo_msgs_py.cli_args import UserError, float_in, int_at_least

from .processes import Graph, NodeSpec, add_graph_options, dds_defaults, graph_env
from .sim import DISCOVERY_TIMEOUT_S, PROG, GraphError, Monitor, open_tap, split_sinks, with_spool
from .supervise import Supervisor
from .supervise import wait_until_up as supervised_wait

BRIDGE_NODES = G.GRAPHS["pepper"]
STANDIN_START_S = 30.0
FIELD_DODS = (("dedicated", 0.25), ("selfish", 0.0))
# --intention -> the intention node's mode: the config's cues name the intention (read by the oracle)
INTENTION_MODES = {"cues": G.ORACLE, G.BAYES: G.BAYES}


def endpoints(intention: str) -> dict:
    """(writers, readers) per topic of the bridge graph; the Bayesian recogniser reads the outcome too."""
    return G.endpoints("pepper", INTENTION_MODES[intention] == G.BAYES)


# -- the stand-in robot as its own process ------------------------------------------------------
class StandinProcess:
    """``python -m pepper_bridge.standin --listen tcp://127.0.0.1:0 ...``; its URL is the first line."""

    def __init__(self, script: str | None, seed: int, time_scale: float, log_path: Path, config: str | None = None,
                 battery: float | None = None):
        cmd = [sys.executable, "-m", "pepper_bridge.standin", "--listen", "tcp://127.0.0.1:0", "--seed", str(seed),
               "--time-scale", repr(float(time_scale))]
        if script:
            cmd += ["--script", script]
        if config:
            cmd += ["--config", config]
        if battery is not None:
            cmd += ["--battery", repr(float(battery))]
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        self.log_path = log_path
        self.proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                     env=env, start_new_session=True, preexec_fn=_die_with_parent)
        self.url = self._read_url()
        self._drain = threading.Thread(target=self._copy_output, daemon=True, name="standin-output")
        self._drain.start()

    def _read_url(self) -> str:
        end = time.monotonic() + STANDIN_START_S
        buf = b""
        fd = self.proc.stdout.fileno()
        while b"\n" not in buf:
            left = end - time.monotonic()
            if left <= 0 or self.proc.poll() is not None:
                break
            r, _, _ = select.select([fd], [], [], min(left, 0.5))
            if r:
                chunk = os.read(fd, 4096)
                if not chunk:
                    break
                buf += chunk
        line, _, rest = buf.partition(b"\n")
        self._rest = rest
        url = line.decode(errors="replace").strip()
        if not url.startswith(("tcp://", "tcps://")):
            self.stop()
            raise GraphError("the stand-in robot did not start" + (f": {url or buf.decode(errors='replace')[-400:]}"
                                                                   if url or buf else " (no URL printed)"))
        return url

    def _copy_output(self) -> None:
        with open(self.log_path, "ab") as log:
            log.write(self._rest)
            for chunk in iter(lambda: self.proc.stdout.read1(4096), b""):
                log.write(chunk)

    def dead(self) -> int | None:
        return self.proc.poll()

    def user_log(self, timeout: float = 10.0) -> list:
        """The scripted user's judgement of each robot action (HomeoStandin.userLog over qi)."""
        import qi

        qi.logging.setLevel(qi.logging.ERROR)
        s = qi.Session()
        try:
            fut = s.connect(self.url, _async=True)
            fut.value(int(timeout * 1000))
            return [dict(r) for r in s.service("HomeoStandin").userLog()]
        except Exception:
            return []
        finally:
            try:
                s.close()
            except Exception:
                pass

    def stop(self) -> int | None:
        if self.proc.poll() is None:
            try:
                os.killpg(self.proc.pid, 15)
                self.proc.wait(timeout=3.0)
            except (ProcessLookupError, PermissionError):
                pass
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, 9)
                self.proc.wait(timeout=2.0)
        return self.proc.returncode


def _die_with_parent() -> None:  # runs in the child before exec
    try:
        import ctypes

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, 15)  # PR_SET_PDEATHSIG = SIGTERM
    except (OSError, AttributeError):
        pass


# -- is the robot there? ----------------------------------------------------------------------
def probe_robot(url: str, bound: float, user: str | None = None, password: str | None = None,
                shown: float | None = None) -> None:
    """Raise UserError (one line) unless ``url`` answers as NAOqi (an ALMemory service) within ``bound`` s:
    a malformed URL, an unknown host, a refused connection, a port that is not NAOqi, or silence."""
    import socket
    from urllib.parse import urlsplit

    try:
        u = urlsplit(url)
        host, port = u.hostname, u.port
    except ValueError:
        host = port = None
    if u.scheme not in ("tcp", "tcps") or not host or not port:
        raise UserError(f"cannot reach the robot at {url}: not a NAOqi URL (tcp://HOST:9559 or tcps://HOST:9503)")
    result: dict = {}

    def attempt():
        import qi

        end = time.monotonic() + bound
        try:
            socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
        except socket.gaierror:
            result["error"] = f"unknown host {host!r}"
            return
        except OSError as exc:
            result["error"] = f"cannot resolve {host!r} ({exc})"
            return
        qi.logging.setLevel(qi.logging.ERROR)
        s = qi.Session()
        result["session"] = s
        if user:
            from pepper_bridge.naoqi_link import _AuthenticatorFactory

            s.setClientAuthenticatorFactory(_AuthenticatorFactory(user, password or ""))
        try:
            s.connect(url, _async=True).value(max(1, int((end - time.monotonic()) * 1000)))
        except RuntimeError as exc:
            msg = str(exc).strip().splitlines()[0] if str(exc).strip() else "connection failed"
            result["error"] = ("no NAOqi handshake (not a NAOqi port?)" if "timeout" in msg.lower()
                               else f"connection failed: {msg}")
            return
        try:
            s.service("ALMemory", _async=True).value(max(1, int((end - time.monotonic()) * 1000)))
        except RuntimeError:
            result["error"] = "it answers but offers no ALMemory service: not NAOqi"
            return
        result["ok"] = True

    t = threading.Thread(target=attempt, daemon=True, name="robot-probe")
    t.start()
    t.join(bound)
    s = result.get("session")
    if s is not None:
        threading.Thread(target=s.close, daemon=True).start()  # closing a half-open session may block
    if result.get("ok"):
        return
    raise UserError(f"cannot reach the robot at {url}: "
                    + result.get("error", f"no answer within {shown or bound:g} s (--connect-bound)"))


# -- the graph --------------------------------------------------------------------------------
def scenario_file(path: str | None, out_dir: Path, continue_schedule: bool) -> str:
    """The scenario the nodes load: the given (or thesis) one; with ``continue_schedule`` its
    learning schedule is reduced to the last phase (the robot continues after its training)."""
    from homeo_decision.scenarios import default_scenario_path

    if not continue_schedule:
        return os.path.abspath(path) if path else ""
    src = Path(path) if path else default_scenario_path()
    raw = json.loads(src.read_text())
    raw = copy.deepcopy(raw)
    last = dict(raw["learning"]["schedule"][-1], **{"from": 0})
    raw["learning"]["schedule"] = [last]
    dst = out_dir / "scenario.json"
    dst.write_text(json.dumps(raw))
    return str(dst)


def pepper_specs(*, url: str, scenario: str, overrides: dict, seed: int, dod: float | None, q_table: str | None,
                 interactions: int, collect_window: float, collect_quiet: float, action_timeout: float,
                 end_with_script: bool, user: str = "", password: str = "", config: str = "",
                 intention: str = "cues", extra_readers: int = 0, naoqi_version: str = "",
                 data_dir: str = "out", durable: dict | None = None) -> list[NodeSpec]:
    from homeo_decision.node_runtime import overrides_param

    common = {"scenario": scenario, "overrides": overrides_param(overrides), "data_dir": os.path.abspath(data_dir),
              "extra_readers": extra_readers}
    decision = dict(common, seed=seed)
    if dod is not None:
        decision["dod"] = float(dod)
    if q_table:
        decision["q_table_path"] = os.path.abspath(q_table)
        decision["load_on_start"] = True
    bridge = dict(common, qi_url=url, user=user, password=password, config=os.path.abspath(config) if config else "",
                  interactions=interactions, collect_window=float(collect_window), collect_quiet=float(collect_quiet),
                  action_timeout=float(action_timeout), end_with_script=end_with_script,
                  intention_cues=intention == "cues", outcome_readers=endpoints(intention)["outcome"][1],
                  naoqi_version=naoqi_version)
    params = {"pepper_bridge": bridge, "homeo_intention": dict(common, mode=INTENTION_MODES[intention]),
              "homeo_drives": dict(common), "homeo_decision": decision}
    if durable:
        from types import SimpleNamespace

        from .sim import durable_params

        durable_params(SimpleNamespace(**durable), params)
    return [NodeSpec(n, G.NODES[n].module, params[n]) for n in BRIDGE_NODES]


def run_pepper_graph(specs: list[NodeSpec], log_dir: Path, standin: StandinProcess | None = None, on_row=None,
                     last: dict | None = None, discovery_timeout: float = DISCOVERY_TIMEOUT_S,
                     env: dict | None = None, intention: str = "cues", sinks=(), namespace: str = "",
                     auth: bool = True, max_restarts: int = 0, checkpoint_dir: str = "", quiet: bool = False) -> dict:
    """Run the bridge graph until the bridge reports done; returns its last run status fields.
    Raises GraphError (a node or the stand-in died, or the graph never came up) or KeyboardInterrupt.
    ``sinks``: as for ``sim.run_graph``; with a tap the robot nodes start first, and every node's
    topics wait for the tap (``extra_readers``) before their first message."""
    os.environ.update(dds_defaults())
    tap_sinks, writers = split_sinks(sinks)
    if writers is not None:
        with_spool(specs, writers, specs[0].params["data_dir"])
    graph = Graph(specs, env or graph_env(), str(log_dir), namespace=namespace, auth=auth)
    mon = tap = None
    shown = 0
    try:
        mon = Monitor(graph.namespace, graph.signer)
        sup = Supervisor(graph, mon.node, max_restarts, os.path.abspath(checkpoint_dir) if checkpoint_dir else "",
                         log=(lambda text: None) if quiet else None, spool=writers.own if writers else None)
        tap = open_tap(mon, graph, tap_sinks, writers)
        if tap_sinks:
            from .sim import start_robot_first

            start_robot_first(graph, mon, tap, discovery_timeout)
        graph.start()
        _wait_up(graph, mon, standin, endpoints(intention), discovery_timeout, sup)
        while True:
            mon.spin(0.05)
            sup.check()  # nodes are restarted from their checkpoints; a restarted bridge goes on with the run
            _check_standin(standin)
            st = mon.status
            if st is None:
                continue
            if last is not None:
                last.clear()
                last.update(st.fields)
            rows = (st.fields.get("extra") or {}).get("log") or []
            for r in rows:  # by number: a restarted bridge's log goes on from its checkpoint
                k = r.get("interaction") if isinstance(r, dict) else None
                if type(k) is int and k > shown:
                    shown = k
                    if on_row is not None:
                        on_row(r)
            if sup.restarts and last is not None:
                last["restarts"] = dict(sup.restarts)
            if st.fields["done"]:
                if tap_sinks:
                    from .sim import drain

                    drain(mon, tap)
                return dict(st.fields, **({"restarts": dict(sup.restarts)} if sup.restarts else {}))
    finally:
        if tap is not None:
            tap.close()
        if mon is not None:
            mon.close()
        graph.stop()
        graph.close()


def _wait_up(graph, mon, standin, endpoints, bound, sup) -> None:
    end = time.monotonic() + bound
    while True:
        _check_standin(standin)
        try:
            return supervised_wait(graph, mon, sup, BRIDGE_NODES, endpoints, min(1.0, max(0.0, end - time.monotonic())))
        except GraphError:
            if time.monotonic() > end or graph.dead():
                raise


def _check_standin(standin: StandinProcess | None) -> None:
    if standin is not None and standin.dead() is not None:
        tail = ""
        try:
            tail = "\n".join(standin.log_path.read_text(errors="replace").rstrip().splitlines()[-12:])
        except OSError:
            pass
        raise GraphError(f"the stand-in robot exited with code {standin.dead()}" + (f"; its last output:\n{tail}"
                                                                                    if tail else ""))


# -- one robot ---------------------------------------------------------------------------------
def run_robot(a, label: str, dod: float | None, q_table: str | None, log_dir: Path, on_row=None,
              last: dict | None = None, sinks=()) -> dict:
    """One graph run (with its own stand-in when asked); returns {"status", "user_log", ...}."""
    from pepper_bridge.user import load_script

    script = None
    overrides: dict = {}
    if a.script:
        script_path = _script_path(a.script)
        raw = load_script(script_path)
        drives = (raw.get("robot") or {}).get("drives")
        if drives:
            overrides["initial_drives"] = dict(drives)
        script = str(script_path)
    standin = None
    try:
        url = a.qi_url
        if a.standin:
            standin = StandinProcess(script, a.seed, a.time_scale, log_dir / "standin.log", a.config)
            url = standin.url
        sc_path = scenario_file(a.scenario, log_dir, bool(q_table) and not a.fresh_schedule)
        durable = dict(getattr(a, "durable", None) or {"checkpoint_dir": "", "checkpoint_every": 100, "resume": None,
                                                       "max_restarts": 0})
        if durable["checkpoint_dir"] and label != "robot":  # the field test's two robots: one folder each
            durable["checkpoint_dir"] = os.path.join(durable["checkpoint_dir"], label)
        from .sim import new_session

        durable["session"] = new_session()
        specs = pepper_specs(url=url, scenario=sc_path, overrides=overrides, seed=a.seed, dod=dod, q_table=q_table,
                             interactions=a.interactions, collect_window=a.collect_window,
                             collect_quiet=a.collect_quiet, action_timeout=a.action_timeout,
                             end_with_script=bool(a.standin and script), user=a.user or "",
                             password=a.password or "", config=a.config or "", intention=a.intention,
                             extra_readers=1 if split_sinks(sinks)[0] else 0, naoqi_version=a.naoqi_version or "",
                             data_dir=a.data_dir, durable=durable)
        status = run_pepper_graph(specs, log_dir, standin, on_row=on_row, last=last, intention=a.intention,
                                  sinks=sinks, namespace=a.namespace, auth=not a.no_auth,
                                  max_restarts=durable["max_restarts"], checkpoint_dir=durable["checkpoint_dir"],
                                  quiet=getattr(a, "quiet", False))
        user_log = standin.user_log() if standin is not None else []
        return {"label": label, "dod": dod, "status": status, "user_log": user_log}
    finally:
        if standin is not None:
            standin.stop()


def _script_path(s: str) -> Path:
    from pepper_bridge.config import SCRIPTS_DIR

    p = Path(s)
    if not p.exists() and not p.is_absolute() and (SCRIPTS_DIR / p).exists():
        p = SCRIPTS_DIR / p
    if not p.is_file():
        raise UserError(f"user script not found: {s}")
    return p.resolve()


def field_result(run: dict, seed: int, default_dod: float | None = None, roles: dict | None = None):
    from .field import FieldResult

    log = (run["status"].get("extra") or {}).get("log") or []
    dod = run["dod"] if run["dod"] is not None else default_dod
    return FieldResult(run["label"], dod, seed, log=list(log), user_log=list(run["user_log"]), roles=roles or {})


def _roles(a) -> dict:
    """The field summary's charging roles for this run's config and scenario."""
    from homeo_decision.scenario import load_scenario
    from pepper_bridge.config import load_config

    from .field import charging_roles

    sc = load_scenario(a.scenario)
    return charging_roles(load_config(a.config, scenario=sc), sc)


# -- command line ------------------------------------------------------------------------------
def add_parser(subparsers) -> None:
    p = subparsers.add_parser("pepper", help="the graph with the Pepper bridge (a real robot or the stand-in)",
                              description="The node graph with pepper_bridge in place of homeo_sim.")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--qi-url", default="tcp://127.0.0.1:9559", help="the robot's NAOqi URL "
                     "(default tcp://127.0.0.1:9559; tcps://ROBOT:9503 with --user/--password)")
    src.add_argument("--standin", action="store_true", help="start a stand-in Pepper on loopback (its own process)")
    p.add_argument("--connect-bound", type=float_in(0.5, 600.0), default=15.0,
                   help="seconds to wait for the robot at --qi-url before giving up with exit code 2 (default 15)")
    p.add_argument("--naoqi-version", metavar="V", help="read the robot's values in NAOqi V's documented formats "
                   "(e.g. 2.4: voice emotion levels 0..5) instead of asking it (ALSystem.systemVersion); auto = ask")
    p.add_argument("--user", help="NAOqi 2.9 user (tcps)")
    p.add_argument("--password", help="NAOqi 2.9 password (tcps)")
    p.add_argument("--script", metavar="FILE", help="the stand-in's scripted user (a path or a file of "
                   "pepper_bridge/scripts/); its robot.drives are the initial drives")
    p.add_argument("--config", metavar="FILE", help="places/phrases file (default pepper_bridge/scripts/pepper.json)")
    p.add_argument("--scenario", metavar="FILE", help="scenario JSON (default: the thesis scenario)")
    p.add_argument("--q-table", metavar="FILE", help="the decision node loads this Q-table at start "
                   "(with --field: one table for both robots)")
    p.add_argument("--dod", type=float_in(0.0, 1.0), default=None, help="Degree of Dedication (Eq 3.27)")
    p.add_argument("--intention", choices=tuple(INTENTION_MODES), default="cues",
                   help="cues (default): the config's keyword/gesture cues name the intention (the intention node in "
                        "oracle mode; as homeo-pepper-field); bayes: the Bayesian recogniser on the raw cues")
    p.add_argument("--interactions", type=int_at_least(0, G.TICKS_MAX), default=0,
                   help="interactions (0 = until the script ends, or Ctrl-C on a robot)")
    p.add_argument("--seed", type=int_at_least(0, G.SEED_MAX), default=0, help="seed of the decision node and the stand-in")
    p.add_argument("--time-scale", type=float_in(0.0, 1000.0), default=0.0,
                   help="stand-in: simulated seconds per wall second (default 0: each action lasts 10 s, reproducible)")
    p.add_argument("--collect-window", type=float_in(0.0, 600.0), default=None,
                   help="longest wait for the user's reaction, s (default 3 with the stand-in, 8 on a robot)")
    p.add_argument("--collect-quiet", type=float_in(0.0, 600.0), default=None,
                   help="a gap without events that ends the wait, s (default 0.15 with the stand-in; on a robot the "
                        "whole window)")
    p.add_argument("--action-timeout", type=float_in(0.01, 3600.0), default=5.0,
                   help="seconds to wait for the decision before an interaction counts as none (default 5)")
    p.add_argument("--fresh-schedule", action="store_true", help="with a Q-table: start the learning schedule over "
                   "(default: continue in its last phase)")
    p.add_argument("--field", action="store_true", help="the field test: a dedicated (DoD 0.25) and a selfish (DoD 0) "
                   "robot meet the same scripted user on stand-ins; both tables side by side")
    p.add_argument("--q-dedicated", metavar="FILE", help="--field: the dedicated robot's Q-table (default: trained, "
                   "homeo-sim run --iterations 5000 --seed 0)")
    p.add_argument("--q-selfish", metavar="FILE", help="--field: the selfish robot's Q-table (default: trained at DoD 0)")
    p.add_argument("--log-dir", metavar="DIR", help="keep each node's log here (default: a temporary directory)")
    add_graph_options(p)
    p.add_argument("--json", action="store_true", help="print the interaction log as JSON")
    p.add_argument("--quiet", action="store_true", help="no per-interaction progress on stderr")
    from .durable_args import add_durable_options
    from .live_args import add_live_options

    add_live_options(p)
    add_durable_options(p, "pepper")


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
    from .sim import check_files

    check_files(a, read=[("--q-table", a.q_table), ("--q-dedicated", a.q_dedicated), ("--q-selfish", a.q_selfish)])
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

    # a bad scenario or config is a one-line error here, not in four nodes
    sc = load_scenario(a.scenario)
    load_config(a.config, scenario=sc)
    if a.resume and (a.field or a.q_table):
        raise UserError("--resume continues one robot from its checkpoint: leave out --field and --q-table")
    from .durable_args import durable_options

    a.durable = durable_options(a, "pepper", sc, a.intention == "bayes")


def _row_line(r: dict) -> str:
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


def cmd_pepper(a) -> int:
    from homeo_decision.qtable_io import QTableError

    from pepper_bridge.config import ConfigError
    from pepper_bridge.user import ScriptError

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
    tmp = None
    if a.log_dir:
        base = Path(a.log_dir)
        base.mkdir(parents=True, exist_ok=True)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="homeo-pepper-")
        base = Path(tmp.name)
    try:
        if a.field:
            return _cmd_field(a, base)
        return _cmd_one(a, base)
    except (ConfigError, ScriptError, QTableError) as exc:
        raise UserError(str(exc)) from None
    finally:
        if tmp is not None:
            tmp.cleanup()


def _cmd_one(a, base: Path) -> int:
    show = not a.json and not a.quiet
    if show:
        print(HEADER, file=sys.stderr)
    last: dict = {}
    from homeo_decision.scenario import load_scenario

    from .sim import close_sinks, open_sinks

    sinks = open_sinks(a, "pepper", a.interactions, a.seed, load_scenario(a.scenario), {})
    try:
        run = run_robot(a, "robot", a.dod, a.q_table, base, on_row=(lambda r: print(_row_line(r), file=sys.stderr))
                        if show else None, last=last, sinks=sinks)
        code = 0
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted; all nodes stopped", file=sys.stderr)
        run = {"label": "robot", "dod": a.dod, "status": dict(last), "user_log": []}
        code = 0 if a.interactions == 0 and not a.script else 130  # an unbounded run ends with Ctrl-C
        if not (last.get("extra") or {}).get("log"):
            return 130
    finally:
        close_sinks(sinks)

    res = field_result(run, a.seed, float(load_scenario(a.scenario).learning["dod"]), roles=_roles(a))
    st = run["status"]
    if a.json:
        out = {"seed": a.seed, "dod": res.dod, "url": (st.get("extra") or {}).get("robot", {}).get("url"),
               "interactions": len(res.log), "missed": st.get("missed", 0), "log": res.log}
        if res.user_log:
            out["summary"] = res.summary()
            out["user_log"] = res.user_log
        if st.get("restarts"):
            out["restarts"] = st["restarts"]
        print(json.dumps(out, indent=1))
    else:
        if res.user_log:
            print("\n".join(_format(res)))
        else:
            print(HEADER)
            for r in res.log:
                print(_row_line(r))
        print(f"{len(res.log)} interactions, {st.get('missed', 0)} missed")
        if st.get("restarts"):
            print("restarts: " + ", ".join(f"{n} {k}" for n, k in sorted(st["restarts"].items())))
    return code


def _format(res) -> list[str]:
    from .field import format_table

    return format_table(res)


def _field_tables(a, tmp: Path) -> dict:
    from .field import train_q

    tables = {}
    for label, dod in FIELD_DODS:
        given = a.q_table or (a.q_dedicated if label == "dedicated" else a.q_selfish)
        if not given:
            print(f"{PROG}: training the {label} robot's Q-table (5000 simulated iterations, seed 0, DoD {dod})",
                  file=sys.stderr)
            given = str(train_q(Path(a.data_dir) / "field" / f"q_{label}.json", dod))  # kept: the node reads it there
        tables[label] = given
    return tables


def _cmd_field(a, base: Path) -> int:
    from .field import side_by_side

    tables = _field_tables(a, base)
    results = []
    for label, dod in FIELD_DODS:
        d = base / label
        d.mkdir(exist_ok=True)
        if not a.json and not a.quiet:
            print(f"{PROG}: {label} robot (DoD {dod}) through the graph", file=sys.stderr)
        run = run_robot(a, label, dod, tables[label], d)
        results.append(field_result(run, a.seed, roles=_roles(a)))
    if a.json:
        print(json.dumps({"seed": a.seed, "robots": [{"summary": r.summary(), "log": r.log} for r in results]},
                         indent=1))
    else:
        print(side_by_side(*results))
    return 0
