"""The world contract: everything a robot (or a simulated world) gives the graph, in one class (no rclpy).

:class:`WorldBackend` is the contract. The one world node (``world_node``) hosts any subclass through
``world_host.WorldHost`` (the lockstep, the trace, the run status, the run's checkpoint, written once);
the front ends (``homeo-launch NAME``, ``ros2 launch homeo_robot world.launch.py world:=NAME``,
``homeo-launch watch``) read its declarations and class methods, never its name; and
``world_check.check_world`` holds it to the rules below, as Gymnasium's ``check_env`` does.

Worlds are found through one registry, the entry-point group ``homeo_robot.worlds`` (name ->
``module:Class``): the simulation (``sim``), the Pepper (``pepper``) and a scripted day (``day``) ship
with the project; another robot is a package that registers its own (docs/ARCHITECTURE.md, "Adding a
robot").
"""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, field

from homeo_msgs_py.graph import BAYES, ORACLE, SEED_MAX, TICKS_MAX
from homeo_msgs_py.params import ParamSpec

from . import codec
from .environment import Observation
from .scenario import NONE_INTENTION, Scenario

GROUP = "homeo_robot.worlds"
DISTRIBUTION = "homeo-robot"  # the worlds this project ships: those its own distribution registers

# The world node's own parameters, whatever the world (a world adds its own: ``WorldBackend.PARAMS``).
SEED = ParamSpec("seed", 0, "seed of the world's random streams (takes effect at the next ~/reset)", 0, SEED_MAX)
ITERATIONS = ParamSpec("iterations", 5000, "ticks per run (0 = until stopped)", 0, TICKS_MAX)
RATE = ParamSpec("rate", 0.0, "ticks per second (0 = as fast as the lockstep and the world allow)", 0.0, 1000.0)
ACTION_TIMEOUT = ParamSpec("action_timeout", 5.0, "seconds to wait for an action before the tick counts as no "
                           "action", 0.01, 3600.0)
WORLD_PARAMS = (
    ParamSpec("world", "sim", "the world the node hosts: a name of the homeo_robot.worlds registry", fixed=True),
    SEED, ITERATIONS, RATE, ACTION_TIMEOUT,
    ParamSpec("trace_path", "", "write one JSON line per tick here, in data_dir ('' = no trace; takes effect at "
              "the next ~/reset)"),
    ParamSpec("wait_for_readers", True, "start only when the graph's readers and writers have matched"),
    ParamSpec("intention_learns", False, "the intention node learns from each outcome (its bayes mode): the start "
              "gate waits for its reader too, and a world that knows the human's intention scores the recognised "
              "one", fixed=True),
)


class WorldConfigError(ValueError):
    """A world cannot start as configured (a bad parameter, an unreadable file, a robot out of reach): one line."""


@dataclass
class Companion:
    """A process a launch starts beside the graph and stops after it (a stand-in robot on loopback)."""

    name: str
    argv: list


@dataclass
class LaunchPlan:
    """What a front end starts for one launch of a world (``WorldBackend.plan``)."""

    params: dict  # the world node's parameters: the world's own, given or derived
    overrides: dict = field(default_factory=dict)  # open choices of the scenario the world sets (initial drives)
    scenario: str | None = None  # a scenario file the nodes load instead of the given one
    companions: tuple = ()  # Companion processes
    inputs: tuple = ()  # graph topics (keys) the world reads from outside: a live view may publish them
    bounded: bool | None = None  # the run ends by itself (None: when it has a tick count); Ctrl-C then exits 130


class WorldBackend:
    """A world as the graph hosts it: the ticks in message fields, and what the graph cannot know about it.

    **A tick.** ``observe(final)`` gives the fields of ``homeo/world`` and ``homeo/observation``; the
    robot's answer comes back as an ``homeo/action`` message (None when none came within
    ``action_timeout``); ``step(action)`` performs it and gives the fields of ``homeo/outcome``. Fields
    are names of the scenario (``homeo_decision.codec``: ``observation_messages``, ``outcome_fields``).
    The default ``observe``/``step`` do this for ``self.env``, an ``environment.Environment`` (``reset`` /
    ``observe`` / ``step`` in the scenario's indices): a subclass either builds ``self.env`` in ``__init__``
    or overrides both. ``observation()`` builds an ``Observation`` from names.

    **The rules** (``world_check`` tests each):

    - every world, observation and outcome is a valid message of the scenario's vocabulary;
    - ``step(None)`` (no action came) does nothing: the outcome's action is None, feedback 0, no proposal;
    - an outcome's action is the action asked, or None when it was not performed (``last_failure`` says
      why; ``last_missed`` when the world could not act at all, which counts the tick as missed);
    - a proposal comes only with a scolding (feedback -1; Sec 3.2.6); feedback is -1, 0 or +1;
    - once ``finished()`` is true after a step, the next tick is the last: the node observes it with
      ``final`` and lets the robot learn from the last outcome; nothing is stepped after it;
    - one seed, one run: two worlds built with one seed answer the same actions with the same messages;
    - ``status`` is valid run-status data; ``poll``, ``diagnostics``, ``devices`` return their documented
      shapes; every call but ``start``/``observe``/``step`` returns at once.

    **Capabilities** (class attributes the world declares; the checker holds it to each):
    ``blocking`` (its lockstep calls wait for the outside world: the node runs them on a worker thread),
    ``KEEPS_STATE`` (``state``/``set_state`` hold the whole world: a restarted node goes on exactly where
    it was; without it a restarted world starts afresh and the run goes on), ``RESETS`` (``reset(seed)``
    starts the same run again; a robot's world goes on), ``SEEDED`` (another seed, another run),
    ``FAILS_STEPS`` (``step_failed`` gives the outcome of a step that raised; without it the node stops),
    ``DROPS_LINK`` (its link to the outside can drop: ``observe`` raises and ``ready`` says why until it is
    back, and the lockstep retries; ``test_double`` gives the checker a way to drop it).

    **The front ends** read the class, not an instance: ``PARAMS`` (node parameters: flags, launch
    arguments, ``ros2 param``), ``LAUNCH`` (options of a launch only), ``TICKS``, ``INTENTIONS``, and
    ``check``, ``plan``, ``log_line``, ``result``, ``result_text``.
    """

    NAME = ""
    PARAMS: tuple = ()  # ParamSpec of the world's own node parameters
    LAUNCH: tuple = ()  # ParamSpec of options a launch takes for this world (not node parameters)
    TICKS = ("iterations", 5000)  # the launch option that counts ticks, and its default (0 = until stopped)
    INTENTIONS = {BAYES: BAYES, ORACLE: ORACLE}  # --intention values -> the intention node's mode; first = default
    LOG_HEADER = ""  # a world whose run status carries an interaction log (extra.log): the header of log_line

    blocking = False
    KEEPS_STATE = False
    RESETS = True
    SEEDED = False
    FAILS_STEPS = False
    DROPS_LINK = False

    last_missed = False  # the last step could not be performed at all (a robot that was away)
    last_failure: str | None = None  # "ACTION failed: why" when the last step's action was not performed

    def __init__(self, sc: Scenario, values: dict):
        """``values``: every parameter of ``WORLD_PARAMS`` and ``PARAMS``, checked (``seed`` among them).
        Raise ``WorldConfigError`` (one line) for what cannot start: the node exits 2 with it."""
        self.sc, self.values = sc, values

    # -- the lockstep: the node calls these on a worker thread when ``blocking`` ----------------------
    def start(self) -> None:
        """Before tick 0 (a robot waits for its user's first expression)."""

    def observe(self, final: bool) -> tuple[dict, dict]:
        """``homeo/world`` and ``homeo/observation`` fields of the current tick (``final``: the last)."""
        return codec.observation_messages(self.sc, self.env.observe(), final)

    def step(self, action_fields: dict | None) -> dict:
        """Perform the tick's action (None: none came); the ``homeo/outcome`` fields. An ``Outcome``'s
        ``failure`` (why the action asked was not performed) becomes ``last_failure``."""
        name = action_fields.get("action") if action_fields is not None else None
        out = self.env.step(self.sc.action_index(name) if name is not None else None)
        self.last_failure = f"{name} failed: {out.failure}" if out.failure and name is not None else None
        return codec.outcome_fields(self.sc, out)

    def step_failed(self, action_fields: dict | None, reason: str) -> dict:
        """The outcome fields when ``step`` raised (``FAILS_STEPS``); else this raises again."""
        raise RuntimeError(f"the {self.NAME or 'world'} failed to step: {reason}")

    def observation(self, location: str, relation: str, objects: dict | None = None, body: dict | None = None,
                    intention: str | None = None, cues: dict | None = None) -> Observation:
        """An ``Observation`` from names: the robot's ``location``, the human's ``relation`` (near, far,
        absent: Eq 3.9), ``{object: {variable: value}}`` (each variable left out: its first value), the
        body drives' readings ``{drive: 0..100}``, the human's true intention (None: not known) and
        the cues ``{gesture|movement|keyword: symbol}`` (None: not observed)."""
        sc = self.sc
        values = {"robot.location": location, "human.relation": relation, "intention": NONE_INTENTION}
        for o, spec in sc.objects.items():
            for var, vals in spec["variables"].items():
                values[f"{o}.{var}"] = (objects or {}).get(o, {}).get(var, vals[0])
        return Observation(sc.encode(values), codec.body_vector(sc, body or {}),
                           sc.intention_names.index(intention) if intention is not None else None, cues)

    # -- the node's thread: each returns at once ------------------------------------------------------
    def check_action(self, fields: dict, tick: int) -> None:
        """Raise ``homeo_msgs_py.schemas.Rejected`` for an action message this world cannot use."""

    def record(self, action_fields: dict | None) -> None:
        """The robot's drives after the last tick came back with this action message (metrics)."""

    def status(self, done: bool) -> dict:
        """Extra ``homeo/run_status`` fields: ``metrics`` (numbers) and ``extra`` (an object; ``log``: the
        interaction log a robot keeps)."""
        return {}

    def reset(self, seed: int | None) -> None:
        """A new run from tick 0 (the node's ~/reset; None: the world's own seed)."""
        self.env.reset(seed)

    def ready(self) -> list[str]:
        """What the world still waits for before tick 0, one line each (a robot that is not connected)."""
        return []

    def finished(self) -> bool:
        """The world has no more ticks to give (a scripted user is done): the next one is the last."""
        return False

    def set_param(self, name: str, value) -> str | None:
        """A live change of one of ``PARAMS`` (checked by its declaration); a reason to refuse it, or None."""
        return None

    def poll(self) -> list[tuple[str, str]]:
        """Notices to log, ``(level, text)`` with level info, warning or burst (a warning that may come many
        times a second: logged once a second); any notice also sends the node's diagnostics at once."""
        return []

    def diagnostics(self) -> list[dict]:
        """More DiagnosticStatus dicts (name, hardware_id, level 0-3, message, values: {str: str})."""
        return []

    def devices(self) -> list[dict]:
        """Device commands since the last call: ``homeo/device`` fields with their tick
        (``{"device", "command", "action", "tick"}``)."""
        return []

    def inputs(self) -> dict:
        """Topics from outside the graph this world reads (keys of ``graph.NodeDesc.external``): key ->
        handler of the message's text (raises ``Rejected`` for a bad one)."""
        return {}

    def close(self) -> None:
        """The node stops: end any wait in progress, let go of the robot."""

    # -- the run's checkpoint (world_host.WorldHost writes the envelope) -------------------------------
    def run_config(self) -> dict:
        """What a restarted node must share with the checkpoint it goes on from (else it is refused)."""
        return {}

    def state(self) -> tuple[dict | None, dict]:
        """``(random streams, state)`` as JSON data: where the world stands (``KEEPS_STATE``: all of it)."""
        return None, {}

    def set_state(self, rng, state: dict, tick: int) -> None:
        """Go on from ``state()`` at ``tick``; ValueError (one line) for anything else, changing nothing. A
        state that holds the world holds the tick it was taken at (a world counts its own steps), and one
        of another tick than ``tick`` is refused."""
        if state:
            raise ValueError("this world keeps no state")

    def rejoin(self, tick: int, lost: int, step_lost) -> dict | None:
        """The node was down and goes on at ``tick``; ``lost`` ticks since its checkpoint were never seen.
        The outcome fields of ``tick - 1`` to send first, or None: the checkpoint's. A world whose time
        went on meanwhile steps the lost ticks with ``step_lost()`` (one tick without an action, traced)."""
        return None

    # -- the front ends (class methods: they run in the launcher, not in the node) ---------------------
    @classmethod
    def check(cls, sc: Scenario, values: dict) -> None:
        """The node parameters checked before any node starts: WorldConfigError (one line) for what the
        node would refuse, e.g. a file that does not load."""

    @classmethod
    def plan(cls, sc: Scenario, given: dict, workdir: str) -> LaunchPlan:
        """One launch: ``given`` holds ``PARAMS`` and ``LAUNCH`` by name (None: not given), ``intention``,
        ``load_q`` and ``seed``; ``workdir`` is the launch's own folder. WorldConfigError (one line) for
        what cannot start."""
        return LaunchPlan({s.name: given[s.name] for s in cls.PARAMS if given.get(s.name) is not None})

    @classmethod
    def log_line(cls, row: dict) -> str:
        """A row of the run status's interaction log as the front ends print it while the run goes."""
        return str(row)

    @classmethod
    def result(cls, sc: Scenario, status: dict, setting: dict) -> dict:
        """The run's result as JSON data (``--json``), from its last run status. ``setting``: ``seed``,
        ``iterations``, ``intention``, ``learning`` (given), ``values`` (the plan's parameters and the
        launch's options) and ``interrupted``."""
        return {"ticks": run_ticks(status, setting), "missed": status.get("missed", 0)}

    @classmethod
    def result_text(cls, sc: Scenario, result: dict, setting: dict) -> str:
        """``result`` as the text a person reads."""
        return f"{result['ticks']} ticks, {result['missed']} missed"

    @classmethod
    @contextmanager
    def test_double(cls, sc: Scenario, values: dict):
        """For the checker: the outside world this world reaches, stood in for (a robot on loopback).
        Yields the values to build the world with and a callable ``drop(seconds)`` that cuts its link
        (None: nothing to drop)."""
        yield values, None


def run_ticks(status: dict, setting: dict) -> int:
    """The ticks a run took: its own count, or the ones asked when the status has none."""
    return (status.get("extra") or {}).get("ticks", status.get("tick", setting.get("iterations", 0)))


def registered(ours: bool = False) -> dict:
    """Registry name -> entry point, for every world installed (``ours``: the project's own)."""
    from importlib.metadata import entry_points

    return {ep.name: ep for ep in entry_points(group=GROUP)
            if not ours or (ep.dist is not None and ep.dist.name == DISTRIBUTION)}


def world_class(name) -> type[WorldBackend]:
    """The backend class registered as ``name`` (or ``name`` itself, a class); WorldConfigError (one line)."""
    if isinstance(name, type):
        cls = name
    else:
        eps = registered()
        if name not in eps:
            raise WorldConfigError(f"no world {name!r}; registered ({GROUP}): {', '.join(sorted(eps)) or 'none'}")
        try:
            cls = eps[name].load()
        except Exception as exc:  # noqa: BLE001 - another package's import: whatever it raises, one line
            raise WorldConfigError(f"world {name!r} ({eps[name].value}) does not load: {exc}") from None
    if not (isinstance(cls, type) and issubclass(cls, WorldBackend)):
        raise WorldConfigError(f"world {name!r} is not a WorldBackend")
    return cls


def tables() -> str:
    """The world node's parameters and each shipped world's own, as docs/ARCHITECTURE.md shows them."""
    from homeo_msgs_py.params import markdown_table

    out = ["The world node's own (every world):", "", markdown_table(WORLD_PARAMS)]
    for name in sorted(registered(ours=True)):
        cls = world_class(name)
        out += ["", f"`{name}` (`{cls.__module__}.{cls.__name__}`):", "",
                markdown_table(cls.PARAMS) if cls.PARAMS else "(none of its own)"]
        if cls.LAUNCH:
            out += ["", "its launch options:", "", markdown_table(cls.LAUNCH)]
    return "\n".join(out)


if __name__ == "__main__":  # python -m: the classes must be this module's, not __main__'s
    from homeo_decision import world_api

    print(world_api.tables())
