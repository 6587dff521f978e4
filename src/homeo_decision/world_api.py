"""What a robot (or a simulated world) gives the one world node, and where the node finds it (no rclpy).

A world is an environment behind the boundary (``environment.py``: reset / observe / step) seen in
message fields, plus what the node cannot know about it: its own parameters, whether its calls
block, what it still waits for before tick 0, its part of the run's checkpoint, its notices and
diagnostics. :class:`WorldBackend` is that contract with a default for everything a simple world
does not need; ``homeo_decision.world_host.WorldHost`` runs one in lockstep, and
``homeo_decision.world_node`` is the ROS node around the host.

Worlds are found through one registry, the entry-point group ``homeo_robot.worlds`` (name ->
``module:Class``): the simulation (``sim``), the Pepper (``pepper``) and a scripted day (``day``)
ship with the project; another robot is a package that registers its own (docs/ARCHITECTURE.md,
"Adding a robot").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from homeo_msgs_py.graph import SEED_MAX, TICKS_MAX
from homeo_msgs_py.params import ParamSpec

from . import codec
from .scenario import Scenario

GROUP = "homeo_robot.worlds"

# The world node's own parameters, whatever the world (a world adds its own: ``WorldBackend.PARAMS``).
WORLD_PARAMS = (
    ParamSpec("world", "sim", "the world the node hosts: a name of the homeo_robot.worlds registry", fixed=True),
    ParamSpec("seed", 0, "seed of the world's random streams (takes effect at the next ~/reset)", 0, SEED_MAX),
    ParamSpec("iterations", 5000, "ticks per run (0 = until stopped)", 0, TICKS_MAX),
    ParamSpec("rate", 0.0, "ticks per second (0 = as fast as the lockstep and the world allow)", 0.0, 1000.0),
    ParamSpec("action_timeout", 5.0, "seconds to wait for an action before the tick counts as no action",
              0.01, 3600.0),
    ParamSpec("trace_path", "", "write one JSON line per tick here, in data_dir ('' = no trace; takes effect at "
              "the next ~/reset)"),
    ParamSpec("wait_for_readers", True, "start only when the graph's readers and writers have matched"),
    ParamSpec("intention_learns", False, "the intention node learns from each outcome (its bayes mode): the start "
              "gate waits for its reader too, and a world that knows the human's intention scores the recognised "
              "one", fixed=True),
)


class WorldConfigError(ValueError):
    """A world cannot start as configured (a bad parameter, an unreadable file): one line."""


@dataclass
class WorldContext:
    """What the node lends a world: its log, its event counter, and where files named by parameters live."""

    log: Callable[[str], None] = lambda text: None
    note: Callable[..., None] = lambda what, n=1: None  # counted events on /diagnostics
    data_path: Callable[[str, str], str] = lambda path, what: path  # raises ValueError outside the data dir


class WorldBackend:
    """A world in message fields (``homeo_decision.codec``), as the world node hosts it.

    Subclasses set ``env`` (an ``environment.Environment``) and may override anything below. The
    lockstep calls (``start``, ``observe``, ``step``) may block when ``blocking`` is true: the node
    runs them on a worker thread, one at a time; everything else runs on the node's thread.
    """

    NAME = ""
    PARAMS: tuple = ()  # ParamSpec of the world's own node parameters
    blocking = False  # observe/step wait for the outside world (a robot, a person)
    last_missed = False  # the last step could not be performed at all (a robot that was away)
    last_failure: str | None = None  # "ACTION failed: why" when the last step's action was not performed

    def __init__(self, sc: Scenario, values: dict, ctx: WorldContext):
        self.sc, self.values, self.ctx = sc, values, ctx

    @classmethod
    def check(cls, sc: Scenario, values: dict) -> None:
        """The world's parameters checked before any node starts (the launcher calls it): a
        WorldConfigError (one line) for what the node would refuse, e.g. a file that does not load."""

    # -- the lockstep (homeo_msgs_py.lockstep.WorldSide) ------------------------------------------
    def start(self) -> None:
        """Before tick 0 (a robot waits for its user's first expression)."""

    def observe(self, final: bool) -> tuple[dict, dict]:
        """``homeo/world`` and ``homeo/observation`` fields of the current tick."""
        return codec.observation_messages(self.sc, self.env.observe(), final)

    def step(self, action_fields: dict | None) -> dict:
        """Perform the tick's action (None: none came); the ``homeo/outcome`` fields."""
        name = action_fields.get("action") if action_fields is not None else None
        return codec.outcome_fields(self.sc, self.env.step(self.sc.action_index(name) if name is not None else None))

    def step_failed(self, action_fields: dict | None, reason: str) -> dict:
        """The outcome fields when ``step`` raised. A world that cannot fail raises again."""
        raise RuntimeError(f"the {self.NAME or 'world'} failed to step: {reason}")

    def check_action(self, fields: dict, tick: int) -> None:
        """Raise ``Rejected`` for an action message this world cannot use."""

    def record(self, action_fields: dict | None) -> None:
        """The robot's drives after the last tick came back with this action message (metrics)."""

    def status(self, done: bool) -> dict:
        """Extra ``homeo/run_status`` fields (``metrics``, ``extra``)."""
        return {}

    # -- the run -----------------------------------------------------------------------------
    def reset(self, seed: int) -> None:
        """A new run from tick 0 (the node's ~/reset)."""
        self.env.reset(seed)

    def ready(self) -> list[str]:
        """What the world still waits for before tick 0 (e.g. a robot that is not connected)."""
        return []

    def finished(self) -> bool:
        """The world has no more ticks to give (a scripted user is done): the next one is the last."""
        return False

    def set_param(self, name: str, value) -> str | None:
        """A live change of one of ``PARAMS`` (checked by its declaration); a reason to refuse it, or None."""
        return None

    def poll(self) -> list[tuple[str, str]]:
        """Called often on the node's thread: notices to log, ``(level, text)`` with level info,
        warning or burst (a warning that may come many times a second: logged once a second); any
        notice also sends the node's diagnostics at once."""
        return []

    def diagnostics(self) -> list[dict]:
        """More DiagnosticStatus dicts (level, name, message, hardware_id, values)."""
        return []

    def devices(self) -> list[dict]:
        """Device commands since the last call: ``homeo/device`` fields with the tick they belong to
        (``{"device", "command", "action", "tick"}``)."""
        return []

    def inputs(self) -> dict:
        """Topics from outside the graph this world reads (keys of ``graph.NodeDesc.external``):
        key -> handler of the message's text (raises ``Rejected`` for a bad one)."""
        return {}

    def close(self) -> None:
        """The node stops: end any wait in progress, let go of the robot."""

    # -- the run's checkpoint (world_host.WorldHost writes the envelope) ----------------------
    def run_config(self) -> dict:
        """What a restarted node must share with the checkpoint it goes on from (else it is refused)."""
        return {}

    def state(self) -> tuple[dict | None, dict]:
        """``(random streams, state)`` as JSON-able data: where the world stands now."""
        return None, {}

    def set_state(self, rng, state: dict, tick: int) -> None:
        """Go on from ``state()`` at ``tick``; ValueError (one line) for anything else, changing nothing."""
        if state:
            raise ValueError("this world keeps no state")

    def rejoin(self, tick: int, lost: int, step_lost: Callable[[], dict]) -> dict | None:
        """The node was down and goes on at ``tick``; ``lost`` ticks since its checkpoint were never
        seen. The outcome fields of ``tick - 1`` to send first, or None: the checkpoint's. A world
        whose time went on meanwhile steps the lost ticks with ``step_lost()`` (one tick without an
        action, traced; its outcome fields)."""
        return None


def registered() -> dict:
    """Registry name -> entry point, for every world installed."""
    from importlib.metadata import entry_points

    return {ep.name: ep for ep in entry_points(group=GROUP)}


def world_class(name: str) -> type[WorldBackend]:
    """The backend class registered as ``name``; WorldConfigError (one line) when there is none."""
    eps = registered()
    if name not in eps:
        raise WorldConfigError(f"no world {name!r}; registered ({GROUP}): {', '.join(sorted(eps)) or 'none'}")
    cls = eps[name].load()
    if not (isinstance(cls, type) and issubclass(cls, WorldBackend)):
        raise WorldConfigError(f"world {name!r} ({eps[name].value}) is not a WorldBackend")
    return cls


def tables() -> str:
    """The world node's parameters and each registered world's own, as docs/ARCHITECTURE.md shows them."""
    from homeo_msgs_py.params import markdown_table

    out = ["The world node's own (every world):", "", markdown_table(WORLD_PARAMS)]
    for name in sorted(registered()):
        cls = world_class(name)
        out += ["", f"`{name}` (`{cls.__module__}.{cls.__name__}`):", "",
                markdown_table(cls.PARAMS) if cls.PARAMS else "(none of its own)"]
    return "\n".join(out)


if __name__ == "__main__":  # python -m: the classes must be this module's, not __main__'s
    from homeo_decision import world_api

    print(world_api.tables())
