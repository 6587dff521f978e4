"""The in-process thesis simulation (Section 4.2): a robot in the simulated home, one loop.

One iteration (tick t) is ``homeo_decision.robot.run_loop``: the robot recognises the human's
intention (or, in the thesis's own setting, observes it), perceives its drives and the world
(Eq 3.2-3.3) and picks an action by softmax (Algorithm 1 lines 2-17); the environment applies it
(Table 4.1), the human answers (Algorithm 2 lines 8-19), time passes (Table 4.2) and the human
decides what it wants next (lines 3-6); at tick t+1 the robot learns from tick t (Eq 3.14, 3.23)
before it chooses again. The metrics record d(t) after the iteration. The node graph runs the
very same objects, split across processes.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from typing import Callable, Iterable, TextIO

from homeo_decision import checkpoint, qtable_io
from homeo_decision.robot import Robot, run_loop
from homeo_decision.scenario import Scenario, load_scenario
from homeo_msgs_py.graph import BAYES, ORACLE
from homeo_msgs_py.learning import DOD, PSEUDO_UPDATE, XI

from .environment import SimEnvironment
from .metrics import MetricRecorder, accuracy_ends, stage_marks
from .parallel import keeps, parallel_map


# the learning parameters a run takes (homeo-sim run's flags): RunConfig's fields of the same names
RUN_LEARNING = (DOD, XI, PSEUDO_UPDATE)


@dataclass(frozen=True)
class RunConfig:
    iterations: int = 5000
    seed: int = 0
    # the learning parameters of RUN_LEARNING; None: the scenario's
    dod: float | None = None
    xi: float | None = None
    pseudo_update: bool | None = None
    scenario: str | None = None  # path; None = the thesis scenario
    overrides: tuple = ()  # (key, value) pairs for the scenario's open choices
    load_q: str | None = None
    save_q: str | None = None
    trace: str | None = None
    series: bool = False  # keep the per-iteration metric series
    policy: str = "objectq"  # see POLICIES
    adaptive_dod: bool = False
    intention: str = ORACLE  # ORACLE: the intention is observed (the thesis's simulation); BAYES: recognised
    load_intention: str | None = None  # start the bayes recogniser from a saved model
    save_intention: str | None = None


@keeps
@dataclass
class EpisodeResult:
    seed: int
    metrics: dict
    series: dict | None = None
    load_report: object | None = None
    actions: list = field(default_factory=list)
    intention_hits: list | None = None  # bayes mode: per tick, recognised intention == the human's true one
    stages: list = field(default_factory=list)  # the metrics' running sums after the ticks of stage_marks


def build_scenario(cfg: RunConfig) -> Scenario:
    return load_scenario(cfg.scenario, overrides=dict(cfg.overrides))


_COMPILED: dict = {}


def cached_scenario(cfg: RunConfig) -> Scenario:
    """``build_scenario`` once per process and configuration: compiling costs about a quarter of a
    5000-iteration episode, and a worker runs many episodes of the same scenario."""
    key = (cfg.scenario, json.dumps(list(cfg.overrides), sort_keys=True, default=repr))
    sc = _COMPILED.get(key)
    if sc is None:
        sc = _COMPILED[key] = build_scenario(cfg)
    return sc


class Simulation:
    """The simulated home and a robot, wired as in the thesis's simulation."""

    def __init__(self, sc: Scenario, cfg: RunConfig):
        self.sc = sc
        self.cfg = cfg
        self.policy = make_decision(sc, cfg)
        self.load_report = None
        if cfg.load_q:
            self.load_report = checkpoint.load_table(self.policy.q, cfg.load_q)
        self.recognition = make_recognition_of(sc, cfg)
        self.robot = Robot(sc, self.policy, self.recognition)
        self.env = SimEnvironment(sc, cfg.seed, cues=cfg.intention == BAYES)

    @property
    def model(self):
        """The intention model of a bayes run (None in oracle mode)."""
        return getattr(self.recognition, "model", None)

    def run(self, iterations: int, trace: TextIO | None = None, on_tick: Callable[[int], None] | None = None,
            keep_actions: bool = False) -> EpisodeResult:
        sc, robot = self.sc, self.robot
        # d(t) of the metrics: after the whole iteration, or before the time increase (open choice)
        rec = MetricRecorder(sc.drive_names, [d.threshold for d in sc.drives], keep=self.cfg.series,
                             marks=stage_marks(iterations)).follow(robot.perception, sc.open.metrics_sample == "after_action")
        record = rec.on_tick
        bayes = self.cfg.intention == BAYES
        actions: list = []
        hits: list = []
        dec = robot.decision

        def tick(t, p, r, a, out):
            record(t, p, r, a, out)
            if bayes:
                hits.append(r.intention == out.true_intention)
            if keep_actions:
                actions.append(a)
            if trace is not None:
                trace.write(json.dumps(trace_line(sc, t, p, a, out, dec.learned, r if bayes else None)) + "\n")
            if on_tick is not None:
                on_tick(t)

        fast = not (bayes or keep_actions or trace is not None or on_tick is not None)
        run_loop(self.env, robot, iterations, self.env.observe(), record if fast else tick)
        metrics = rec.summary()
        if bayes:
            metrics["intention_accuracy"] = accuracy_ends(hits)
        return EpisodeResult(self.cfg.seed, metrics, rec.series() if self.cfg.series else None, self.load_report,
                             actions, hits if bayes else None, rec.stages)


def make_recognition_of(sc: Scenario, cfg: RunConfig):
    """The robot's recognition part: the oracle (the thesis's simulation) or the Bayesian network."""
    from homeo_intention.recognition import make_recognition

    if cfg.intention == ORACLE and (cfg.load_intention or cfg.save_intention):
        raise ValueError("--load-intention/--save-intention need --intention bayes")
    rec = make_recognition(cfg.intention, sc)
    if cfg.load_intention:
        rec.model.load(cfg.load_intention)
    return rec


def make_decision(sc: Scenario, cfg: RunConfig):
    """The decision maker of a run. Any policy offers DecisionCore's perceive / select / learn
    and a ``q`` attribute when it has a table to save or load (see homeo_decision.baselines)."""
    from homeo_decision.adaptive_dod import AdaptiveDoDRobot
    from homeo_decision.baselines import POLICIES, make_policy
    from homeo_decision.objectq import ObjectQ

    if cfg.policy not in POLICIES:
        raise ValueError(f"unknown policy {cfg.policy!r}; known: {', '.join(POLICIES)}")
    if cfg.adaptive_dod and cfg.policy not in ("objectq", "nofeedback"):
        raise ValueError(f"--adaptive-dod needs a DoD-weighted Object-Q robot (objectq or nofeedback), not {cfg.policy!r}")
    robot = make_policy(cfg.policy, sc, cfg.seed, dod=cfg.dod, xi=cfg.xi, pseudo_update=cfg.pseudo_update)
    if cfg.adaptive_dod:
        robot = AdaptiveDoDRobot(robot)
    if (cfg.save_q or cfg.load_q) and not isinstance(getattr(robot, "q", None), ObjectQ):
        what = "--save-q" if cfg.save_q else "--load-q"
        raise qtable_io.QTableError(f"{what}: policy {cfg.policy!r} has no Object-Q table to save or load")
    return robot


def trace_line(sc: Scenario, t: int, p, a: int, out, learned, recognised=None) -> dict:
    """One JSON line of ``--trace``: the state the robot decided in and what followed."""
    it = sc.c.intention_of[p.code]
    line = {
        "tick": t,
        "drives": dict(zip(sc.drive_names, p.drives)),
        "intensities": dict(zip(sc.motivation_names, p.intensities)),
        "m_dom": sc.internal_states[p.m_dom],
        "intention": sc.intention_names[it] if it else None,
        "action": sc.actions[a].name,
        "feedback": out.feedback,
        "proposal": sc.actions[out.proposal].name if out.proposal is not None else None,
        "reward": learned.reward,
        "pseudo_reward": learned.pseudo_reward,
    }
    if recognised is not None:
        true_it = out.true_intention
        line |= {"true_intention": sc.intention_names[true_it] if true_it else None,
                 "confidence": recognised.confidence,
                 "clarified": sc.intention_names[out.clarified] if out.clarified is not None else None}
    return line


def run_episode(cfg: RunConfig, sc: Scenario | None = None, on_tick=None, keep_actions: bool = False) -> EpisodeResult:
    sc = sc or build_scenario(cfg)
    sim = Simulation(sc, cfg)
    if cfg.trace:
        with open(cfg.trace, "w") as fh:
            res = sim.run(cfg.iterations, trace=fh, on_tick=on_tick, keep_actions=keep_actions)
    else:
        res = sim.run(cfg.iterations, on_tick=on_tick, keep_actions=keep_actions)
    if cfg.save_q:
        robot = sim.policy
        qtable_io.save(robot.q, cfg.save_q, meta={
            "iterations": cfg.iterations, "seed": cfg.seed, "policy": cfg.policy, "adaptive_dod": cfg.adaptive_dod,
            **{s.name: getattr(robot, s.name, None) for s in RUN_LEARNING}})
    if cfg.save_intention and sim.model is not None:
        sim.model.save(cfg.save_intention, meta={"iterations": cfg.iterations, "seed": cfg.seed})
    return res


def _run_one(cfg: RunConfig) -> EpisodeResult:
    return run_episode(cfg, cached_scenario(cfg))


def run_seeds(cfg: RunConfig, seeds: Iterable[int], workers=None, bar=None) -> list[EpisodeResult]:
    """Run one episode per seed, on ``workers`` processes (or a ``parallel.Pool``); results come back in
    seed order; ``bar`` counts them."""
    cfgs = [replace(cfg, seed=s, trace=None, save_q=None, save_intention=None) for s in seeds]
    return parallel_map(_run_one, cfgs, workers, bar)
