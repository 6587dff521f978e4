"""What the robot nodes share to survive crashes and restarts (``homeo_decision.checkpoint`` does
the files): the parameters (``DURABLE_PARAMS``, set at start only), the start from a checkpoint, and
the rejoining join.
"""

from __future__ import annotations

import os

from homeo_msgs_py.data_dir import OutsideDataDir
from homeo_msgs_py.graph import NODES
from homeo_msgs_py.node_base import NodeConfigError
from homeo_msgs_py.params import ParamSpec
from homeo_msgs_py.rejoin import make_rejoinable

from . import checkpoint

CHECKPOINT_EVERY = ParamSpec("checkpoint_every", 100, "ticks between checkpoints", 1, 10**9, fixed=True)
DURABLE_PARAMS = (
    ParamSpec("supervised", False, "the launcher restarts nodes that die: a gap in the ticks is skipped, not waited "
              "for (homeo_msgs_py.rejoin)", fixed=True),
    ParamSpec("checkpoint_dir", "", "write DIR/<node>.json every checkpoint_every ticks and at shutdown ('' = never)",
              fixed=True),
    CHECKPOINT_EVERY,
    ParamSpec("resume_dir", "", "start from the checkpoint in this folder ('' = from scratch)", fixed=True),
    ParamSpec("respawned", False, "this process replaces one that died in the same run: go on with the run's tick "
              "offset and parameters, fresh if no checkpoint of this launch exists", fixed=True),
    ParamSpec("session", "", "the launch's id, written into each checkpoint", fixed=True),
    ParamSpec("respawn_rejoins", False, "a start that finds this launch's own checkpoint in checkpoint_dir rejoins "
              "the run as a respawned one does (ros2 launch respawn passes no flag)", fixed=True),
)


def declare(node) -> dict:
    """Declare the parameters (set at start); returns their values, the folders resolved inside the
    node's data directory (``homeo_msgs_py.data_dir``)."""
    cfg = node.declare_specs(DURABLE_PARAMS)
    for key in ("checkpoint_dir", "resume_dir"):
        try:
            cfg[key] = node.data_path(cfg[key], key, trusted=True)  # set at start only
        except OutsideDataDir as exc:
            raise NodeConfigError(str(exc)) from None
    if cfg["respawn_rejoins"] and not cfg["respawned"] and launch_started(cfg):
        cfg.update(respawned=True, resume_dir=cfg["checkpoint_dir"])
        node.get_logger().info("checkpoints of this launch are here: a respawn, rejoining the run")
    return cfg


def launch_started(cfg: dict) -> bool:
    """Whether ``checkpoint_dir`` holds a checkpoint written in this launch (its session), by any node
    of the graph (the drives node writes one every tick): the run has begun, so this start is a respawn."""
    if not cfg["checkpoint_dir"] or not cfg["session"]:
        return False
    for name in NODES:
        try:
            if checkpoint.load(checkpoint.path_for(cfg["checkpoint_dir"], name), name).get("session") == cfg["session"]:
                return True
        except checkpoint.CheckpointError:  # none, or not readable
            pass
    return False


def setup_stage(node, stage, cfg: dict) -> None:
    if cfg["supervised"] or cfg["respawned"]:
        make_rejoinable(stage)


def read_start(node, cfg: dict) -> dict | None:
    """The checkpoint to start from (checked envelope), or None. A respawned node without one
    starts fresh; a resume without one is a configuration error."""
    d = cfg["resume_dir"]
    if not d:
        return None
    path = checkpoint.path_for(d, node.get_name())
    if cfg["respawned"] and not os.path.exists(path):
        node.get_logger().warning(f"no checkpoint {path} yet: starting fresh")
        return None
    try:
        ck = checkpoint.load(path, node.get_name())
    except checkpoint.CheckpointError as exc:
        raise NodeConfigError(f"resume: {exc}") from None
    if cfg["respawned"] and ck.get("session") != cfg["session"]:
        node.get_logger().warning(f"{path} is of an earlier launch: starting fresh")
        return None
    return ck


def checkpointer(node, make, every: int | None = None, directory: str | None = None,
                 throttle_s: float | None = None, background: bool = True) -> checkpoint.Checkpointer:
    """The node's checkpoints (``node.durable``: its parameters), written off the tick's path by a
    thread of their own (``background``); ``make`` takes the snapshot in the tick. ``throttle_s``: at
    most one warning that often (a node that writes every tick)."""
    cfg, log = node.durable, node.get_logger()
    warn = (lambda text: log.warning(text)) if throttle_s is None else \
        (lambda text: log.warning(text, throttle_duration_sec=throttle_s))
    return checkpoint.Checkpointer(cfg["checkpoint_dir"] if directory is None else directory, node.get_name(),
                                   cfg["checkpoint_every"] if every is None else every, make, warn, background=background)


def status(name: str, ck: checkpoint.Checkpointer, ticks: int, skipped: int) -> dict:
    """The node's checkpoint and rejoin health as a DiagnosticStatus dict."""
    level = 1 if ck.failed else 0
    return {"level": level, "name": f"{name}: checkpoints", "hardware_id": name,
            "message": ck.last_error or (f"last at tick {ck.last_ticks}" if ck.saved else "none written yet"),
            "values": {"learned_ticks": str(ticks), "written": str(ck.saved), "failed": str(ck.failed),
                       "superseded": str(ck.superseded), "path": str(ck.path or ""), "skipped_ticks": str(skipped)}}


class CheckpointedNode:
    """Mixed into a robot node that writes checkpoints (``self.checkpoints``, ``self.ticks``,
    ``self.host.stage``): their health on /diagnostics, and the last one written at shutdown."""

    def extra_statuses(self) -> list[dict]:
        return [status(self.get_name(), self.checkpoints, self.ticks, getattr(self.host.stage.join, "skipped", 0))]

    def destroy_node(self):
        self.checkpoints.close()  # what is on its way is written first
        if self.ticks > 0 and self.checkpoints.last_ticks != self.ticks:
            self.checkpoints.save()  # at shutdown (Ctrl-C, SIGTERM, the launcher's stop)
        return super().destroy_node()


class DurableWorld:
    """Mixed into a world node (``self.driver``): its checkpoint every checkpoint_every ticks, at the
    driver's step point, and at shutdown; and, in a process that replaces one that died
    (``respawned``), the way back into the run: restore the checkpoint, wait for the robot nodes'
    latched answers (``homeo_msgs_py.world_rejoin``), go on after the newest one. The node supplies
    ``world_checkpoint()`` (the envelope), ``restore_world(ck)`` (returns the driver's position, or
    raises CheckpointError), ``go_on(run, tick, position, lost)`` (the driver rejoins at ``tick``;
    ``lost`` ticks since the position were never seen) and may supply ``fresh_run()`` (no checkpoint
    of the run the robot is in)."""

    def fresh_run(self) -> None:
        pass

    def setup_durable_world(self, cfg: dict) -> None:
        from homeo_msgs_py.world_rejoin import RejoinPoint

        self.durable = cfg
        self.checkpoints = checkpointer(self, self.world_checkpoint)
        self.driver.on_step = self.checkpoints.after_tick
        self._rejoin = self._rejoin_since = None
        self._rejoin_pos = None
        if not cfg["respawned"]:
            return
        ck = read_start(self, cfg)
        if ck is not None:
            where = str(checkpoint.path_for(cfg["resume_dir"], self.get_name()))
            try:
                self._rejoin_pos = self.restore_world(ck)
            except checkpoint.CheckpointError as exc:
                raise NodeConfigError(f"resume: {exc}") from None
            self.get_logger().info(f"restored {where}: run {ck['run']}, tick {ck['ticks']}")
        pos = self._rejoin_pos
        self._rejoin = RejoinPoint(pos["run"] if pos else None, pos["tick"] if pos else 0)
        self._rejoin_subs = [self.subscribe(k, lambda m, k=k: self._rejoin.put(k, m)) for k in ("intention", "drives")]

    def rejoin_due(self) -> bool:
        """Called once the start gate is open: True when the rejoin was made (the driver goes on)."""
        from homeo_msgs_py.world_rejoin import WAIT_S

        import time

        if self._rejoin is None:
            return False
        now = time.monotonic()
        if self._rejoin_since is None:
            self._rejoin_since = now
        if not self._rejoin.complete and now - self._rejoin_since < WAIT_S:
            return True  # still listening for the robot's latched answers
        point, self._rejoin = self._rejoin, None
        for sub in self._rejoin_subs:
            self.destroy_subscription(sub)  # heard once; not a reader of the run's ticks
        self._rejoin_subs = []
        run, tick = point.where(self.driver.iterations)
        self.get_logger().info(f"the robot nodes answered {point.heard or 'nothing'}: going on with run {run} at "
                               f"tick {tick}")
        self._go_on(run, tick, self._rejoin_pos)
        return True

    def _go_on(self, run: int, tick: int, pos: dict | None) -> None:
        drv = self.driver
        if pos is None or run != pos["run"]:
            self.fresh_run()
            pos = {"run": run, "tick": 0, "missed": 0, "elapsed": 0.0, "outcome": None, "done": False,
                   "started": False}
        if pos["done"]:
            drv.rejoin(run, pos["tick"], pos["missed"], pos["elapsed"], done=True)
            self._publish_status()
            return
        if tick == 0 and not pos["started"]:  # the run had not begun: begin it
            drv.run = run
            drv.begin()
            return
        lost = tick - pos["tick"]
        if lost:
            self.rejects.note("missed ticks", lost)
        self.go_on(run, tick, pos, lost)

    def extra_statuses(self) -> list[dict]:
        return [status(self.get_name(), self.checkpoints, self.driver.tick, 0)]

    def save_final(self) -> None:
        """At shutdown: a run that started leaves its last checkpoint (a node that is still waiting
        to rejoin keeps the one it was given)."""
        from homeo_msgs_py.lockstep import WAITING

        self.checkpoints.close()  # what is on its way is written first
        if self.driver.state != WAITING and self._rejoin is None:
            self.checkpoints.save()
