"""The package's layers: imports point down, and the heavy libraries stay where they belong.

The table is the one in docs/development.md. A new module must be placed in it (the test fails on a module
it does not know), so the architecture is decided when a file is added, not discovered later.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "sins"

#: Rank of each module or package (longest prefix wins); a module may import only lower ranks, or its
#: own package's modules.
RANKS = {
    "sins": 0,
    "sins.errors": 0,
    "sins.core": 0,  # rotations, the Earth, Allan variances, row-wise arithmetic, the data model
    "sins.nav": 1,
    "sins.imu": 2,
    "sins.io": 3,
    "sins.aiding": 4,
    "sins.compensation": 5,
    "sins.gap": 5,
    "sins.characterise": 5,
    "sins.scenario": 6,
    "sins.runs": 7,
    "sins.unit_gap": 8,  # a unit's recordings diagnosed: over gap, compensation's intervals and the readings
    "sins.campaign": 8,
    "sins.viz": 9,
    "sins.cli": 10,
}

#: Third-party libraries confined to the modules that need them.
CONFINED = {
    "rerun": {"sins.viz.viewer"},
    "matplotlib": {"sins.viz.plots"},
    "torch": {"sins.compensation.mlp", "sins.compensation.window_net"},
    "minisom": {"sins.compensation.kohonen_pure"},
    "dask": {"sins.campaign.engine"},
    "distributed": {"sins.campaign.engine"},
    "rosbags": {"sins.io.bags"},
    "filterpy": {"sins.aiding.ekf"},
}


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        if "scenarios" in path.relative_to(PACKAGE).parts:
            continue
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _key(module: str) -> str:
    """The longest prefix of ``module`` in :data:`RANKS` ("" if none)."""
    parts = module.split(".")
    for n in range(len(parts), 0, -1):
        if ".".join(parts[:n]) in RANKS and (n > 1 or len(parts) == 1):
            return ".".join(parts[:n])
    return ""


@functools.cache  # by the text, not the path: the rules' own tests rewrite one file
def _parsed(text: str) -> ast.Module:
    """A module's syntax tree, parsed once for every test that reads it (none changes it)."""
    return ast.parse(text)


def _imports(module: str, path: Path) -> list[tuple[int, str]]:
    """Every imported module name, at any depth (imports inside functions count)."""
    found = []
    for node in ast.walk(_parsed(path.read_text())):
        if isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            # ``from sins.gap import lattice`` imports the submodule; ``from sins.gap import diagnose``
            # the package.
            for a in node.names:
                sub = f"{node.module}.{a.name}"
                found.append((node.lineno, sub if sub in MODULES else node.module))
    return found


MODULES = _modules()


def test_every_module_has_a_layer():
    assert {m: _key(m) for m in MODULES if not _key(m)} == {}


def test_layers_are_whole_numbers():
    """A module squeezed between two layers (6.5, 6.8) is a package that is missing: ranks are integers."""
    assert {k: r for k, r in RANKS.items() if not isinstance(r, int)} == {}


#: The modules that may sit loose in ``sins/`` beside the packages (the front door aside): what every
#: layer raises. Everything else lives in the package that names its domain.
LOOSE = {"sins.errors"}


def test_the_folders_are_the_architecture():
    loose = {m for m in MODULES if m.count(".") == 1 and not MODULES[m].name == "__init__.py"}
    loose -= {m for m in loose if (PACKAGE / m.split(".")[1]).is_dir()}  # packages
    assert loose == LOOSE
    assert len(LOOSE) <= 2


def _package(module: str) -> str:
    return ".".join(module.split(".")[:2])


def _violations(module: str, path: Path) -> list[str]:
    rank = RANKS[_key(module)]
    wrong = []
    for line, target in _imports(module, path):
        if not target.startswith("sins") or target == module:
            continue
        t_rank = RANKS[_key(target)]
        # Side by side (compensation and gap) is not below: neither may import the other.
        beside = t_rank == rank and rank > 0 and _package(target) != _package(module)
        if t_rank > rank or beside:
            wrong.append(f"line {line}: {target} (layer {t_rank}) from layer {rank}")
    return wrong


#: The package's front door, ``sins/__init__.py``, names entry points of every layer, but imports them
#: lazily or for type checkers only (``tests/test_api.py`` holds that): it is not a layer.
FACADE = "sins"


@pytest.mark.parametrize("module", sorted(m for m in MODULES if m != FACADE))
def test_imports_point_down_the_layers(module: str):
    assert _violations(module, MODULES[module]) == []


def _graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    """Each module's imports of other modules of ``sins`` (imports inside functions included)."""
    return {m: {t for _, t in _imports(m, p) if t in modules and t != m} for m, p in modules.items()}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The import cycles of ``graph``: its strongly connected components of more than one module
    (Tarjan's algorithm), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(m: str) -> None:
        index[m] = low[m] = len(index)
        stack.append(m)
        for t in sorted(graph.get(m, ())):
            if t not in index:
                visit(t)
                low[m] = min(low[m], low[t])
            elif t in stack:
                low[m] = min(low[m], index[t])
        if low[m] == index[m]:
            part = []
            while True:
                t = stack.pop()
                part.append(t)
                if t == m:
                    break
            if len(part) > 1:
                found.append(sorted(part))

    for m in sorted(graph):
        if m not in index:
            visit(m)
    return sorted(found)


def test_no_import_cycles():
    """No module of sins imports, at any depth and however late, a module that imports it back. The root
    package's own imports are left out: it loads its entry points on first use (PEP 562) and imports
    nothing of sins when imported (``tests/test_api.py``), so its modules may take ``__version__`` from it."""
    graph = _graph(MODULES)
    graph["sins"] = set()
    assert _cycles(graph) == []


def test_the_cycle_rule_catches_a_deferred_cycle(tmp_path):
    """A cycle closed by an import inside a function is found; a chain without one is not."""
    a, b, c = tmp_path / "a.py", tmp_path / "b.py", tmp_path / "c.py"
    a.write_text("from sins.imu import stream\n")
    b.write_text("def f():\n    from sins.imu import model\n")
    c.write_text("from sins.core import rotation\n")
    fake = {"sins.imu.model": a, "sins.imu.stream": b, "sins.core.rotation": c, "sins.core.series": c}
    assert _cycles(_graph(fake)) == [["sins.imu.model", "sins.imu.stream"]]
    b.write_text("from sins.core import rotation\n")
    assert _cycles(_graph(fake)) == []


@pytest.mark.parametrize("library", sorted(CONFINED))
def test_heavy_libraries_are_confined(library: str):
    users = {m for m in MODULES for _, t in _imports(m, MODULES[m]) if t.split(".")[0] == library}
    assert users <= CONFINED[library], sorted(users - CONFINED[library])


def test_the_layer_rule_catches_upward_and_sideways_imports(tmp_path):
    """The check can fail: rotations that import the integrator (lazily, inside a function) and a
    compensation module that imports the gap diagnosis are caught; the integrator importing rotations
    is not."""
    fake = tmp_path / "fake.py"
    fake.write_text("def f():\n    from sins.nav import strapdown\n")
    assert _violations("sins.core.rotation", fake) == ["line 2: sins.nav.strapdown (layer 1) from layer 0"]
    fake.write_text("from sins.gap import diagnose\n")
    assert _violations("sins.compensation.mlp", fake) == ["line 1: sins.gap (layer 5) from layer 5"]
    fake.write_text("from sins.core import rotation\n")
    assert _violations("sins.nav.strapdown", fake) == []


def test_every_package_is_installed():
    """A package missing from pyproject's list would work in the editable install and vanish from a wheel."""
    import tomllib

    listed = set(
        tomllib.loads((PACKAGE.parent / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]
    )
    on_disk = {".".join(p.parent.relative_to(PACKAGE.parent).parts) for p in PACKAGE.rglob("__init__.py")}
    assert on_disk <= listed, sorted(on_disk - listed)


#: A function's body (docstring aside) fits on a screen; these are the reasoned exceptions.
SCREEN_LINES = 65
LONG_ON_PURPOSE = {
    # The integrator's numba loop: its steps share scalar state numba keeps in registers (see its comment).
    "sins.nav.strapdown._kernel",
}


def _long_functions(module: str, path: Path) -> list[str]:
    """Functions of ``module`` whose body, docstring aside, is longer than :data:`SCREEN_LINES`."""
    found = []
    for node in ast.walk(_parsed(path.read_text())):
        if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        body = node.body
        if isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) and len(body) > 1:
            body = body[1:]
        lines = (body[-1].end_lineno or body[-1].lineno) - body[0].lineno + 1
        name = f"{module}.{node.name}"
        if lines > SCREEN_LINES and name not in LONG_ON_PURPOSE:
            found.append(f"{name}: {lines} lines")
    return found


def test_functions_fit_on_a_screen():
    assert [f for m, p in MODULES.items() for f in _long_functions(m, p)] == []


def test_the_screen_rule_catches_a_long_function(tmp_path):
    fake = tmp_path / "fake.py"
    fake.write_text('def f():\n    """Doc."""\n' + "    x = 1\n" * (SCREEN_LINES + 1))
    assert _long_functions("sins.fake", fake) == [f"sins.fake.f: {SCREEN_LINES + 1} lines"]
    fake.write_text('def f():\n    """Doc."""\n' + "    x = 1\n" * SCREEN_LINES)
    assert _long_functions("sins.fake", fake) == []


#: A module fits in a reader's head: no module of ``sins/`` is longer than this many lines.
MODULE_LINES = 700
#: Modules over the limit for now, each with its reason; one that comes under the limit must leave.
LONG_MODULES_FOR_NOW: set[str] = set()  # none: every module of sins/ fits


def _long_modules(modules: dict[str, Path]) -> dict[str, int]:
    """The modules of ``modules`` longer than :data:`MODULE_LINES`, with their lengths."""
    lengths = {m: len(p.read_text().splitlines()) for m, p in modules.items()}
    return {m: n for m, n in lengths.items() if n > MODULE_LINES}


def test_modules_fit_in_a_readers_head():
    long = _long_modules(MODULES)
    assert {m: n for m, n in long.items() if m not in LONG_MODULES_FOR_NOW} == {}
    assert sorted(LONG_MODULES_FOR_NOW - set(long)) == [], "no longer long: drop from LONG_MODULES_FOR_NOW"


#: A command's module parses its options, calls the library and prints: the work is the library's.
CLI_MODULE_LINES = 250


def test_commands_stay_thin():
    lengths = {m: len(p.read_text().splitlines()) for m, p in MODULES.items() if m.startswith("sins.cli.")}
    assert {m: n for m, n in lengths.items() if n > CLI_MODULE_LINES} == {}


def test_the_size_rule_catches_a_long_module(tmp_path):
    fake = tmp_path / "fake.py"
    fake.write_text("x = 1\n" * (MODULE_LINES + 1))
    assert _long_modules({"sins.fake": fake}) == {"sins.fake": MODULE_LINES + 1}
    fake.write_text("x = 1\n" * MODULE_LINES)
    assert _long_modules({"sins.fake": fake}) == {}
