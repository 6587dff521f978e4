"""The in-process thesis simulation (Section 4.2): world, human, body and robot in one loop.

One iteration (tick t):
  1. the robot perceives drives and world (the human's intention included) and picks an
     action by softmax (Algorithm 1 lines 2-17);
  2. the world and the body apply the action's effects (Table 4.1);
  3. the human answers with feedback and maybe a proposal (Algorithm 2 lines 8-19);
  4. feedback moves NAch, drives grow with time (Table 4.2), and the human decides what
     it wants next (Algorithm 2 lines 3-6);
  5. the robot perceives the new state s' and learns (Eq 3.14, 3.23);
  6. the metrics record d(t) after the iteration.

With ``intention="bayes"`` the robot no longer sees the human's intention: it recognises it from
the human's observations (Section 2.3, ``homeo_intention``). One tick t of that loop, in the
order the ROS node graph replicates (docs/INTENTION.md):
  obs_t = human.observe(); rec_t = model.recognise(obs_t);
  perceived code = the true world code with the intention replaced by rec_t.intention;
  p = robot.perceive(drives, perceived code); a = robot.select(p, t);
  world.execute(a) (the true world); body.apply_action; drives.apply_action(perceived code, a);
  resp = human.respond(a) (the true intention); model.learn(obs_t, resp.clarified);
  drives.apply_feedback; body.apply_time; drives.apply_time(rec_t.intention != 0 or feedback != 0,
  resp.satisfied); drives.set_body; human.advance; world.set_human; obs/recognition/perceive of
  t+1; robot.learn. HSR and the other metrics use the human's true expressed/satisfied.
The oracle mode keeps the loop below unchanged (bit-identical results, full speed).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from typing import Callable, Iterable, TextIO

from homeo_decision import qtable_io
from homeo_decision.drives import DriveModel
from homeo_decision.scenario import Scenario, load_scenario

from .body import SimBody
from .human import SimHuman
from .metrics import MetricRecorder, accuracy_ends
from .world import World


@dataclass(frozen=True)
class RunConfig:
    iterations: int = 5000
    seed: int = 0
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
    intention: str = "oracle"  # "oracle": the intention is observed (the thesis's simulation); "bayes": recognised
    load_intention: str | None = None  # start the bayes recogniser from a saved model
    save_intention: str | None = None


INTENTION_MODES = ("oracle", "bayes")


@dataclass
class EpisodeResult:
    seed: int
    metrics: dict
    series: dict | None = None
    load_report: object | None = None
    actions: list = field(default_factory=list)
    intention_hits: list | None = None  # bayes mode: per tick, recognised intention == the human's true one


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
    """World, human, body and robot wired as in the thesis's simulation."""

    def __init__(self, sc: Scenario, cfg: RunConfig):
        self.sc = sc
        self.cfg = cfg
        self.world = World(sc)
        self.human = SimHuman(sc, cfg.seed)
        self.body = SimBody(sc)
        self.drives = DriveModel(sc)
        self.robot = make_robot(sc, cfg)
        self.load_report = None
        if cfg.load_q:
            self.load_report = qtable_io.load(self.robot.q, cfg.load_q)
        self.model = make_intention_model(sc, cfg)  # None in oracle mode: the fast loop

    def run(self, iterations: int, trace: TextIO | None = None, on_tick: Callable[[int], None] | None = None,
            keep_actions: bool = False) -> EpisodeResult:
        if self.model is not None:
            return self.run_recognised(iterations, trace, on_tick, keep_actions)
        sc, world, human, body, drives, robot = self.sc, self.world, self.human, self.body, self.drives, self.robot
        rec = MetricRecorder(sc.drive_names, [d.threshold for d in sc.drives])
        span_action = sc.open["reward_span"] == "action"
        # d(t) of the metrics: after the whole iteration, or before the time increase (open choice)
        sample_after_action = sc.open["metrics_sample"] == "after_action"
        actions = []

        human.advance(world.code)  # Algorithm 2 lines 1-6: the first intention
        world.set_human(human.present, human.intention)
        drives.set_body(body.values)
        p = robot.perceive(drives.values, world.code)
        for t in range(iterations):
            a = robot.select(p, t)
            before = world.execute(a)
            body.apply_action(before, a)
            drives.apply_action(before, a)
            expressed = human.intention != 0
            resp = human.respond(a)
            drives.apply_feedback(resp.feedback)
            after_action = None
            if span_action or sample_after_action:
                drives.set_body(body.values)
                after_action = tuple(drives.values)
            body.apply_time()
            drives.apply_time(expressed, resp.satisfied)
            drives.set_body(body.values)
            human.advance(world.code)
            world.set_human(human.present, human.intention)
            p_next = robot.perceive(drives.values, world.code)
            learned = robot.learn(p, a, after_action if span_action else p_next.drives, resp.feedback,
                                  resp.proposal, p_next, t)
            rec.record(after_action if sample_after_action else p_next.drives, expressed, resp.satisfied)
            if keep_actions:
                actions.append(a)
            if trace is not None:
                trace.write(json.dumps(trace_line(sc, t, p, a, resp, learned)) + "\n")
            if on_tick is not None:
                on_tick(t)
            p = p_next
        res = EpisodeResult(self.cfg.seed, rec.summary(), rec.series() if self.cfg.series else None, self.load_report, actions)
        return res

    def run_recognised(self, iterations: int, trace: TextIO | None = None,
                       on_tick: Callable[[int], None] | None = None, keep_actions: bool = False) -> EpisodeResult:
        """The loop with a recogniser between the human and the robot (tick order in the module docstring)."""
        sc, world, human, body, drives, robot, model = (self.sc, self.world, self.human, self.body, self.drives,
                                                        self.robot, self.model)
        rec = MetricRecorder(sc.drive_names, [d.threshold for d in sc.drives])
        span_action = sc.open["reward_span"] == "action"
        sample_after_action = sc.open["metrics_sample"] == "after_action"
        with_intention = sc.c.with_intention
        truth = model.needs_truth  # the oracle reads the true intention from the observation
        actions, hits = [], []

        human.advance(world.code)
        world.set_human(human.present, human.intention)
        drives.set_body(body.values)
        obs = human.observe(truth)
        r = model.recognise(obs)
        p = robot.perceive(drives.values, with_intention[world.code][r.intention])
        for t in range(iterations):
            a = robot.select(p, t)
            before = world.execute(a)  # the true world
            body.apply_action(before, a)
            drives.apply_action(p.code, a)  # the perceived world of tick t
            true_it = human.intention
            resp = human.respond(a)
            model.learn(obs, resp.clarified)
            drives.apply_feedback(resp.feedback)
            after_action = None
            if span_action or sample_after_action:
                drives.set_body(body.values)
                after_action = tuple(drives.values)
            body.apply_time()
            # the robot's NAch grows while it believes an intention is pending (Table 4.2, open `serving_growth`)
            drives.apply_time(r.intention != 0 or resp.feedback != 0, resp.satisfied)
            drives.set_body(body.values)
            human.advance(world.code)
            world.set_human(human.present, human.intention)
            obs_next = human.observe(truth)
            r_next = model.recognise(obs_next)
            p_next = robot.perceive(drives.values, with_intention[world.code][r_next.intention])
            learned = robot.learn(p, a, after_action if span_action else p_next.drives, resp.feedback,
                                  resp.proposal, p_next, t)
            rec.record(after_action if sample_after_action else p_next.drives, true_it != 0, resp.satisfied)
            hits.append(r.intention == true_it)
            if keep_actions:
                actions.append(a)
            if trace is not None:
                line = trace_line(sc, t, p, a, resp, learned)
                line |= {"true_intention": sc.intention_names[true_it] if true_it else None,
                         "confidence": r.confidence, "clarified": sc.intention_names[resp.clarified]
                         if resp.clarified is not None else None}
                trace.write(json.dumps(line) + "\n")
            if on_tick is not None:
                on_tick(t)
            p, obs, r = p_next, obs_next, r_next
        metrics = rec.summary()
        metrics["intention_accuracy"] = accuracy_ends(hits)
        return EpisodeResult(self.cfg.seed, metrics, rec.series() if self.cfg.series else None, self.load_report,
                             actions, hits)


def make_intention_model(sc: Scenario, cfg: RunConfig):
    """The recogniser of a run: None in oracle mode (the fast loop reads the intention itself)."""
    if cfg.intention not in INTENTION_MODES:
        raise ValueError(f"unknown intention mode {cfg.intention!r}; known: {', '.join(INTENTION_MODES)}")
    if cfg.intention == "oracle":
        if cfg.load_intention or cfg.save_intention:
            raise ValueError("--load-intention/--save-intention need --intention bayes")
        return None
    from homeo_intention.model import IntentionModel

    model = IntentionModel(sc)
    if cfg.load_intention:
        model.load(cfg.load_intention)
    return model


def make_robot(sc: Scenario, cfg: RunConfig):
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


def trace_line(sc: Scenario, t: int, p, a: int, resp, learned) -> dict:
    """One JSON line of ``--trace``: the state the robot decided in and what followed."""
    it = sc.c.intention_of[p.code]
    return {
        "tick": t,
        "drives": dict(zip(sc.drive_names, p.drives)),
        "intensities": dict(zip(sc.motivation_names, p.intensities)),
        "m_dom": sc.motivation_names[p.m_dom],
        "intention": sc.intention_names[it] if it else None,
        "action": sc.actions[a].name,
        "feedback": resp.feedback,
        "proposal": sc.actions[resp.proposal].name if resp.proposal is not None else None,
        "reward": learned.reward,
        "pseudo_reward": learned.pseudo_reward,
    }


def run_episode(cfg: RunConfig, sc: Scenario | None = None, on_tick=None, keep_actions: bool = False) -> EpisodeResult:
    sc = sc or build_scenario(cfg)
    sim = Simulation(sc, cfg)
    if cfg.trace:
        with open(cfg.trace, "w") as fh:
            res = sim.run(cfg.iterations, trace=fh, on_tick=on_tick, keep_actions=keep_actions)
    else:
        res = sim.run(cfg.iterations, on_tick=on_tick, keep_actions=keep_actions)
    if cfg.save_q:
        robot = sim.robot
        qtable_io.save(robot.q, cfg.save_q, meta={
            "iterations": cfg.iterations, "seed": cfg.seed, "policy": cfg.policy, "adaptive_dod": cfg.adaptive_dod,
            "dod": getattr(robot, "dod", None), "xi": getattr(robot, "xi", None),
            "pseudo_update": getattr(robot, "pseudo", None)})
    if cfg.save_intention and sim.model is not None:
        sim.model.save(cfg.save_intention, meta={"iterations": cfg.iterations, "seed": cfg.seed})
    return res


def _run_one(cfg: RunConfig) -> EpisodeResult:
    return run_episode(cfg, cached_scenario(cfg))


def run_seeds(cfg: RunConfig, seeds: Iterable[int], workers: int | None = None,
              on_done: Callable[[EpisodeResult], None] | None = None) -> list[EpisodeResult]:
    """Run one episode per seed, on ``workers`` processes; results come back in seed order."""
    from .parallel import parallel_map

    cfgs = [replace(cfg, seed=s, trace=None, save_q=None, save_intention=None) for s in seeds]
    return parallel_map(_run_one, cfgs, workers, on_done)
