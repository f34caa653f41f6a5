"""Write glint_core.pyi, the type stub editors and type checkers read for the
compiled module, from the module itself: pybind11 puts each function's
signature on the first line of its docstring, so the stub cannot drift from
the bindings. Run by the build after linking the module:

    /usr/bin/python3 make_stub.py <folder holding glint_core*.so>

The stub lands beside the module, where a checker looks for it.
"""
from __future__ import annotations

import importlib
import inspect
import os
import re
import sys

# pybind11's names for the types it converts -> annotations a checker knows. A
# `handle` is whatever the binding checks itself at run time (an array, a path,
# a list of layers): Any, with the docstring saying what it takes.
_TYPES = (
    (re.compile(r"numpy\.ndarray\[numpy\.(\w+)\]"), r"numpy.typing.NDArray[numpy.\1]"),
    (re.compile(r"\bhandle\b"), "Any"),
    # The module's own classes, as the stub declares them.
    (re.compile(r"\bglint_core\."), ""),
)


def _annotation(text: str) -> str:
    for pattern, replacement in _TYPES:
        text = pattern.sub(replacement, text)
    return text


def _doc_body(doc: str) -> list:
    lines = doc.strip("\n").splitlines()[1:]
    while lines and not lines[0].strip():
        lines.pop(0)
    return [line.replace('"""', "'''") for line in lines]


def _function(name: str, fn, indent: str = "") -> str:
    doc = fn.__doc__ or ""
    first = doc.splitlines()[0] if doc else ""
    if not first.startswith(name + "("):
        raise SystemExit(f"make_stub: {name}'s docstring does not start with its signature: {first!r}")
    signature = _annotation(first[len(name):])
    return f"{indent}def {name}{signature}:\n" + _body(_doc_body(doc), indent + "    ")


def _body(body: list, indent: str) -> str:
    text = ""
    if body:
        text += indent + '"""' + "\n".join((indent + line).rstrip() for line in body).lstrip() + \
            "\n" + indent + '"""\n'
    return text + indent + "...\n"


def _class(name: str, cls) -> str:
    """A class the module defines: its constructor, methods and read-only properties,
    each from its own docstring (pybind11 starts a property getter's with
    ``(self: ...) -> type``)."""
    doc = (cls.__doc__ or "").strip().replace('"""', "'''")
    text = f"class {name}:\n"
    if doc:
        text += '    """' + "\n".join(("    " + line).rstrip() for line in doc.splitlines()).lstrip() + '\n    """\n'
    for attr, member in vars(cls).items():
        if isinstance(member, property):
            first = (member.fget.__doc__ or "").splitlines()[0] if member.fget.__doc__ else ""
            returns = first.rpartition("->")[2].strip() if "->" in first else "Any"
            text += f"    @property\n    def {attr}(self) -> {_annotation(returns)}:\n"
            lines = (member.__doc__ or "").strip("\n").splitlines()
            text += _body([line.replace('"""', "'''") for line in lines], "        ")
        elif attr == "__init__" and not (member.__doc__ or "").startswith("__init__("):
            continue  # no constructor of its own: made by the module only
        elif attr == "__init__" or (callable(member) and not attr.startswith("_")):
            text += _function(attr, member, "    ")
    return text


def _constant(name: str, value) -> str:
    kind = type(value).__name__
    if isinstance(value, (list, tuple)) and value and all(isinstance(v, str) for v in value):
        kind = f"{kind}[str]" if kind == "list" else f"{kind}[str, ...]"
    return f"{name}: {kind}\n"


def _exception(name: str, cls) -> str:
    base = cls.__mro__[1].__name__
    doc = (cls.__doc__ or "").strip()
    body = f'    """{doc}"""\n' if doc else "    ...\n"
    return f"class {name}({base}):\n{body}"


def stub(module) -> str:
    parts = [f'"""{(module.__doc__ or module.__name__).strip()}"""\n',
             "# Written by bindings/python/make_stub.py from the module: do not edit.\n"
             "from typing import Any, Optional\n\nimport numpy\nimport numpy.typing\n"]
    for name in sorted(n for n in dir(module) if not n.startswith("_")):
        obj = getattr(module, name)
        if inspect.isclass(obj) and issubclass(obj, BaseException):
            parts.append(_exception(name, obj))
        elif inspect.isclass(obj):
            parts.append(_class(name, obj))
        elif callable(obj):
            parts.append(_function(name, obj))
        else:
            parts.append(_constant(name, obj))
    return "\n\n".join(parts)


def main(argv) -> int:
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    folder = os.path.abspath(argv[1])
    sys.path.insert(0, folder)
    module = importlib.import_module("glint_core")
    text = stub(module)
    compile(text, "glint_core.pyi", "exec")  # a stub that does not parse is a build error
    path = os.path.join(folder, "glint_core.pyi")
    with open(path, "w") as f:
        f.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
