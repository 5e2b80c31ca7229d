"""The public API: every module says what it exports, and ``import sins`` stays light.

Every module of ``sins/`` has an ``__all__``; a public top-level name (not starting with ``_``) that it
defines is in it, so that what a module promises is what it lists; every listed name exists. ``import
sins`` gives the main entry points and the subpackages lazily: the import itself loads neither sins's
modules nor the heavy libraries, and the entry points (the whole simulate → corrupt → compensate →
integrate path) load no torch, rerun, dask or matplotlib.
"""

from __future__ import annotations

import ast
import importlib
import json
import sys
from pathlib import Path

import pytest
from conftest import run_process

import sins

PACKAGE = Path(__file__).resolve().parents[1] / "sins"

#: Libraries a user pays for only where they use them (the learned networks, the viewer, campaigns, plots).
HEAVY = ("torch", "rerun", "dask", "distributed", "matplotlib")

#: Generic types a module names for its own annotations (``Array = NDArray[np.float64]``): aliases,
#: not part of what the module offers.
_ALIAS_BASES = {"NDArray", "Callable", "Literal", "tuple", "dict", "list", "Mapping", "Sequence", "Iterator"}


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__main__":
            continue  # running it is its whole job: it exports nothing
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


MODULES = _modules()


def _is_alias(value: ast.expr) -> bool:
    if isinstance(value, ast.Subscript):
        base = value.value
        name = base.id if isinstance(base, ast.Name) else base.attr if isinstance(base, ast.Attribute) else ""
        return name in _ALIAS_BASES
    return isinstance(value, ast.Name) and value.id == "Any"


def _top_level(tree: ast.Module) -> tuple[list[str], set[str], list[str] | None]:
    """The names a module defines (aliases aside), every name bound at its top level, and its ``__all__``."""
    defined: list[str] = []
    bound: set[str] = set()
    listed: list[str] | None = None
    for node in tree.body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            defined.append(node.name)
        elif isinstance(node, ast.Assign):
            for target in node.targets:
                if isinstance(target, ast.Name) and target.id == "__all__":
                    listed = list(ast.literal_eval(node.value))
                    continue
                names = [e.id for e in ast.walk(target) if isinstance(e, ast.Name)]  # ``A, B = ...`` too
                bound.update(names)
                if not _is_alias(node.value):
                    defined.extend(names)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            if node.target.id == "__all__" and node.value is not None:  # a package of modules only: ``= []``
                listed = list(ast.literal_eval(node.value))
                continue
            bound.add(node.target.id)
            defined.append(node.target.id)
        elif isinstance(node, ast.Import | ast.ImportFrom):
            bound.update((a.asname or a.name).split(".")[0] for a in node.names)
    bound.update(defined)
    return defined, bound, listed


def test_every_public_name_a_module_defines_is_in_its_all():
    missing, unlisted = {}, []
    for module, path in MODULES.items():
        defined, _, listed = _top_level(ast.parse(path.read_text(), str(path)))
        if listed is None:
            unlisted.append(module)
            continue
        public = sorted(n for n in defined if not n.startswith("_") and n not in listed)
        if public:
            missing[module] = public
    assert unlisted == [] and missing == {}


def test_every_name_in_all_exists():
    # Statically where the module binds it; lazily exported names (PEP 562) are the module's own table.
    lazy = {"sins": sins.ENTRY_POINTS.keys() | set(sins.SUBMODULES)}
    for package in ("sins.nav", "sins.aiding"):
        lazy[package] = importlib.import_module(package).NAMES.keys()
    absent = {}
    for module, path in MODULES.items():
        _, bound, listed = _top_level(ast.parse(path.read_text(), str(path)))
        gone = [n for n in listed or [] if n not in bound and n not in lazy.get(module, ())]
        if gone:
            absent[module] = gone
    assert absent == {}


def _fresh(code: str) -> dict[str, list[str]]:
    """What a fresh interpreter has imported after ``code``: sins's modules and the top-level packages."""
    probe = "import json, sys\n" + code + "\nprint(json.dumps(sorted(sys.modules)))"
    done = run_process([sys.executable, "-c", probe], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    names = json.loads(done.stdout.splitlines()[-1])
    return {
        "sins": [n for n in names if n.split(".")[0] == "sins"],
        "libraries": sorted({n.split(".")[0] for n in names}),
    }


def test_import_sins_imports_nothing_heavy():
    loaded = _fresh("import sins")
    # The front door and its error type only: numpy and the rest wait for the first entry point used.
    assert loaded["sins"] == ["sins", "sins.errors"]
    assert not {"numpy", "scipy", "numba", *HEAVY} & set(loaded["libraries"])


def test_the_entry_points_load_no_torch_rerun_dask_or_matplotlib():
    loaded = _fresh("import sins\nfor name in sins.ENTRY_POINTS: getattr(sins, name)")
    assert "numpy" in loaded["libraries"]  # the probe did load the entry points
    assert not set(HEAVY) & set(loaded["libraries"])
    # The aiding package's names wait for their use too: filterpy comes with the filter, not the package.
    assert "filterpy" not in _fresh("import sins.aiding")["libraries"]


@pytest.mark.parametrize("package", ["sins", "sins.nav", "sins.aiding"])
def test_lazy_names_are_their_modules_objects(package: str):
    front = importlib.import_module(package)
    table = front.ENTRY_POINTS if package == "sins" else front.NAMES
    for name, module in table.items():
        assert getattr(front, name) is getattr(importlib.import_module(module), name), name
    assert set(table) <= set(dir(front)) and set(table) <= set(front.__all__)
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        front.not_a_name  # noqa: B018


def test_the_subpackages_are_reachable_from_sins():
    for name in sins.SUBMODULES:
        assert getattr(sins, name) is importlib.import_module(f"sins.{name}"), name
    assert set(sins.SUBMODULES) <= set(dir(sins))
