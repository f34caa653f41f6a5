"""glint_core.pyi, the type stub the build writes beside the module: it parses,
declares every public name of the module and nothing else, and its functions take
the keywords the module takes."""
import ast
import inspect
import os
from pathlib import Path

import pytest

import glint_core


@pytest.fixture(scope="module")
def stub():
    path = Path(glint_core.__file__).with_name("glint_core.pyi")
    if not path.exists() and "libasan" in os.environ.get("LD_PRELOAD", ""):
        pytest.skip("a sanitized build writes no stub (bindings/python/CMakeLists.txt)")
    assert path.exists(), f"no stub beside the module: {path} (GLINT_PYTHON_STUB off?)"
    return ast.parse(path.read_text())


def _declared(tree):
    out = {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            out[node.name] = node
        elif isinstance(node, ast.AnnAssign):
            out[node.target.id] = node
    return out


def test_the_stub_names_the_module_exactly(stub):
    public = {n for n in dir(glint_core) if not n.startswith("_")}
    assert set(_declared(stub)) == public


def test_the_stub_says_what_each_name_is(stub):
    for name, node in _declared(stub).items():
        obj = getattr(glint_core, name)
        if inspect.isclass(obj):
            assert isinstance(node, ast.ClassDef), name
        elif callable(obj):
            assert isinstance(node, ast.FunctionDef), name
        else:
            assert isinstance(node, ast.AnnAssign), name


def test_stub_signatures_are_the_bindings(stub):
    """The keywords the docs and the add-on use, written out here, are in the stub."""
    functions = _declared(stub)
    def names(fn):
        node = functions[fn]
        return [a.arg for a in node.args.args], [a.arg for a in node.args.kwonlyargs]
    positional, keywords = names("trace")
    assert positional == ["position", "normal", "projection"]
    assert {"march", "blocked", "back_position", "max_distance", "resolution", "steps", "thickness",
            "backend", "memory_limit_mb"} <= set(keywords)
    positional, keywords = names("composite_layers")
    assert positional == ["position", "normal", "specular", "projection"]
    assert {"march", "blocked", "back_position"} <= set(keywords)
    assert ast.unparse(functions["trace"].returns) == "numpy.typing.NDArray[numpy.float32]"
    assert ast.unparse(functions["presets"].returns) == "dict"


def test_stub_classes_declare_their_methods(stub):
    """A class the module defines (not an exception) has its constructor, methods and
    properties in the stub, with the bindings' keywords."""
    scene = _declared(stub)["ExactScene"]
    members = {n.name: n for n in scene.body if isinstance(n, ast.FunctionDef)}
    assert {"__init__", "update", "seen_from", "last_update", "vertex_count", "triangle_count"} <= set(members)
    init = members["__init__"].args
    assert [a.arg for a in init.args] == ["self", "vertices", "triangles"]
    assert [a.arg for a in init.kwonlyargs] == ["threads", "memory_limit_mb"]
    assert ast.unparse(members["seen_from"].returns) == "ExactView"
    assert any(ast.unparse(d) == "property" for d in members["last_update"].decorator_list)
