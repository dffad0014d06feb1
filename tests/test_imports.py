"""The packages' import graph: modules that build on each other without circles, private names that stay private,
and packages that never import the training script (train.py is a command; its logic is agents.train)."""

from __future__ import annotations

import ast
import graphlib
import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("connenv", "agents")


def modules():
    """{dotted name: parsed source} of every module of the packages."""
    found = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            found[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = ast.parse(path.read_text())
    return found


def imports(name, tree, known):
    """(module, name taken from it or None, {name bound: the module it is}) for every import of the module, at its top
    or inside a function (an import deferred into a function ties the two modules together all the same)."""
    package = name if any(other.startswith(f"{name}.") for other in known) else name.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                top = alias.name.partition(".")[0]  # import a.b binds a
                yield alias.name, None, {alias.asname: alias.name} if alias.asname else {top: top}
        elif isinstance(node, ast.ImportFrom):
            base = importlib.util.resolve_name("." * node.level + (node.module or ""), package)
            for alias in node.names:
                child = f"{base}.{alias.name}"  # from package import module
                yield (child, None, {alias.asname or alias.name: child}) if child in known else (base, alias.name, {})


def graph():
    known = modules()
    return {name: list(imports(name, tree, known)) for name, tree in known.items()}, known


def test_the_packages_import_each_other_without_a_circle():
    found, known = graph()
    edges = {name: {module for module, *_ in found[name] if module in known and module != name} for name in found}
    try:
        tuple(graphlib.TopologicalSorter(edges).static_order())
    except graphlib.CycleError as error:
        raise AssertionError(f"import circle: {' -> '.join(reversed(error.args[1]))}") from None


def dotted(node):
    """'a.b.c' of the expression a.b.c, else None."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts, node = [node.attr, *parts], node.value
    return ".".join([node.id, *parts]) if isinstance(node, ast.Name) else None


def test_no_module_takes_another_modules_private_names():
    found, known = graph()
    taken = [f"{name} takes {module}.{private}" for name in found for module, private, _ in found[name]
             if module in known and (private or "").startswith("_")]  # fmt: skip
    for name, tree in known.items():  # module._name, on a module imported whole
        bound = {as_name: module for *_, binding in found[name] for as_name, module in binding.items()}
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__"):
                head, _, rest = (dotted(node.value) or "").partition(".")
                if ".".join(filter(None, [bound.get(head, "?"), rest])) in known:
                    taken.append(f"{name} reads {dotted(node)}")
    assert not taken, taken


def test_nothing_in_the_packages_imports_the_training_script():
    found, _ = graph()
    importers = [name for name in found for module, *_ in found[name] if module.partition(".")[0] == "train"]
    assert not importers, f"{importers} import the top-level train.py; its logic is agents.train"
