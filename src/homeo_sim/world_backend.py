"""The simulated home as a world of the graph (``homeo_decision.world_api.WorldBackend``), no rclpy.

The thesis's simulated environment (world, human, body: ``environment.SimEnvironment``) in message
fields, and the metrics of Section 4.1, which need the robot's drives after each tick: they come
back with the action of the next tick (d(t) after the iteration, as ``homeo-sim run`` records
them). The human is the simulated one of Algorithm 2 or, with ``human: person``, a person whose
messages on ``homeo/human_input`` answer instead (``person.PersonHuman``): the world then waits
for them, off the node's thread.

Its part of the run's checkpoint: the human's two random streams; the environment (world code,
body, human, the cues of the current observation), the recorder's running sums, the recognition
hits kept, and the truth of the tick whose drives have not come back yet.
"""

from __future__ import annotations

from homeo_decision import codec
from homeo_decision.environment import Outcome
from homeo_decision.world_api import LaunchPlan, WorldBackend, WorldConfigError, run_ticks
from homeo_msgs_py.graph import BAYES, ORACLE
from homeo_msgs_py.params import ParamSpec
from homeo_msgs_py.schemas import Rejected

from .environment import SimEnvironment
from .metrics import AccuracyEnds, MetricRecorder

SIM_HUMAN, PERSON = "sim", "person"


class SimWorld(WorldBackend):
    """The simulated world and human of the thesis; its result: Table 4.5's metrics beside the thesis's."""

    NAME = "sim"
    PARAMS = (
        ParamSpec("human", SIM_HUMAN, "who plays the human: the simulated one, or a person on homeo/human_input",
                  choices=(SIM_HUMAN, PERSON), fixed=True, eq="Algorithm 2"),
        ParamSpec("human_timeout", 10.0, "seconds a tick waits for the person before it counts as no intention "
                  "(no answer)", 0.01, 3600.0),
    )
    KEEPS_STATE = SEEDED = True

    def __init__(self, sc, values: dict, human=None):
        super().__init__(sc, values)
        seed = values.get("seed", 0)
        self.intention_accuracy = bool(values.get("intention_learns", False))  # score the recognised intention
        self.sample_after = sc.open.metrics_sample == "after_action"
        self.drives_key = "after_action" if self.sample_after else "drives"
        self.person = None
        if human is None and values.get("human", SIM_HUMAN) == PERSON:
            from .person import PersonHuman

            human = self.person = PersonHuman(sc, seed, values.get("human_timeout", 10.0))
        self.blocking = self.person is not None  # a person is waited for
        self.env = SimEnvironment(sc, seed, cues=True, body_after=True, human=human)
        self.reset(seed)

    def reset(self, seed: int | None = None) -> None:
        self.env.reset(seed)
        self.rec = MetricRecorder(self.sc.drive_names, [d.threshold for d in self.sc.drives])
        self.hits = AccuracyEnds()  # fixed memory: the node runs for hours
        self._last: Outcome | None = None

    # -- the lockstep -----------------------------------------------------------------------------
    def start(self) -> None:
        self.env.start()

    def check_action(self, fields: dict, tick: int) -> None:
        if tick > 0 and fields.get(self.drives_key) is None:
            raise Rejected(f"no {self.drives_key}: the metrics need them")

    def step(self, action_fields: dict | None) -> dict:
        sc, env = self.sc, self.env
        name = action_fields["action"] if action_fields is not None else None
        recognised = action_fields.get("intention") if action_fields is not None else None
        if recognised is not None:
            self.hits.append(recognised == sc.intention_names[env.human.intention])
        out = self._last = env.step(sc.action_index(name) if name is not None else None)
        return codec.outcome_fields(sc, out)

    def record(self, action_fields: dict | None) -> None:
        if self._last is None or action_fields is None or action_fields.get(self.drives_key) is None:
            return
        d = action_fields[self.drives_key]
        self.rec.record([d[n] for n in self.sc.drive_names], self._last.true_intention != 0, self._last.satisfied)
        self._last = None  # recorded: a checkpoint from here on must not record it again

    def status(self, done: bool) -> dict:
        if not self.rec.n:
            return {}
        m = self.rec.summary()
        if self.intention_accuracy and self.hits:
            m["intention_accuracy"] = self.hits.ends()
        return {"metrics": m}

    # -- the node's other calls -------------------------------------------------------------------
    def set_param(self, name: str, value) -> str | None:
        if name == "human_timeout" and self.person is not None:
            self.person.timeout = value
        return None

    def inputs(self) -> dict:
        if self.person is None:
            return {}
        from homeo_msgs_py.human_input import decode_human_input

        voc, inbox = codec.vocabulary(self.sc), self.person.inbox
        return {"human_input": lambda text: inbox.put(decode_human_input(text, voc))}

    def close(self) -> None:
        if self.person is not None:
            self.person.inbox.put(None)  # a wait in progress ends now (as silence)

    # -- the run's checkpoint ---------------------------------------------------------------------
    def run_config(self) -> dict:
        return {"human": PERSON if self.person is not None else SIM_HUMAN, "intention_accuracy": self.intention_accuracy}

    def state(self) -> tuple[dict, dict]:
        env = self.env.state()
        h = env["human"]
        rng = {"human": h.pop("rng"), "observation": h.pop("obs_rng")}
        o = self._last
        pending = None if o is None else [o.true_intention != 0, bool(o.satisfied)]
        return rng, {"env": env, "metrics": self.rec.state(), "accuracy": self.hits.state(), "pending": pending}

    def set_state(self, rng, st, tick: int) -> None:
        if not isinstance(st, dict):
            raise ValueError("the world's state must be an object")
        env, pending = st.get("env"), st.get("pending")
        if not isinstance(env, dict) or not isinstance(env.get("human"), dict) or not isinstance(rng, dict):
            raise ValueError("env, env.human and rng must be objects")
        if env.get("tick") != tick:
            raise WorldConfigError(f"tick {tick} is not the environment's {str(env.get('tick'))[:20]}")
        if pending is not None and not (isinstance(pending, list) and len(pending) == 2
                                        and all(type(x) is bool for x in pending)):
            raise ValueError("pending must be null or [expressed, satisfied]")
        env = dict(env, human=dict(env["human"], rng=rng.get("human"), obs_rng=rng.get("observation")))
        # each part is checked on a scratch copy first, so a failure in a later one changes nothing
        rec = MetricRecorder(self.rec.drive_names, self.rec.thresholds)
        rec.set_state(st.get("metrics"))
        hits = AccuracyEnds(self.hits.window)
        hits.set_state(st.get("accuracy"))
        self.env.set_state(env)  # last: it checks everything before it changes anything
        self.rec, self.hits = rec, hits
        self._last = None if pending is None else Outcome(None, 0, None, None, None, int(pending[0]), pending[1])

    # -- the front ends: Table 4.5's metrics of the run, beside the thesis's --------------------------
    @classmethod
    def plan(cls, sc, given: dict, workdir: str) -> LaunchPlan:
        plan = super().plan(sc, given, workdir)
        plan.inputs = ("human_input",) if plan.params.get("human") == PERSON else ()  # a live view may play it
        return plan

    @classmethod
    def result(cls, sc, status: dict, setting: dict) -> dict | None:
        """``homeo-sim run``'s JSON of the run (``restarts`` and the ticks they cost when there were any);
        None before any tick was measured."""
        from .cli import run_output

        if not status.get("metrics"):
            return None
        out = run_output(run_ticks(status, setting), [setting["seed"]], [status["metrics"]], sc.drive_names)
        if status.get("restarts"):  # only when there were any: an undisturbed run prints what homeo-sim run prints
            out.update(restarts=status["restarts"], missed=status.get("missed", 0))
        return out

    @classmethod
    def result_text(cls, sc, result: dict, setting: dict) -> str:
        from .cli import format_table

        how = {ORACLE: "the human's intention observed, as in the thesis's simulation",
               BAYES: "the intention recognised by the Bayesian network, learning from scratch\n(the thesis "
                      "observes it: --intention oracle)"}[setting["intention"]]
        table = format_table(result, sc.drive_names, sc.name, sc.reference.metrics if sc.reference else None)
        if sc.reference is None:
            return table
        return (f"{table}\nsetting: {result['iterations']} iterations, one seed ({setting['seed']}); {how}. The "
                f"thesis's column\nis a mean over its runs, and one seed scatters around it: homeo-sim run --seeds "
                f"20 gives ours\nwith 95% intervals (docs/EXPERIMENTS.md, \"One run and many\").")

    def rejoin(self, tick: int, lost: int, step_lost) -> dict | None:
        """Time passed while the node was down and nobody acted: ``lost`` ticks stepped without an
        action, none of them recorded (no robot drives came back)."""
        if not lost:
            return None
        fields = {}
        for _ in range(lost):
            fields = step_lost()
        self._last = None
        return fields
