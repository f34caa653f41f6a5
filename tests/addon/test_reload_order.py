"""F3 > Reload Scripts reloads the add-on's modules in ``RELOAD_ORDER``
(addon/glint/__init__.py): a module left out keeps its old code after a reload,
and one reloaded before a module it imports binds the stale one. Read from the
source (the package's __init__ needs bpy to import)."""
import ast
import os

from glint_addon_helpers import ADDON


def _reload_order():
    tree = ast.parse(open(os.path.join(ADDON, "__init__.py"), encoding="utf-8").read())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "RELOAD_ORDER" for t in node.targets):
            return [ast.literal_eval(e) for e in node.value.elts]
    raise AssertionError("no RELOAD_ORDER in addon/glint/__init__.py")


def _modules():
    names = set()
    for folder, _, files in os.walk(ADDON):
        for f in files:
            if f.endswith(".py"):
                rel = os.path.relpath(os.path.join(folder, f), ADDON)[:-3].replace(os.sep, ".")
                names.add(rel[:-len(".__init__")] if rel.endswith(".__init__") else rel)
    names.discard("__init__")
    return names


def _imports_of(module):
    """The package's modules ``module`` imports at its top level (relative imports)."""
    path = os.path.join(ADDON, *module.split(".")) + ".py"
    if not os.path.exists(path):
        path = os.path.join(ADDON, *module.split("."), "__init__.py")
    package = module.rsplit(".", 1)[0] if "." in module and not path.endswith("__init__.py") else (
        module if path.endswith("__init__.py") else "")
    out = set()
    for node in ast.parse(open(path, encoding="utf-8").read()).body:
        if isinstance(node, ast.ImportFrom) and node.level:
            base = package.split(".") if package else []
            base = base[:len(base) - (node.level - 1)] if node.level > 1 else base
            prefix = ".".join(base + ([node.module] if node.module else []))
            for alias in node.names:
                full = f"{prefix}.{alias.name}" if prefix else alias.name
                out.add(full if full in _modules() else prefix)
    return {m for m in out if m in _modules()}


def test_every_module_is_reloaded():
    order = _reload_order()
    assert len(order) == len(set(order))
    assert set(order) == _modules(), f"missing {_modules() - set(order)}, unknown {set(order) - _modules()}"


def test_a_module_is_reloaded_after_what_it_imports():
    order = _reload_order()
    for i, module in enumerate(order):
        late = [m for m in _imports_of(module) if m != module and order.index(m) > i]
        assert not late, f"{module} is reloaded before {late}, which it imports"
