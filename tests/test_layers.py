"""The package layers of docs/ARCHITECTURE.md, read from the source's imports (every import, also
those inside functions), and no import cycle between modules."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
CORE = ("homeo_msgs_py", "homeo_decision", "homeo_intention", "homeo_sim", "pepper_bridge")  # layers 1-4
FRONT_ENDS = ("homeo_record", "homeo_launch", "homeo_ops", "homeo_topic")  # layer 5: products of their own
PACKAGES = CORE + FRONT_ENDS
# what each package may import besides itself (docs/ARCHITECTURE.md; each package's docstring says it too)
ALLOWED = {
    "homeo_msgs_py": set(),
    "homeo_decision": {"homeo_msgs_py"},
    "homeo_intention": {"homeo_msgs_py", "homeo_decision"},
    "homeo_sim": {"homeo_msgs_py", "homeo_decision", "homeo_intention"},
    "pepper_bridge": {"homeo_msgs_py", "homeo_decision", "homeo_intention"},
    "homeo_record": set(CORE),
    "homeo_launch": set(CORE) | {"homeo_record"},
    "homeo_ops": set(PACKAGES) - {"homeo_ops", "homeo_topic"},
    "homeo_topic": {"homeo_msgs_py", "homeo_decision"},
}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imports(path: Path) -> set[str]:
    """Every module this file imports, absolute (relative imports resolved)."""
    mod = _module_name(path)
    pkg = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            out.add(target)
            for a in node.names:  # ``from pkg import module`` imports a module
                out.add(f"{target}.{a.name}")
    return out


def _graph() -> dict[str, set[str]]:
    files = {_module_name(p): p for p in SRC.rglob("*.py")}
    return {m: {i for i in _imports(p) if i in files} for m, p in files.items()}


def test_the_scan_sees_imports_inside_functions_and_relative_ones():
    imports = _imports(SRC / "homeo_sim" / "cli.py")
    assert "homeo_sim.runner" in imports  # from .runner import ...
    assert "homeo_sim.intention_bench" in imports  # imported inside cmd_bench


@pytest.mark.parametrize("pkg", PACKAGES)
def test_each_package_imports_only_the_layers_below_it(pkg):
    bad = []
    for mod, deps in _graph().items():
        if mod.split(".")[0] != pkg:
            continue
        for d in deps:
            top = d.split(".")[0]
            if top != pkg and top not in ALLOWED[pkg]:
                bad.append(f"{mod} imports {d}")
    assert not bad, "\n".join(sorted(bad))


def test_only_the_operations_tools_import_the_launcher_and_nothing_imports_them():
    """The launcher finds the operations tools' commands through entry points (``homeo_robot.commands``),
    so the tools import it and not the other way round; the package docstrings say what each may import."""
    g = _graph()
    bad = [f"{m} imports {d}" for m, deps in g.items() for d in deps
           if (d.startswith("homeo_launch") and m.split(".")[0] not in ("homeo_launch", "homeo_ops"))
           or (d.startswith("homeo_ops") and not m.startswith("homeo_ops"))]
    assert not bad, "\n".join(bad)
    for pkg in FRONT_ENDS:
        assert "import" in __import__(pkg).__doc__, pkg


def test_no_front_end_names_a_robot():
    """The launcher and the other front ends know no world by name (issue 28): a world's command, launch
    arguments, progress and result come from its declarations; what is left is the default world ``sim``."""
    import re

    hits = [f"{f.relative_to(SRC)}:{i}" for pkg in FRONT_ENDS for f in sorted((SRC / pkg).rglob("*.py"))
            for i, line in enumerate(f.read_text().splitlines(), 1) if re.search(r"pepper|\bday\b|naoqi", line, re.I)]
    assert not hits, hits


def test_the_launcher_is_small():
    lines = sum(len(f.read_text().splitlines()) for f in (SRC / "homeo_launch").rglob("*.py"))
    assert lines <= 2500, lines


def _calls(name: str) -> list[str]:
    """The source files that call ``name(...)`` (a class built, a function called)."""
    out = []
    for f in sorted(SRC.rglob("*.py")):
        for node in ast.walk(ast.parse(f.read_text(), str(f))):
            if isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", None)) == name:
                out.append(str(f.relative_to(SRC)))
                break
    return out


def test_one_world_host_builds_the_lockstep_driver():
    """Every world runs on one host (issue 22): the lockstep driver is built in the world host alone,
    which the world node and the in-memory bus runner share."""
    assert _calls("LockstepDriver") == ["homeo_decision/world_host.py"]
    assert sorted(_calls("WorldHost")) == ["homeo_decision/world_node.py", "homeo_ops/bus.py"]


def test_the_module_import_graph_has_no_cycle():
    g = _graph()
    # a package's __init__ re-exporting its own modules is not a cycle through them
    for m in g:
        g[m] = {d for d in g[m] if not m.startswith(d + ".")}
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        stack.append(m)
        for d in sorted(g.get(m, ()) - {m}):  # a module importing itself (``python -m``'s idiom) is no cycle
            if state.get(d) == 1:
                return stack[stack.index(d):] + [d]
            if d not in state:
                found = visit(d)
                if found:
                    return found
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(g):
        if m not in state:
            cycle = visit(m)
            assert cycle is None, " -> ".join(cycle)


# -- the scenario is data everywhere (issue 10) ------------------------------------------------------
def _docstrings(tree: ast.AST) -> set[int]:
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str):
                out.add(id(first.value))
    return out


def test_no_drive_object_action_or_motivation_name_of_the_thesis_in_code(thesis):
    """String literals (docstrings aside: they cite the thesis) and identifiers of every module:
    no word may be a drive, motivation, object or action name of the thesis scenario, nor a
    prefix of an action name (e.g. a "MoveTo" convention)."""
    import re

    names = set(thesis.drive_names) | set(thesis.motivation_names) | set(thesis.action_names) | set(thesis.objects)
    prefixes = {a[:k] for a in thesis.action_names for k in range(4, len(a))}
    hits = []
    files = sorted(SRC.rglob("*.py"))
    for f in files:
        tree = ast.parse(f.read_text(), str(f))
        docs = _docstrings(tree)
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docs:
                words = set(re.findall(r"[A-Za-z]+", node.value))
                bad = words & names or ({node.value} & prefixes)
            elif isinstance(node, ast.Name):
                bad = {node.id} & names
            elif isinstance(node, ast.Attribute):
                bad = {node.attr} & names
            else:
                continue
            if bad:
                hits.append(f"{f.relative_to(SRC)}:{node.lineno}: {sorted(bad)}")
    assert len(files) > 50
    assert not hits, "\n".join(hits)


def test_the_learning_parameters_are_named_in_one_place():
    """Each learning parameter is declared once (``homeo_msgs_py.learning``): its name is a string
    literal there, and wherever else it is written the code says ``DOD.name`` (issue 22: at most 8
    modules; today one)."""
    from homeo_msgs_py.learning import DOD, GAMMA, PSEUDO_UPDATE, XI

    names = {s.name for s in (DOD, XI, GAMMA, PSEUDO_UPDATE)}
    holders = set()
    for f in sorted(SRC.rglob("*.py")):
        tree = ast.parse(f.read_text(), str(f))
        docs = _docstrings(tree)
        if any(isinstance(n, ast.Constant) and n.value in names and id(n) not in docs for n in ast.walk(tree)):
            holders.add(str(f.relative_to(SRC)))
    assert holders == {"homeo_msgs_py/learning.py"}
