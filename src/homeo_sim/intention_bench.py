"""What intention recognition costs (``homeo-sim bench --intention bayes``).

Reported: one recognition (a posterior-table lookup), the learning per tick (counting, plus the
EM runs that corrections trigger, spread over all ticks), one EM run, one pgmpy exact-inference
query for comparison, and the in-process iteration rate in bayes mode against oracle mode.
Times are the best of a few repetitions: the machine may be shared.
"""

from __future__ import annotations

import time
import warnings


class _Timed:
    """Wraps a model and adds up the time spent in recognise and learn."""

    def __init__(self, model):
        self.model = model
        self.t_rec = self.t_learn = 0.0
        self.n_rec = self.n_learn = 0

    def recognise(self, obs):
        t0 = time.perf_counter()
        r = self.model.recognise(obs)
        self.t_rec += time.perf_counter() - t0
        self.n_rec += 1
        return r

    def learn(self, obs, label):
        t0 = time.perf_counter()
        n = self.model.learn(obs, label)
        self.t_learn += time.perf_counter() - t0
        self.n_learn += 1
        return n



def _best_rate(cfg, sc, repeats: int) -> float:
    from .runner import run_episode

    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        run_episode(cfg, sc)
        best = min(best, time.perf_counter() - t0)
    return cfg.iterations / best


def bench_intention(iterations: int = 20000, repeats: int = 3) -> dict:
    from homeo_decision.scenario import load_scenario
    from homeo_msgs_py.graph import BAYES

    from .runner import RunConfig, Simulation

    sc = load_scenario()
    oracle_ips = _best_rate(RunConfig(iterations=iterations), sc, repeats)
    bayes_ips = _best_rate(RunConfig(iterations=iterations, intention=BAYES), sc, repeats)

    # recognise / learn shares inside one bayes episode
    sim = Simulation(sc, RunConfig(iterations=iterations, intention=BAYES))
    timed = _Timed(sim.recognition.model)
    sim.recognition.model = timed
    sim.run(iterations)
    model = timed.model
    em_us = timed.t_learn / max(model.em_runs, 1) * 1e6

    # one recognition in isolation, on the observations of that episode's human
    obs = [sim.env.human.observe() for _ in range(2000)]
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        for o in obs:
            model.recognise(o)
        best = min(best, (time.perf_counter() - t0) / len(obs))
    rec_us = best * 1e6

    # pgmpy's exact inference on the same network, per query (what the posterior table replaces)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        from pgmpy.inference import VariableElimination
    ve = VariableElimination(model.network())
    t0 = time.perf_counter()
    for o in obs[:50]:
        ve.query(["intention"], evidence=o, show_progress=False)
    ve_us = (time.perf_counter() - t0) / 50 * 1e6

    return {
        "iterations": iterations,
        "recognise_us": rec_us,
        "recognise_in_loop_us": timed.t_rec / timed.n_rec * 1e6,
        "learn_per_tick_us": timed.t_learn / timed.n_learn * 1e6,
        "em_runs": model.em_runs,
        "em_run_us": em_us,
        "em_iterations_per_run": model.em_iterations / max(model.em_runs, 1),
        "pgmpy_query_us": ve_us,
        "oracle_iterations_per_s": oracle_ips,
        "bayes_iterations_per_s": bayes_ips,
        "bayes_over_oracle_time": oracle_ips / bayes_ips,
    }


def format_bench(r: dict) -> str:
    return "\n".join([
        f"recognition (posterior-table lookup) : {r['recognise_us']:8.2f} us",
        f"learning, per tick (all ticks)       : {r['learn_per_tick_us']:8.2f} us  "
        f"({r['em_runs']} EM runs in {r['iterations']} ticks, {r['em_run_us']:.0f} us and "
        f"{r['em_iterations_per_run']:.1f} iterations each; counting otherwise)",
        f"recognition + learning per tick      : {r['recognise_in_loop_us'] + r['learn_per_tick_us']:8.2f} us",
        f"pgmpy VariableElimination, one query : {r['pgmpy_query_us']:8.0f} us  (not used per tick)",
        f"in-process loop, oracle              : {r['oracle_iterations_per_s']:8,.0f} iterations/s",
        f"in-process loop, bayes               : {r['bayes_iterations_per_s']:8,.0f} iterations/s  "
        f"(a bayes iteration takes {r['bayes_over_oracle_time']:.2f}x an oracle one)",
    ])
