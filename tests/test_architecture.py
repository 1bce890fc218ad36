"""The package layout keeps its layers (docs/architecture.md): no import against the layer
table, every module covered by it, and no import circle between modules (lazy and
``TYPE_CHECKING`` imports included)."""

from __future__ import annotations

import ast
import re
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "marsscene"
DOC = ROOT / "docs" / "architecture.md"


def _modules() -> dict[str, Path]:
    out = {}
    for p in PKG.rglob("*.py"):
        parts = list(p.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


def _imports(mods: dict[str, Path]) -> dict[str, set[str]]:
    """Every marsscene module each module imports (anywhere in the file)."""
    edges: dict[str, set[str]] = defaultdict(set)
    for name, path in mods.items():
        pkg = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = pkg.split(".")[: len(pkg.split(".")) - (node.level - 1)]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                if target.split(".")[0] != "marsscene":
                    continue
                for alias in node.names:  # `from pkg import module` names the module
                    full = f"{target}.{alias.name}"
                    edges[name].add(full if full in mods else target)
            elif isinstance(node, ast.Import):
                edges[name].update(a.name for a in node.names
                                   if a.name.split(".")[0] == "marsscene")
    return edges


def _layers() -> dict[str, int]:
    text = DOC.read_text()
    table = text.split("<!-- layers:begin -->")[1].split("<!-- layers:end -->")[0]
    layers: dict[str, int] = {}
    for row in table.splitlines():
        cells = [c.strip() for c in row.strip().strip("|").split("|")]
        if len(cells) < 2 or not cells[0].isdigit():
            continue
        for entry in re.findall(r"`([\w.]+)`", cells[1]):
            assert entry not in layers, f"{entry} listed twice in docs/architecture.md"
            layers[entry] = int(cells[0])
    return layers


def _entry(module: str, layers: dict[str, int]) -> str | None:
    """The longest table entry naming ``module`` (``marsscene`` alone: the root only)."""
    best = None
    for entry in layers:
        hit = module == entry or (entry != "marsscene" and module.startswith(entry + "."))
        if hit and (best is None or len(entry) > len(best)):
            best = entry
    return best


MODS = _modules()
EDGES = _imports(MODS)
LAYERS = _layers()


def test_the_table_is_read():
    assert len(LAYERS) >= 30 and LAYERS["marsscene.cli"] > LAYERS["marsscene.sim"]


def test_every_module_has_a_layer():
    missing = sorted(m for m in MODS if _entry(m, LAYERS) is None)
    assert not missing, f"add these to the layer table in docs/architecture.md: {missing}"


def test_imports_run_down_the_layers():
    bad = []
    for src, targets in EDGES.items():
        e_src = _entry(src, LAYERS)
        for dst in targets:
            e_dst = _entry(dst, LAYERS)
            if e_src is None or e_dst is None or e_src == e_dst:
                continue
            if LAYERS[e_dst] >= LAYERS[e_src]:
                bad.append(f"{src} (layer {LAYERS[e_src]}) imports {dst} "
                           f"(layer {LAYERS[e_dst]})")
    assert not bad, "imports against the layers:\n" + "\n".join(sorted(bad))


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (iterative Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = 0
    nodes = sorted(set(edges) | {d for ds in edges.values() for d in ds})
    for root in nodes:
        if root in index:
            continue
        work = [(root, iter(sorted(edges.get(root, ()))))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(edges.get(w, ())))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return out


def test_no_import_circles():
    assert _cycles(EDGES) == []


def test_the_checks_can_fail():
    """The checker finds a planted circle and a planted upward import."""
    planted = {"marsscene.terrain.a": {"marsscene.terrain.b"},
               "marsscene.terrain.b": {"marsscene.terrain.a"}}
    assert _cycles(planted) == [["marsscene.terrain.a", "marsscene.terrain.b"]]
    assert LAYERS[_entry("marsscene.sim.driver", LAYERS)] > \
        LAYERS[_entry("marsscene.runs.export.bag", LAYERS)] > \
        LAYERS[_entry("marsscene.runs.tum", LAYERS)]
    assert _entry("marsscene.export.config", LAYERS) == "marsscene.export.config"
    assert _entry("marsscene.anything", LAYERS) is None


@pytest.mark.parametrize("name", ["sim", "bag", "config", "datasets"])
def test_no_moved_module_shim(name):
    """The paths of the old flat ``runtime/`` folder were never released: no import hook
    keeps them alive."""
    import importlib
    import sys

    with pytest.raises(ModuleNotFoundError):
        importlib.import_module(f"marsscene.runtime.{name}")
    assert not any("MovedModule" in type(f).__name__ for f in sys.meta_path)


#: Packages that only wire the others together: their functions stay short.
WIRING = ("cli", "sweep", "benchmark", "pipeline")
MAX_WIRING_LINES = 80


def _long_functions(root: Path, limit: int) -> list[str]:
    """``module:function (N lines)`` for every function of ``root`` longer than ``limit``
    lines (decorators excluded, the docstring included)."""
    long = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                n = (node.end_lineno or node.lineno) - node.lineno + 1
                if n > limit:
                    long.append(f"{path.relative_to(root.parent)}:{node.name} ({n} lines)")
    return long


@pytest.mark.parametrize("package", WIRING)
def test_wiring_functions_are_short(package):
    assert _long_functions(PKG / package, MAX_WIRING_LINES) == []


def test_long_function_check_can_fail(tmp_path):
    body = "\n".join(f"    x{i} = {i}" for i in range(MAX_WIRING_LINES))
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "m.py").write_text(f"def f():\n{body}\n\n\ndef g():\n    pass\n",
                                           encoding="utf-8")
    assert _long_functions(tmp_path / "pkg", MAX_WIRING_LINES) == ["pkg/m.py:f (81 lines)"]


#: Packages whose tests live in a folder of another name, and why.
TEST_FOLDER_OF = {"testing": "dem"}  # the PDS3 writers, tested by the DEM readers reading them


def test_tests_mirror_the_package():
    """Every subpackage of marsscene has its test folder, ``tests/<name>/`` (or the one named
    in :data:`TEST_FOLDER_OF`), holding at least one test file."""
    packages = sorted(p.parent.name for p in PKG.glob("*/__init__.py"))
    missing = [name for name in packages
               if not list((ROOT / "tests" / TEST_FOLDER_OF.get(name, name)).glob("test_*.py"))]
    assert missing == []
