"""The field test (thesis Section 4.3, Tables 4.7 and 4.8) on the stand-in Pepper over libqi.

The Q-tables are the ends of the default simulation (5000 iterations, seed 0) at DoD 0.25 and
at DoD 0; the robots start nearly depleted and meet the same scripted user.
"""

from __future__ import annotations

import json

import pytest

qi = pytest.importorskip("qi")

from pepper_bridge import field  # noqa: E402
from pepper_bridge.user import load_script  # noqa: E402

pytestmark = pytest.mark.qi
qi.logging.setLevel(qi.logging.WARNING)
SEEDS = (0, 1, 2)
NEVER = 100  # first_attach of a robot that never plugs in during the session


@pytest.fixture(scope="module")
def qtables(tmp_path_factory):
    d = tmp_path_factory.mktemp("q")
    return {label: str(field.train_q(d / f"{label}.json", dod)) for label, dod in field.DODS}


def run_pair(script, seed, qtables, thesis):
    return [field.run_field(script, dod, seed, qtables[label], label=label, scenario=thesis)
            for label, dod in field.DODS]


# Q-tables trained on several seeds: with one training seed the comparison is one draw of two Q-tables
# (issue 15, third stage: trained on seed 0 alone, the two robots tied 39 to 39 over sessions 0-2 with the
# adopted block; over training seeds 0-5 x sessions 0-2 the dedicated robot satisfied 241 against 227,
# and 241/229 and 238/229 with the proposal probability at 0.9 and 0.8: docs/PEPPER.md). Issue 25's block:
# over training seeds 0-2 the two tie, 121 to 122 (training seed 2 alone: 39 to 42); over 0-5 the dedicated
# robot satisfies 245 against 233 and the selfish one plugs in first in 6 of 18 sessions against 2 of 18
TRAIN_SEEDS = tuple(range(6))


@pytest.fixture(scope="module")
def qtables_by_seed(tmp_path_factory):
    d = tmp_path_factory.mktemp("qs")
    return {t: {label: str(field.train_q(d / f"{label}-{t}.json", dod, seed=t)) for label, dod in field.DODS}
            for t in TRAIN_SEEDS}


@pytest.mark.slow
def test_dedicated_satisfies_more_and_selfish_charges_earlier(qtables_by_seed, thesis):
    script = load_script("field_user.json")
    n = len(script["interactions"])
    sat = {"dedicated": 0, "selfish": 0}
    attach = {"dedicated": 0, "selfish": 0}
    for tables in qtables_by_seed.values():
        for seed in SEEDS:
            for res in run_pair(script, seed, tables, thesis):
                s = res.summary()
                assert s["intentions"] == n - 2  # two pauses
                sat[res.label] += s["satisfied"]
                # never = one late mark, the same for both robots (it was the run's own length + 1, which
                # differs between the two robots' runs and alone decided the comparison when neither plugs in)
                attach[res.label] += s["first_attach"] or NEVER
    assert sat["dedicated"] > sat["selfish"], sat
    assert attach["selfish"] < attach["dedicated"], attach


def test_table_4_7_user_gives_one_row_per_interaction(qtables, thesis):
    ded, selfish = run_pair("field_dedicated.json", 0, qtables, thesis)
    for res in (ded, selfish):
        assert [r["interaction"] for r in res.log] == list(range(1, 11))
        for r in res.log:
            assert set(r) >= {"m_dom", "intention", "action", "feedback", "proposal"}
            assert r["feedback"] in (-1, 0, 1)
            if r["feedback"] == -1:  # every scolding of this user proposes the desired action
                assert r["proposal"] is not None
        # the intentions the robot recognised are the user's, in the table's order
        assert [r["intention"] for r in res.log] == [
            "light", "no_light", "come", "music", None, "no_music", "light", "music", "leave", None]
        assert res.log[0]["m_dom"] == "Serving"  # NAch 70 + 20 > NEng 65
        assert res.diagnostics["rejected_total"] == 0
    table = field.side_by_side(ded, selfish)
    assert "dedicated (DoD 0.25, seed 0)" in table and "selfish (DoD 0.0, seed 0)" in table


def test_field_run_is_reproducible(qtables, thesis):
    a = field.run_field("field_selfish.json", 0.0, 5, qtables["selfish"], scenario=thesis)
    b = field.run_field("field_selfish.json", 0.0, 5, qtables["selfish"], scenario=thesis)
    strip = lambda log: [{k: r[k] for k in ("m_dom", "intention", "action", "feedback", "proposal", "drives")} for r in log]  # noqa: E731
    assert strip(a.log) == strip(b.log) and a.user_log == b.user_log


def test_field_cli_json(qtables, capsys):
    assert field.main(["--script", "field_selfish.json", "--seeds", "1", "--json",
                       "--q-dedicated", qtables["dedicated"], "--q-selfish", qtables["selfish"]]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [r["summary"]["label"] for r in out[0]["robots"]] == ["dedicated", "selfish"]
    assert all(set(row) >= {"m_dom", "intention", "action", "feedback", "proposal"}
               for r in out[0]["robots"] for row in r["log"])
