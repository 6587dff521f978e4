"""``homeo-replay --policy Q_TABLE``: judge a Q-table on a recorded session before it goes on a robot.

A decision core loaded with the table sees each recorded perception (``homeo/drives`` of tick k:
world code, drives, intensities, m_dom) and, without learning, gives its softmax over the valid
actions at tick k's temperature (Eq 3.17). It is scored on what the robot chose at tick k:

- ``agreement``: how often the table's most likely action is the robot's choice;
- ``p_robot_choice``: the mean probability the table gives the robot's choice;
- ``expected_reward``: the recorded rewards (Eq 3.18 with the table's DoD weights, from the drives
  before and after each tick and the human's feedback), each weighted by the probability the table
  gives the action that earned it (self-normalised); beside it ``recorded_reward``, their plain
  mean. Only actions the robot tried carry a reward, so this ranks tables on what was recorded:
  a table that prefers what earned more there scores higher.
"""

from __future__ import annotations

from homeo_msgs_py.learning import DOD, XI

from .bag import BagError, RecordedRun

# the learning parameters the evaluation takes (homeo-replay's flags): the reward's (Eq 3.18-3.20)
POLICY_LEARNING = (DOD, XI)


def evaluate(run: RecordedRun, q_table: str, learning: dict | None = None) -> dict:
    """``learning``: values of ``POLICY_LEARNING`` by name (the rest: the recorded scenario's)."""
    from homeo_decision import codec
    from homeo_decision.agent import DecisionCore
    from homeo_decision.checkpoint import load_table as load
    from homeo_decision.reward import reward

    sc = run.sc
    core = DecisionCore(sc, 0, **(learning or {}))
    load(core.q, q_table)
    acts = sc.action_names
    drives = run.by_tick("drives")
    drives_final = run.by_tick("drives", final=True)
    actions = run.by_tick("action")
    span_action = sc.open.reward_span == "action"
    n = agree = 0
    p_sum = w_sum = wr_sum = r_sum = 0.0
    n_r = 0
    for k in sorted(actions):
        a_name = actions[k]["action"]
        if a_name is None or k not in drives:
            continue  # nothing chosen (a timeout): nothing to compare
        code, dv, inten, m_dom = codec.perception_from_fields(sc, drives[k])[0]
        p = core.percept(code, dv, inten, m_dom)
        valid = list(sc.c.valid[code])
        a = acts.index(a_name)
        if a not in valid:
            continue
        probs = core.q.probabilities(p.states, valid, core.phase(k).tau)
        pa = probs[valid.index(a)]
        n += 1
        p_sum += pa
        agree += valid[max(range(len(valid)), key=probs.__getitem__)] == a
        nxt = drives.get(k + 1) or drives_final.get(k + 1)  # tick k+1 perceived what k's action did
        if nxt is None or (nxt.get("outcome") or {}).get("action") != a_name:
            continue
        after = nxt.get("after_action") if span_action and nxt.get("after_action") else nxt["drives"]
        r = reward(p.drives, [after[d] for d in sc.drive_names], core.weights, core.bonus_drive(p), core.xi,
                   nxt["outcome"]["feedback"], core.f)
        n_r += 1
        r_sum += r
        w_sum += pa
        wr_sum += pa * r
    if not n:
        raise BagError(f"{run.path}: no recorded choice to compare with")
    return {"ticks": n, "agreement": agree / n, "p_robot_choice": p_sum / n, "rewarded_ticks": n_r,
            "expected_reward": wr_sum / w_sum if w_sum else None, "recorded_reward": r_sum / n_r if n_r else None,
            **{s.name: getattr(core, s.name) for s in POLICY_LEARNING}, "q_table": q_table}


def format_eval(res: dict) -> str:
    f = lambda v: "n/a" if v is None else f"{v:.4f}"  # noqa: E731
    return "\n".join([
        f"policy {res['q_table']} (DoD {res[DOD.name]:g}, xi {res[XI.name]:g}) on {res['ticks']} recorded choices:",
        f"  chooses the robot's action (most likely)  : {res['agreement']:.1%}",
        f"  mean probability of the robot's action    : {res['p_robot_choice']:.4f}",
        f"  expected reward on the record (Eq 3.18)   : {f(res['expected_reward'])}  "
        f"(recorded mean {f(res['recorded_reward'])}, {res['rewarded_ticks']} ticks)",
    ])
