"""The type stub documents the API: every public function, class, method and property has a
docstring, and every documented function names each of its parameters."""

from __future__ import annotations

import ast
import re
from pathlib import Path
from typing import Iterator, Union

import pytest

STUB = Path(__file__).parents[1] / "py_src/modelgap/_modelgap.pyi"

_Def = Union[ast.FunctionDef, ast.AsyncFunctionDef]
_CONSTRUCTORS = ("__init__", "__new__")


def _tree() -> ast.Module:
    return ast.parse(STUB.read_text(encoding="utf-8"), filename=str(STUB))


def _walk(body: list[ast.stmt], prefix: str = "") -> Iterator[tuple[str, ast.AST]]:
    """Every class and function of the stub with its dotted name, classes' members
    included."""
    for node in body:
        if isinstance(node, ast.ClassDef):
            yield prefix + node.name, node
            yield from _walk(node.body, prefix + node.name + ".")
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield prefix + node.name, node


def _params(fn: _Def) -> list[str]:
    """The parameters a caller passes (``self`` and ``cls`` left out)."""
    a = fn.args
    names = [p.arg for p in [*a.posonlyargs, *a.args, *a.kwonlyargs]]
    if a.vararg is not None:
        names.append(a.vararg.arg)
    if a.kwarg is not None:
        names.append(a.kwarg.arg)
    return [n for n in names if n not in ("self", "cls")]


def _needs_docstring(name: str, node: ast.AST) -> bool:
    short = name.rsplit(".", 1)[-1]
    if not short.startswith("_"):
        return True
    # A constructor with parameters documents them.
    return (
        short in _CONSTRUCTORS
        and isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
        and bool(_params(node))
    )


def _documented() -> list[tuple[str, _Def, str]]:
    out = []
    for name, node in _walk(_tree().body):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            doc = ast.get_docstring(node)
            if doc is not None:
                out.append((name, node, doc))
    return out


def test_the_stub_parses_and_has_definitions() -> None:
    names = [name for name, _ in _walk(_tree().body)]
    # Sanity: the walk sees the API (a broken walk would make the other tests pass vacuously).
    for expected in ("explain", "compare", "Recording", "Recording.signal", "ClothWorld.step"):
        assert expected in names
    assert len(names) > 300


def test_every_public_definition_has_a_docstring() -> None:
    missing = [
        name
        for name, node in _walk(_tree().body)
        if _needs_docstring(name, node)
        and isinstance(node, (ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
        and not (ast.get_docstring(node) or "").strip()
    ]
    assert missing == [], f"{len(missing)} without a docstring in {STUB.name}: {missing}"


def test_documented_functions_name_their_parameters() -> None:
    unnamed = []
    for name, fn, doc in _documented():
        for p in _params(fn):
            # As a word: ``t`` must be named, not found inside "the".
            if re.search(rf"(?<![\w]){re.escape(p)}(?![\w])", doc) is None:
                unnamed.append(f"{name}({p})")
    assert unnamed == [], f"parameters not named in their docstring: {unnamed}"


@pytest.mark.parametrize("name", ["explain", "compare"])
def test_the_loop_documents_args_returns_raises(name: str) -> None:
    doc = next(d for n, _, d in _documented() if n == name)
    for section in ("Args:", "Returns:", "Raises:"):
        assert section in doc, f"{name}: no {section} section"
