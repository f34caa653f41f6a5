"""No function of the add-on (addon/glint, logic/ and host/ included) is longer
than MAX_LINES (issue 24): a longer one is split into steps named for what they
do. Counted from the def line to the last line of the body, nested functions
and methods each on their own (and inside their parent's count)."""
import ast
import os

from glint_addon_helpers import ADDON

MAX_LINES = 80


def function_lengths(root=ADDON):
    """(lines, "path:line name") of every function and method under ``root``."""
    out = []
    for folder, _, files in os.walk(root):
        for name in sorted(files):
            if not name.endswith(".py"):
                continue
            path = os.path.join(folder, name)
            with open(path, encoding="utf-8") as f:
                tree = ast.parse(f.read(), path)
            for node in ast.walk(tree):
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    where = f"{os.path.relpath(path, root)}:{node.lineno} {node.name}"
                    out.append((node.end_lineno - node.lineno + 1, where))
    return out


def test_the_count_sees_every_module():
    lengths = function_lengths()
    files = {where.split(":")[0] for _, where in lengths}
    assert {"frame.py", os.path.join("logic", "compositing.py"), os.path.join("host", "nodes.py")} <= files
    assert all(n >= 1 for n, _ in lengths)


def test_no_addon_function_is_longer_than_the_limit():
    long = sorted((n, where) for n, where in function_lengths() if n > MAX_LINES)
    assert not long, f"functions over {MAX_LINES} lines: {long}"
