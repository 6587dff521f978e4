"""The docs' tables of the declared contracts are the generated ones: docs/GRAPH.md's learning
parameters (``homeo_msgs_py.learning``), docs/FIDELITY.md's open choices
(``homeo_decision.scenario.open_choices``). Regenerate with the functions named in the messages."""

from __future__ import annotations

from pathlib import Path

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_graph_md_has_the_learning_parameters_table_of_the_declaration():
    from homeo_msgs_py.learning import table

    assert table() in (DOCS / "GRAPH.md").read_text(), "regenerate: python -m homeo_msgs_py.learning"


def test_fidelity_md_has_the_open_choices_table_of_the_declaration():
    from homeo_decision.scenario.open_choices import NAMES, table

    text = (DOCS / "FIDELITY.md").read_text()
    assert table() in text, "regenerate: homeo_decision.scenario.open_choices.table()"
    assert all(f"| `{n}` |" in table() for n in NAMES)


def test_architecture_md_has_the_generated_parameter_tables():
    from homeo_decision.world_api import tables
    from homeo_msgs_py.learning import table

    text = (DOCS / "ARCHITECTURE.md").read_text()
    assert table() in text, "regenerate: python -m homeo_msgs_py.learning"
    assert tables() in text, "regenerate: python -m homeo_decision.world_api"


def test_graph_md_has_the_graph_description():
    """Who sends what to whom, and what rides in what (issue 29: the outcome of k-1 in the world and
    observation of k), as the one description says it."""
    from homeo_msgs_py.graph import describe

    assert describe() in (DOCS / "GRAPH.md").read_text(), "regenerate: python -m homeo_msgs_py.graph"
