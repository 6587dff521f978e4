"""The test suite's own rules (issue 32): checks that can fail. No xfail that can pass unnoticed (``xfail_strict``
and no ``strict=False``), no assert whose check sits in its message, no ``except Exception`` (or bare ``except``)
in a test that neither re-raises nor asserts."""

from __future__ import annotations

import ast
import tomllib
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def _trees():
    for f in sorted(TESTS.glob("*.py")):
        yield f.name, ast.parse(f.read_text(), str(f))


def test_every_xfail_is_strict():
    cfg = tomllib.loads((TESTS.parent / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    assert cfg.get("xfail_strict") is True
    loose = [(name, n.lineno) for name, tree in _trees() for n in ast.walk(tree) if isinstance(n, ast.keyword)
             and n.arg == "strict" and isinstance(n.value, ast.Constant) and n.value.value is False]
    assert loose == []


def test_no_assert_keeps_its_check_in_the_message():
    def a_check(m):
        return isinstance(m, (ast.Compare, ast.BoolOp)) or (isinstance(m, ast.UnaryOp) and isinstance(m.op, ast.Not))

    found = [(name, n.lineno) for name, tree in _trees() for n in ast.walk(tree)
             if isinstance(n, ast.Assert) and (a_check(n.msg) or isinstance(n.test, ast.Tuple))]
    assert found == []


def test_no_test_swallows_every_exception():
    def broad(h):
        return h.type is None or (isinstance(h.type, ast.Name) and h.type.id in ("Exception", "BaseException"))

    def handled(h):
        return any(isinstance(n, (ast.Raise, ast.Assert)) for n in ast.walk(ast.Module(body=h.body, type_ignores=[])))

    found = [(name, h.lineno) for name, tree in _trees() for h in ast.walk(tree)
             if isinstance(h, ast.ExceptHandler) and broad(h) and not handled(h)]
    assert found == []
