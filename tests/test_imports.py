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


def fresh(code: str) -> str:
    """stdout of code run in a fresh interpreter from the repository's root."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    return done.stdout


def test_import_connenv_registers_every_spec_from_the_generated_table():
    """connenv/envs/ids.py is Gymnasium's registration of exactly the specs (python -m connenv.envs.spec writes it),
    and import connenv registers those ids as the specs would."""
    import gymnasium as gym

    from connenv.envs import spec as specs
    from connenv.envs.ids import IDS

    assert IDS == [specs.registration(spec) for spec in specs.discover()], "stale: run python -m connenv.envs.spec"
    assert [entry["id"] for entry in IDS] == list(specs.registry)
    for entry in IDS:
        registered = gym.registry[entry["id"]]
        assert (registered.entry_point, registered.vector_entry_point) == (entry["entry_point"],
                                                                             entry["vector_entry_point"])
        assert (registered.max_episode_steps, registered.kwargs) == (entry["max_episode_steps"], entry["kwargs"])


def test_import_connenv_loads_neither_an_env_module_nor_scipy_nor_the_applications():
    """import connenv registers its ids and loads no env module, scipy, sympy, jax or agents (the import's time is
    python -m connenv.bench import's to print); making an id loads its module and names its class."""
    loaded = fresh(
        "import sys, connenv\n"
        "print(sorted(m for m in sys.modules if m.partition('.')[0] in ('scipy', 'sympy', 'jax', 'agents')\n"
        "    or m.startswith('connenv.') and m not in ('connenv.envs', 'connenv.envs.ids')))\n"
        "import gymnasium as gym\n"
        "print(gym.make('connenv/BeadOnBar-v1').unwrapped.name)\n"
    ).split("\n")
    assert loaded[:2] == ["[]", "BeadOnBar"], loaded


def test_the_library_never_imports_the_applications():
    """connenv is the library and agents its applications (controllers, training): no module of connenv imports
    agents, at its top or inside a function."""
    found, _ = graph()
    importers = [f"{name} imports {module}" for name in found if name.partition(".")[0] == "connenv"
                 for module, *_ in found[name] if module.partition(".")[0] == "agents"]  # fmt: skip
    assert not importers, importers


def test_the_import_benchmark_prints_the_median_and_refuses_a_bad_module(capsys):
    import pytest

    from connenv.bench import import_time

    import_time.main(["--runs", "1"])
    printed = capsys.readouterr().out
    assert printed.startswith("import connenv: median ") and "import gymnasium alone" in printed
    assert "imports scipy" not in printed
    for bad in ("os; print(1)", "no_such_module_here"):
        with pytest.raises(ValueError, match="--module"):
            import_time.main(["--module", bad, "--runs", "1"])
