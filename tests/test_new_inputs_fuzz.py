"""Property tests of the inputs added for issues 11-13 that are not messages (those are in
test_decode_boundary): path parameters, namespaces, the overrides parameter, the graph's secret
file, numeric command-line options, checkpoint files and the robot's answer to
ALSystem.systemVersion; for issue 14 the record_spool parameter and --record-from. Each either accepts a valid value or refuses it with its own error type;
nothing else escapes."""

from __future__ import annotations

import argparse
import copy
import json
import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from homeo_decision.agent import DecisionCore
from homeo_decision.checkpoint import CheckpointError, decision_checkpoint, load, restore_decision
from homeo_decision.node_runtime import load_node_scenario, overrides_param
from homeo_decision.scenario import ScenarioError
from homeo_launch.processes import check_namespace
from homeo_msgs_py.auth import ENV, AuthError, load_signer
from homeo_msgs_py.cli_args import int_at_least
from homeo_msgs_py.data_dir import OutsideDataDir, resolve
from homeo_msgs_py.node_base import NodeConfigError
from pepper_bridge.mapping import emotion_scale

SCALARS = (st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=30)
           | st.sampled_from(["", ".", "..", "/", "\0", "~", "2.5", "2.4.3", "a=1", "=", "initial_q=0.5"]))
JSON = st.recursive(SCALARS, lambda inner: st.lists(inner, max_size=3)
                    | st.dictionaries(st.text(max_size=8), inner, max_size=3), max_leaves=10)
pytestmark = pytest.mark.filterwarnings("ignore::hypothesis.errors.HypothesisWarning")  # a large drawn value
FAST = settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                         HealthCheck.function_scoped_fixture])


@FAST
@given(path=st.text(max_size=40) | st.sampled_from(["../x", "a/../../x", "/etc/passwd", "link/x", "sub/x", "~/x"]),
       trusted=st.booleans())
@example(path="/\n", trusted=False)  # found by CI: the refusal's reason was two lines
def test_a_path_parameter_resolves_inside_the_data_dir_or_is_refused(tmp_path, path, trusted):
    """A path set while the node runs (over the network) lies inside the data directory or is refused;
    one the node started with (``trusted``: the user's command line) may lie anywhere, a relative one
    under the data directory."""
    base = tmp_path / "out"
    (base / "sub").mkdir(parents=True, exist_ok=True)
    if not (base / "link").exists():
        (base / "link").symlink_to(tmp_path)
    try:
        full = resolve(str(base), path, "q_table_path", trusted)
    except OutsideDataDir as exc:
        assert "\n" not in str(exc) and (not trusted or "\0" in path)
        return
    real = os.path.realpath(base)
    if not path:
        assert full == ""
    elif trusted:
        assert full == os.path.realpath(os.path.join(real, os.path.expanduser(path)))
    else:
        assert os.path.commonpath([real, full]) == real and full != real


@FAST
@given(ns=st.text(max_size=20))
def test_a_namespace_is_a_ros_name_or_refused(ns):
    try:
        out = check_namespace(ns)
    except ValueError:
        return
    assert out == "" or (out.startswith("/") and "//" not in out and out.rstrip("/") == out)
    assert check_namespace(out) == out  # normalised once and for all


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(items=st.lists(SCALARS, max_size=4))
def test_the_overrides_parameter_builds_a_scenario_or_is_refused(items):
    try:
        load_node_scenario("", items)
    except (NodeConfigError, ScenarioError) as exc:
        assert "\n" not in str(exc)


def test_overrides_round_trip_through_the_parameter():
    ov = {"initial_q": 0.5, "always_valid_actions": ["Rest", "Chat"], "serving_growth": "unsatisfied"}
    sc = load_node_scenario("", overrides_param(ov))
    assert sc.open.initial_q == 0.5 and list(sc.open.always_valid_actions) == ["Rest", "Chat"]
    assert overrides_param({}) == [""]


@FAST
@given(content=st.binary(max_size=80), mode=st.sampled_from([0o600, 0o644, 0o640, 0o400]))
def test_the_secret_file_is_a_signer_or_a_one_line_error(tmp_path, content, mode):
    f = tmp_path / "graph.key"
    if f.exists():
        os.chmod(f, 0o600)
    f.write_bytes(content)
    os.chmod(f, mode)
    try:
        signer = load_signer({ENV: str(f)})
    except AuthError as exc:
        assert "\n" not in str(exc)
        return
    assert mode & 0o077 == 0 and signer is not None  # a file others can read is never accepted


@FAST
@given(text=st.text(max_size=40) | st.integers().map(str))
def test_numeric_options_are_in_range_or_refused(text):
    conv = int_at_least(0, 2**31 - 1)
    try:
        v = conv(text)
    except argparse.ArgumentTypeError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 400  # the value is cut to 32 characters
        return
    assert 0 <= v <= 2**31 - 1


@pytest.fixture(scope="module")
def trained(thesis):
    core = DecisionCore(thesis, 3)
    for _ in range(30):  # some draws, so the stream's state is not the initial one
        core.rng.random()
    return core, decision_checkpoint(core, 30, 0)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_a_checkpoint_with_any_field_changed_restores_whole_or_not_at_all(thesis, trained, data, tmp_path):
    """As the node reads one: the file (checkpoint.load), then the restore."""
    _, ck = trained
    bad = _mutate(data, ck, ["params", "rng", "state", "state.tables", "state.objects", "ticks", "tick_offset",
                             "version"])
    core = DecisionCore(thesis, 1)
    before = (json.dumps(core.q.q), core.seed, core.dod, core.rng.state())
    f = tmp_path / "homeo_decision.json"
    f.write_text(json.dumps(bad))
    try:
        restore_decision(core, load(f, "homeo_decision"), "f", params=True)
    except CheckpointError as exc:
        assert "\n" not in str(exc)
        assert (json.dumps(core.q.q), core.seed, core.dod, core.rng.state()) == before


@FAST
@given(value=JSON)
def test_any_answer_to_system_version_has_a_scale_or_is_refused(value):
    """ALSystem.systemVersion returns a string such as "2.5.5.5" (NAOqi SDK ALSystemProxy: "running
    system version"); the bridge refuses anything else with the default scale (bridge._ask_version)."""
    try:
        scale = emotion_scale(value)
    except (ValueError, TypeError):
        return
    from pepper_bridge.mapping import EMOTION_SCALES

    assert scale == EMOTION_SCALES[".".join(str(value).strip().split(".")[:2])]


# -- the world's and the drives node's checkpoints (issue 12, the world node restarted) ----------------
@pytest.fixture(scope="module")
def world_ck(thesis):
    """The world node's checkpoint of a simulation after 20 ticks (its streams drawn from), as the file holds it."""
    from test_world_checkpoint import world_at_tick_20

    return world_at_tick_20(thesis, 5)


def _mutate(data, ck: dict, places) -> dict:
    bad = copy.deepcopy(ck)
    where = data.draw(st.sampled_from(places))
    target = bad
    *path, last = where.split(".")
    for p in path:
        target = target[p]
    if isinstance(target.get(last), dict) and target[last] and data.draw(st.booleans()):
        inner = data.draw(st.sampled_from(sorted(target[last])))
        target[last][inner] = data.draw(JSON)
    elif isinstance(target.get(last), list) and target[last] and data.draw(st.booleans()):
        target[last][data.draw(st.integers(0, len(target[last]) - 1))] = data.draw(JSON)
    else:
        target[last] = data.draw(JSON)
    return bad


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_a_world_checkpoint_with_any_field_changed_restores_whole_or_not_at_all(thesis, world_ck, data, tmp_path):
    from test_world_checkpoint import sim_host

    bad = _mutate(data, world_ck, ["params", "rng", "rng.human", "rng.observation", "state", "state.world",
                                   "state.world.env", "state.world.env.human", "state.world.metrics",
                                   "state.world.accuracy", "state.world.pending", "state.position",
                                   "state.position.outcome", "ticks", "run"])
    host = sim_host(thesis, 1, lambda *a: None, 40)
    side = host.world

    def now():
        return json.dumps([side.state(), host.driver.position(), host.driver.iterations])

    before = now()
    f = tmp_path / "homeo_world.json"
    f.write_text(json.dumps(bad))
    try:
        host.restore(load(f, "homeo_world"), "f")
    except CheckpointError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 2000
        assert now() == before


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_a_drives_checkpoint_with_any_field_changed_restores_whole_or_not_at_all(thesis, data, tmp_path):
    from homeo_decision.checkpoint import SlotWriter, drives_checkpoint, drives_learned, restore_drives
    from homeo_decision.hosts import PerceptionHost
    from test_checkpoint import _drives_answer

    src = PerceptionHost(thesis)
    ck = json.loads(json.dumps(drives_checkpoint(src.perception, 0, 7, _drives_answer(thesis, src))))
    bad = _mutate(data, ck, ["state", "state.values", "state.answer", "state.answer.drives", "state.after_action",
                             "ticks", "run"])
    host = PerceptionHost(thesis)
    before = json.dumps([drives_learned(host.perception), host.stage.join.expected])
    f = tmp_path / "homeo_drives.slots"
    f.unlink(missing_ok=True)
    try:
        SlotWriter(f).write(bad)
    except CheckpointError:
        return  # too big for a slot: the writer refuses it (one line)
    try:
        restore_drives(host, load(f, "homeo_drives"), "f")
    except CheckpointError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 2000
        assert json.dumps([drives_learned(host.perception), host.stage.join.expected]) == before


@FAST
@given(content=st.binary(max_size=200), at=st.integers(0, 2 * 8192))
def test_any_slot_file_loads_or_is_a_one_line_error(tmp_path, content, at):
    from homeo_decision.checkpoint import load

    f = tmp_path / "homeo_drives.slots"
    f.write_bytes(b" " * at + content)
    try:
        load(f, "homeo_drives")
    except CheckpointError as exc:
        assert "\n" not in str(exc)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_a_bridge_checkpoint_with_any_field_changed_restores_whole_or_not_at_all(thesis, pepper_host, data, tmp_path):
    """The Pepper world as the node builds it (not connected: restoring touches no robot)."""
    from homeo_decision import codec
    from homeo_decision.environment import Outcome

    host = pepper_host
    w = host.world
    w.env.tick = 3
    w.log = [{"interaction": k, "action": "Chat", "ok": True, "missed": False, "feedback": 0, "proposal": None,
              "m_dom": "Social", "intention": None, "reason": None, "cue_intention": None} for k in (1, 2, 3)]
    host.driver.rejoin(0, 3, 0, 1.5, (2, codec.outcome_fields(thesis, Outcome(None, 0, None, None, None))))
    ck = json.loads(json.dumps(host.checkpoint()))
    bad = _mutate(data, ck, ["params", "state", "state.world", "state.world.log", "state.position",
                             "state.position.outcome", "state.world.interactions_done", "ticks"])
    w.log, w.env.tick = [], 0
    host.driver.restart()
    f = tmp_path / "homeo_world.json"
    f.write_text(json.dumps(bad))  # Infinity and NaN too, as a hostile file may hold them
    try:
        host.restore(load(f, "homeo_world"), "f")
    except CheckpointError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 2000
        assert w.log == [] and w.env.tick == 0 and host.driver.tick == 0


@pytest.fixture(scope="module")
def pepper_host(thesis):
    """One Pepper world for every example (its link to a port where no robot listens retries in the
    background; a qi session per example would only slow the test down)."""
    from homeo_decision.world_host import WorldHost
    from pepper_bridge.world_backend import PepperWorld

    values = {s.name: s.default for s in PepperWorld.PARAMS}
    values["qi_url"] = "tcp://127.0.0.1:1"
    world = PepperWorld(thesis, values)
    yield WorldHost(world, lambda *a: None, iterations=10)
    world.close()


@FAST
@given(path=st.text(max_size=30) | st.sampled_from(["", ".", "/", "/proc/x/y", "no/such/dir/f.json", "ok.json"]))
def test_the_soak_samples_file_is_writable_or_a_one_line_refusal(tmp_path, path):
    from homeo_ops.soak import check_samples_file
    from homeo_msgs_py.cli_args import UserError

    full = os.path.join(str(tmp_path), path) if path and not path.startswith("/") else path
    try:
        check_samples_file(full or ".")
    except UserError as exc:
        assert "\n" not in str(exc) and str(exc).startswith("--samples")
        return
    assert not os.path.isdir(full) and os.access(os.path.dirname(os.path.abspath(full)), os.W_OK)


def _joint_search():
    """``tools/joint_search.py`` (a tool, not a package; it imports no Optuna until a search runs)."""
    import importlib
    import sys

    tools = str(Path(__file__).resolve().parents[1] / "tools")
    if tools not in sys.path:
        sys.path.insert(0, tools)
    return importlib.import_module("joint_search")


@FAST
@given(lines=st.lists(st.text(max_size=40) | JSON.map(json.dumps), max_size=4))
def test_a_trials_file_of_an_earlier_search_is_read_or_a_one_line_refusal(tmp_path, lines):
    """``tools/calibrate.py --joint --resume-from / --confirm-from`` (our own JSON-lines format, written
    by ``joint_search.run``): any content is trials or one line and exit 2, never a traceback."""
    joint_search = _joint_search()
    f = tmp_path / "trials.jsonl"
    f.write_text("\n".join(lines), encoding="utf-8", errors="surrogatepass")
    try:
        got = joint_search.read_trials(str(f))
    except joint_search.TrialsFileError as exc:
        assert "\n" not in str(exc) and str(exc).startswith(str(f))
        return
    assert all(isinstance(e["open"], dict) and isinstance(e["score"], float) for e in got)


def test_the_trials_files_in_the_repo_are_read_whole():
    joint_search = _joint_search()
    docs = Path(__file__).resolve().parents[1] / "docs" / "calibration"
    assert len(joint_search.read_trials(f"{docs / 'joint-trials.jsonl'},{docs / 'joint-trials-2.jsonl'}")) == 256


# -- issue 14: recording at the writers ------------------------------------------------------------
@FAST
@given(folder=st.text(max_size=40) | st.sampled_from(["../x", "{elsewhere}", "spool", "spool/../spool", "file", "gone",
                                                     "\0"]))
def test_the_record_spool_parameter_opens_a_spool_or_is_refused(tmp_path, folder):
    """The spool folder is set when the node starts (by its launcher): any existing folder will do,
    a relative one under the data directory, ``~`` the user's home; anything else is one line."""
    from homeo_msgs_py.node_base import open_spool

    base = tmp_path / "out"
    (base / "spool").mkdir(parents=True, exist_ok=True)
    (base / "file").write_text("")
    (tmp_path / "elsewhere").mkdir(exist_ok=True)
    folder = folder.replace("{elsewhere}", str(tmp_path / "elsewhere"))
    try:
        w = open_spool(str(base), folder, "homeo_drives")
    except NodeConfigError as exc:
        assert str(exc) and "\n" not in str(exc)
        return
    if not folder:
        assert w is None
        return
    try:
        want = os.path.realpath(os.path.join(base, os.path.expanduser(folder)))
        assert w.path.parent == Path(want) and w.path.parent.is_dir()
    finally:
        w.close()
        w.path.unlink()


@FAST
@given(value=st.text(max_size=20), command=st.sampled_from(["sim", "pepper", "bench"]))
def test_record_from_is_writers_or_tap_or_refused(value, command):
    from homeo_launch.cli import build_parser
    from homeo_msgs_py.cli_args import UserError

    try:
        a = build_parser().parse_args([command, "--record-from", value])
    except UserError as exc:  # main prints it on one line, exit 2
        assert "--record-from" in str(exc) and "\n" not in str(exc) and value not in ("writers", "tap")
        return
    assert a.record_from == value in ("writers", "tap")


@settings(max_examples=300, deadline=None)
@example(argv=["sim", "\n"])
@given(argv=st.lists(st.sampled_from(["sim", "pepper", "bench", "recover", "soak", "--iterations", "--data-dir"])
                     | st.text(max_size=10), max_size=4))
def test_any_launcher_command_line_parses_or_is_one_line_error(argv):
    """The shared parser (cli_args.Parser): whatever is typed, a namespace or one line, even when the
    text it quotes back holds a line break."""
    from homeo_launch.cli import build_parser
    from homeo_msgs_py.cli_args import UserError

    try:
        build_parser().parse_args(argv)
    except UserError as exc:
        assert "\n" not in str(exc) and "\r" not in str(exc)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.one_of(st.just(None), st.text(max_size=20), st.integers(), st.lists(st.integers(), max_size=2)))
def test_a_drives_checkpoint_of_other_world_codes_is_refused_in_one_line_and_changes_nothing(thesis, saved):
    """A checkpoint written before the world code held the relation (no ``world_codes``) or of another
    numbering: its prev_code would name another world, so it is refused before anything changes."""
    from homeo_decision import checkpoint
    from homeo_decision.hosts import PerceptionHost
    from test_checkpoint import _drives_answer

    host = PerceptionHost(thesis)
    ck = json.loads(json.dumps(checkpoint.drives_checkpoint(host.perception, 0, 0, _drives_answer(thesis, host))))
    if saved is None:
        del ck["state"]["world_codes"]  # as every checkpoint written before issue 22
    else:
        ck["state"]["world_codes"] = saved
    fresh = PerceptionHost(thesis)
    before = checkpoint.drives_learned(fresh.perception)
    with pytest.raises(CheckpointError, match="world codes this program would misread") as e:
        checkpoint.restore_drives(fresh, ck, "f")
    assert "\n" not in str(e.value) and str(e.value).startswith("f: ")
    assert checkpoint.drives_learned(fresh.perception) == before


# -- issues 22-23: a day script, the launch files' arguments -----------------------------------------
DAY_KEYS = st.sampled_from(["schema", "version", "repeat", "moments", "description", "ticks", "wish", "present", "x"])
DAY = st.recursive(SCALARS | st.sampled_from(["homeo-day", "music", "none", 1, 30]), lambda inner: st.lists(
    inner, max_size=4) | st.dictionaries(DAY_KEYS, inner, max_size=5), max_leaves=25)


@FAST
@given(raw=DAY | st.builds(lambda m: {"schema": "homeo-day", "version": 1, "moments": m}, DAY))
def test_any_day_script_is_a_day_or_a_one_line_refusal(thesis, raw):
    from homeo_sim.day import DayScriptError, check_day

    try:
        day = check_day(raw, thesis, "day.json")
    except DayScriptError as exc:
        assert str(exc).startswith("day.json") and "\n" not in str(exc)
        return
    assert day["moments"] and all(1 <= t <= 10**6 and 0 <= w < len(thesis.intention_names) and type(p) is bool
                                  for t, w, p in day["moments"])


@FAST
@given(args=st.fixed_dictionaries({k: st.text(max_size=12) | st.sampled_from(["", "0", "1.5", "-1", "true", "nan",
                                                                                "1e9", "bayes", "person"])
                                   for k in ("seed", "iterations", "rate", "dod", "xi", "human", "human_timeout",
                                             "max_restarts", "checkpoints", "json", "intention")}))
def test_any_launch_argument_is_taken_or_refused_in_one_line(args):
    """``ros2 launch homeo_robot sim.launch.py NAME:=TEXT``: each argument by the declaration of what it sets."""
    from homeo_launch.ros_launch import LaunchArgError, values

    given = dict(args, namespace="", data_dir="out", record="", params_file="", scenario="", load_q="", save_q="",
                 trace="")
    try:
        v = values(given, "sim")
    except LaunchArgError as exc:
        assert str(exc).startswith("launch argument") and "\n" not in str(exc)
        return
    assert v["intention"] in ("oracle", "bayes")
    assert v["seed"] == "" or (type(v["seed"]) is int and 0 <= v["seed"] <= 2**31 - 1)
    assert v["dod"] == "" or 0.0 <= v["dod"] <= 1.0


# -- homeo-topic's number options: a value in range, or one line ---------------------------------------
@FAST
@given(cmd=st.sampled_from([("list", "--wait"), ("echo", "--count"), ("echo", "--timeout"), ("pub", "--times"),
                            ("pub", "--rate"), ("pub", "--wait"), ("param", "--wait"), ("call", "--wait")]),
       value=st.text(max_size=12) | st.sampled_from(["nan", "inf", "-inf", "-1", "0", "1e400", "3", "0.5", "3601"]))
@example(cmd=("pub", "--wait"), value="nan")
def test_homeo_topic_number_options_are_in_range_or_one_line(cmd, value):
    """What homeo-topic waits, counts and repeats (hand ranges: a wait in [0, 3600] s, a count >= 0,
    times in [1, 10^6], a rate in [0.001, 10^4]/s) or UserError in one line: never NaN or infinity,
    which would reach rclpy's Duration."""
    import math

    from homeo_topic.cli import build_parser
    from homeo_msgs_py.cli_args import UserError

    sub, opt = cmd
    positional = {"list": [], "echo": ["/homeo/drives"], "pub": ["/homeo/drives", "{}"],
                  "param": ["/homeo_decision", "dod"], "call": ["/homeo_decision/save_q"]}[sub]
    try:
        a = build_parser().parse_args([sub, *positional, f"{opt}={value}"])
    except UserError as exc:
        assert str(exc) and "\n" not in str(exc)
        return
    v = getattr(a, opt[2:])
    assert math.isfinite(v)
    lo, hi = {"--wait": (0, 3600), "--count": (0, math.inf), "--timeout": (0, 1e9), "--times": (1, 10 ** 6),
              "--rate": (1e-3, 1e4)}[opt]
    assert lo <= v <= hi


# -- issue 24: the bench's new options ---------------------------------------------------------------------------
BENCH_FLAGS = ("--compare-checkpoints", "--profile", "--oracle", "--critical-path")


@FAST
@example(flag="--profile", rest=["=1"])
@example(flag="--compare-checkpoints", rest=["--rounds", "x\n"])
@given(flag=st.sampled_from(BENCH_FLAGS),
       rest=st.lists(st.sampled_from(["--json", "--rounds", "--iterations", "2", "on", *BENCH_FLAGS])
                     | st.text(max_size=12), max_size=3))
def test_the_bench_flags_parse_or_are_one_line_errors_exit_2(flag, rest, capsys):
    """A flag takes no value: whatever follows it is another option, or one line and exit 2."""
    from homeo_launch.cli import build_parser, main
    from homeo_msgs_py.cli_args import UserError

    argv = ["bench", flag, *rest]
    try:
        a = build_parser().parse_args(argv)
    except UserError as exc:
        assert "\n" not in str(exc) and "\r" not in str(exc)
        capsys.readouterr()
        assert main(argv) == 2  # the command line's error: no traceback, one line
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "Traceback" not in err
        return
    assert getattr(a, flag[2:].replace("-", "_")) is True


# -- a parameters file (params_file:=, --params-file): rcl's parse, or one line ---------------------------
PARAM_VALUES = st.one_of(st.booleans(), st.integers(-2**40, 2**40), st.floats(allow_nan=False), st.text(max_size=8),
                         st.lists(st.integers(0, 9), min_size=1, max_size=3))
PARAMS_FILES = st.one_of(
    st.text(max_size=60),
    st.dictionaries(st.sampled_from(["homeo_decision", "homeo_world", "/**", "x y"]),
                    st.fixed_dictionaries({"ros__parameters": st.dictionaries(
                        st.sampled_from(["seed", "dod", "xi", "iterations", "a.b", ""]), PARAM_VALUES, max_size=3)}),
                    max_size=2).map(lambda d: __import__("yaml").safe_dump(d)))


@FAST
@given(content=PARAMS_FILES)
@example(content="homeo_decision:\n  ros__parameters:\n    seed: [1, {a: 2}\n")  # the hand case: unclosed
def test_any_params_file_is_taken_by_rcl_or_refused_in_one_line_before_a_node_starts(tmp_path, content, capfd):
    """``ros2 launch homeo_robot sim.launch.py params_file:=FILE``: the file rcl will read in every node,
    judged by rcl's own parser in the launch. A file it refuses is one line naming it, and nothing else
    reaches the terminal (rcl's own "Failed to parse global arguments" log is kept out)."""
    import yaml

    from homeo_launch.ros_launch import LaunchArgError, values

    path = tmp_path / "params.yaml"
    path.write_text(content)
    given = {k: "" for k in ("seed", "iterations", "rate", "dod", "xi", "human", "human_timeout", "namespace",
                             "record", "scenario", "load_q", "save_q", "trace")}
    given.update(intention="oracle", data_dir="out", max_restarts="3", checkpoints="true", json="false",
                 params_file=str(path))
    capfd.readouterr()
    try:
        values(given, "sim")
    except LaunchArgError as exc:
        assert str(exc).startswith("launch argument params_file: ") and "\n" not in str(exc), exc
        assert str(path) in str(exc)
        assert capfd.readouterr().err == ""
        return
    try:  # rcl took it: YAML (PyYAML, a second reader, reads it too; raises if not)
        yaml.safe_load(content)
    except yaml.scanner.ScannerError as exc:  # pure-Python PyYAML refuses a tab YAML allows as separation, its C
        if "'\\t'" not in str(exc):  # loader does not (yaml/pyyaml#594, #306): that reading, for that case only
            raise
        yaml.load(content, Loader=yaml.CSafeLoader)


def test_params_files_by_hand(tmp_path):
    """The shipped config/params.yaml is taken; a missing file, a folder and an unclosed list are refused."""
    from homeo_msgs_py.node_base import ros_args_refusal

    repo = Path(__file__).resolve().parents[1]
    assert ros_args_refusal(["--ros-args", "--params-file", str(repo / "config" / "params.yaml")]) is None
    (tmp_path / "bad.yaml").write_text("homeo_decision:\n  ros__parameters:\n    seed: [1, {a: 2}\n")
    for path, why in ((tmp_path / "gone.yaml", "Error opening YAML file"), (tmp_path / "bad.yaml", "near line 3")):
        refusal = ros_args_refusal(["--ros-args", "--params-file", str(path)])
        assert refusal is not None and why in refusal and str(path) in refusal and ", at /" not in refusal, refusal


def test_a_node_given_a_params_file_rcl_refuses_says_so_in_one_line_exit_2(tmp_path):
    """``ros2 run homeo_robot homeo-decision-node --ros-args --params-file FILE``: no traceback."""
    import subprocess
    import sys

    bad = tmp_path / "bad.yaml"
    bad.write_text("homeo_decision:\n  ros__parameters:\n    seed: [1, {a: 2}\n")
    r = subprocess.run([sys.executable, "-m", "homeo_decision.node", "--ros-args", "--params-file", str(bad)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2, r.stderr
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("error: Couldn't parse params file"), r.stderr


@FAST
@given(value=SCALARS | st.sampled_from(["events", "single", "Events", " single", "events\n"]))
def test_the_executor_is_events_or_single_or_refused_in_one_line(value):
    """The executor parameter (issue 29), from a parameter file or a launch argument (checked) or the command
    line (parsed): one of its two names, as given, or a ValueError of one line."""
    from homeo_msgs_py.node_base import EXECUTOR

    for take in ((EXECUTOR.check,) + ((EXECUTOR.parse,) if isinstance(value, str) else ())):
        try:
            got = take(value)
        except ValueError as exc:
            assert value not in ("events", "single") and str(exc).count("\n") == 0, exc
        else:
            assert got == value and got in ("events", "single"), got


@FAST
@given(value=st.text(max_size=10) | st.sampled_from(["events", "single"]))
def test_the_launcher_s_executor_flag_parses_or_is_one_line(value):
    from homeo_launch.cli import build_parser
    from homeo_msgs_py.cli_args import UserError

    try:
        a = build_parser().parse_args(["sim", "--executor", value])
    except UserError as exc:
        assert value not in ("events", "single") and "\n" not in str(exc), exc
    else:
        assert a.executor == value in ("events", "single")
