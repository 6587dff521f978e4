"""``--human person``: a person plays the human through ``homeo/human_input``.

The decoder is fuzzed (hostile input: a reason, never a crash); ``PersonHuman`` is driven behind the
environment boundary without ROS; then the graph is driven over DDS by publishing human inputs:
praise lowers the serving drive, a proposal triggers the pseudo update, silence is no intention.
"""

from __future__ import annotations

import json
import queue

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from homeo_decision import codec
from homeo_msgs_py.human_input import HumanInput, decode_human_input
from homeo_msgs_py.schemas import Rejected

# -- decoding -----------------------------------------------------------------------------------
_json = st.recursive(st.none() | st.booleans() | st.integers() | st.floats(allow_nan=True) | st.text(max_size=12),
                     lambda kids: st.lists(kids, max_size=3) | st.dictionaries(st.text(max_size=10), kids, max_size=3),
                     max_leaves=8)


@settings(max_examples=300, deadline=None)
@given(st.one_of(st.text(max_size=80), _json.map(json.dumps),
                 st.dictionaries(st.sampled_from(["intention", "feedback", "proposal", "schema", "version", "tick",
                                                  "extra"]), _json, max_size=4).map(json.dumps)))
def test_any_text_decodes_to_an_input_or_a_one_line_reason(thesis, text):
    voc = codec.vocabulary(thesis)
    try:
        got = decode_human_input(text, voc)
    except Rejected as exc:
        assert str(exc) and "\n" not in str(exc)
        return
    assert isinstance(got, HumanInput)
    assert got.feedback in (-1, 0, 1)
    assert got.intention is None or got.intention in thesis.intention_names
    assert got.proposal is None or got.proposal in thesis.action_names


@settings(max_examples=100, deadline=None)
@given(intention=st.sampled_from([None, "none", "light", "music"]), feedback=st.sampled_from([None, "praise", "scold", 1, -1, 0]),
       proposal=st.sampled_from([None, "LightOn", "Play"]), envelope=st.booleans())
def test_valid_inputs_decode_to_what_they_say(thesis, intention, feedback, proposal, envelope):
    msg = {"intention": intention, "feedback": feedback, "proposal": proposal}
    if envelope:
        msg.update(schema="homeo/human_input", version=1, run=0, tick=7, stamp=1.0)
    fb = {None: 0, "praise": 1, "scold": -1}.get(feedback, feedback)
    voc = codec.vocabulary(thesis)
    if proposal is not None and fb == 1:
        with pytest.raises(Rejected, match="proposal"):
            decode_human_input(json.dumps(msg), voc)
        return
    got = decode_human_input(json.dumps(msg), voc)
    assert got == HumanInput(None if intention in (None, "none") else intention, True, fb, proposal)


@pytest.mark.parametrize("text,words", [
    ('{"feedback": "great"}', "Invalid enum value 'great' - at `\\$.feedback`"),
    ('{"intention": "pizza"}', "Invalid enum value 'pizza' - at `\\$.intention`"),
    ('{"proposal": "Fly"}', "Invalid enum value 'Fly' - at `\\$.proposal`"),
    ('{"mood": "happy"}', "Object contains unknown field `mood`"), ("{}", "says nothing"),
    ('{"schema": "homeo/action", "feedback": "praise"}', "schema"), ("[1]", "Expected `object`, got `array`"),
    ("x" * 5000, "too long"),
])
def test_mistakes_are_named(thesis, text, words):
    with pytest.raises(Rejected, match=words):
        decode_human_input(text, codec.vocabulary(thesis))


# -- the person behind the environment boundary (no ROS) ----------------------------------------
def test_person_human_waits_then_answers_and_silence_is_no_intention(thesis):
    from homeo_sim.environment import SimEnvironment
    from homeo_sim.person import PersonHuman

    voc = codec.vocabulary(thesis)
    person = PersonHuman(thesis, 0, timeout=0.2)
    env = SimEnvironment(thesis, 0, human=person)
    say = lambda **kw: person.inbox.put(decode_human_input(json.dumps(kw), voc))  # noqa: E731
    light = thesis.intention_names.index("light")
    say(intention="light")
    env.start()
    assert env.observe().intention == light
    say(feedback="scold", proposal="LightOn", intention="light")
    out = env.step(thesis.action_names.index("Play"))
    assert (out.feedback, thesis.action_names[out.proposal], out.true_intention) == (-1, "LightOn", light)
    assert env.observe().intention == light  # the wish sent with the answer is the next tick's
    say(feedback="praise")
    out = env.step(thesis.action_names.index("LightOn"))
    assert out.feedback == 1 and out.satisfied
    assert env.observe().intention == 0  # nobody spoke for the next tick's wish: no intention
    assert person.silent == 1  # the wish of tick 2 timed out
    out = env.step(thesis.action_names.index("Chat"))  # no wish: no wait for an answer
    assert out.feedback == 0 and out.true_intention == 0
    assert person.silent == 2  # the wish of tick 3 timed out; no wait for tick 2's answer (that would be 3)


# -- the graph, driven by a person's messages ------------------------------------------------------
@pytest.mark.ros
def test_a_person_drives_the_graph_praise_proposal_and_silence(tmp_path, thesis):
    from std_srvs.srv import Trigger

    from rosgraph import Probe, fresh_domain, sim_graph, sim_opts

    
    d = fresh_domain()
    q_file = tmp_path / "q.json"
    opts = sim_opts(iterations=3, intention="oracle", human="person", human_timeout=1.5, save_q=str(q_file),
                      data_dir=str(tmp_path))
    with sim_graph(opts, d):
        probe = Probe(d)
        try:
            acts, outs, drives = probe.collect("/homeo/action"), probe.collect("/homeo/outcome"), probe.collect("/homeo/drives")
            status = probe.collect("/homeo/run_status")
            pub = probe.publisher("/homeo/human_input")
            # the world waits for the person's first wish (state "starting"); discovery settles both ways
            heard = lambda: all(probe.node.count_publishers(f"/homeo/{t}") for t in ("action", "outcome", "drives"))  # noqa: E731
            assert probe.spin_until(lambda: probe.node.count_subscribers("/homeo/human_input") >= 1 and heard()
                                    and status and status[-1]["state"] == "starting", 60.0)
            probe.spin_until(lambda: False, 0.5)
            say = lambda **kw: pub(json.dumps(kw))  # noqa: E731
            say(intention="light")  # tick 0's wish (the world waits for it before tick 0)
            assert probe.spin_until(lambda: len(acts) >= 1, 60.0), "no action at tick 0"
            proposal = next(a for a in ("LightOn", "Play", "Chat", "LightOff") if a != acts[0]["action"])
            say(feedback="scold", proposal=proposal, intention="light")  # the answer, and tick 1's wish
            assert probe.spin_until(lambda: len(acts) >= 2, 20.0)
            # the decision learned from tick 0 before choosing tick 1: the proposal, never performed,
            # can only have moved by the pseudo update (Eq 3.23)
            r = probe.call(Trigger, "/homeo_decision/save_q", Trigger.Request())
            assert r.success, r.message
            say(feedback="praise")
            # tick 2: nobody speaks; after the timeout it is a tick without a wish
            assert probe.spin_until(lambda: len(acts) >= 3 and len(outs) >= 3 and len(drives) >= 3, 30.0)
        finally:
            probe.close()
    by = lambda xs: {m["tick"]: m for m in xs}  # noqa: E731
    outs, drives = by(outs), by(drives)
    assert (outs[0]["feedback"], outs[0]["proposal"], outs[0]["truth"]["intention"]) == (-1, proposal, "light")
    assert drives[1]["outcome"]["proposal"] == proposal
    tables = json.loads(q_file.read_text())["tables"]
    moved = [v[proposal] for tbl in tables.values() for v in tbl.values() if proposal in v and v[proposal] != 0.0]
    assert moved, f"no Q value of the proposal {proposal} changed"
    assert outs[1]["feedback"] == 1 and drives[2]["outcome"]["feedback"] == 1
    assert drives[2]["drives"]["NAch"] < drives[1]["drives"]["NAch"], sorted(drives)  # praise -10 beats growth +3
    assert outs[2]["truth"] == {"intention": "none", "expressed": False, "satisfied": False}
    assert outs[2]["feedback"] == 0
