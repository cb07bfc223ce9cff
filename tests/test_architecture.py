"""The house rules (``docs/architecture.md``), checked on the source: data flows one way.

Every module of ``rockbench/`` is parsed with :mod:`ast` and its imports collected, wherever
they stand (module level, functions, ``TYPE_CHECKING`` blocks), relative ones resolved;
``from rockbench import name`` counts as an import of the module that ``rockbench/__init__.py``
takes ``name`` from. Then:

* the report reads Results and tables only: ``rockbench.report.*`` imports nothing from
  ``engines``, ``scene``, ``sweep``, ``runner`` or ``campaign``;
* ``rockbench.compare`` imports no backend module, and nothing of the runner, the engines or
  the scenes at module level (so that the report may import it);
* backend adapters never import each other;
* ``rockbench.scene.*`` imports nothing above it;
* no module but ``analytic/paper.py`` is over 650 lines;
* an engine run builds at most one analytic ``Reference``, once per scene.
"""

from __future__ import annotations

import ast
from functools import cache
from pathlib import Path

import pytest

import rockbench as rb
from rockbench.engines import REGISTRY

PACKAGE = Path(rb.__file__).resolve().parent
MAX_LINES = 650
LONG_ALLOWED = {"rockbench.analytic.paper"}


def module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def is_module(name: str) -> bool:
    """``name`` (dotted) is a module or package of the source tree."""
    p = PACKAGE.parent.joinpath(*name.split("."))
    return p.with_suffix(".py").is_file() or (p / "__init__.py").is_file()


@cache
def modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


@cache
def top_level_names() -> dict[str, str]:
    """Name -> module it comes from, for the names ``rockbench/__init__.py`` imports."""
    out = {}
    for name, found in _imports_of("rockbench", with_names=True):
        if name:
            out[name] = found
    return out


def _base(module: str, level: int) -> str:
    """The package a relative import of ``level`` dots in ``module`` starts from."""
    parts = module.split(".")
    is_pkg = modules()[module].name == "__init__.py"
    keep = len(parts) - level + (1 if is_pkg else 0)
    return ".".join(parts[:keep])


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def _walk(tree: ast.AST, top_only: bool):
    """Import nodes of ``tree``: all of them, or (``top_only``) those that run on import (module
    level, outside functions and ``if TYPE_CHECKING`` blocks)."""
    if not top_only:
        yield from (n for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom)))
        return
    stack = list(tree.body)
    while stack:
        n = stack.pop()
        if isinstance(n, (ast.Import, ast.ImportFrom)):
            yield n
        elif isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            continue
        elif isinstance(n, ast.If) and _is_type_checking(n):
            stack.extend(n.orelse)
        else:
            stack.extend(c for c in ast.iter_child_nodes(n) if isinstance(c, ast.stmt))


def _imports_of(module: str, *, top_only: bool = False, with_names: bool = False):
    tree = ast.parse(modules()[module].read_text(encoding="utf-8"))
    for node in _walk(tree, top_only):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield (a.asname or a.name, a.name) if with_names else a.name
            continue
        base = _base(module, node.level) if node.level else (node.module or "")
        if node.level and node.module:
            base = f"{base}.{node.module}" if base else node.module
        for a in node.names:
            full = f"{base}.{a.name}"
            if is_module(full):
                found = full
            elif base == "rockbench" and not with_names:
                found = top_level_names().get(a.name, base)
            else:
                found = base
            yield (a.asname or a.name, found) if with_names else found


def imports(module: str, *, top_only: bool = False) -> set[str]:
    """Every rockbench module ``module`` imports."""
    return {m for m in _imports_of(module, top_only=top_only)
            if m == "rockbench" or m.startswith("rockbench.")}


def under(name: str, *packages: str) -> bool:
    return any(name == p or name.startswith(p + ".") for p in packages)


def violations(prefix: str, forbidden: tuple[str, ...], *, top_only: bool = False
               ) -> list[str]:
    return sorted(f"{m} imports {i}" for m in modules() if under(m, prefix)
                  for i in imports(m, top_only=top_only) if under(i, *forbidden))


ADAPTERS = sorted({spec.split(":")[0] for spec in REGISTRY.values()
                   if isinstance(spec, str) and spec.startswith("rockbench.")})


# -----------------------------------------------------------------------------------------
def test_the_import_graph_sees_imports():
    """The collector itself: relative imports resolved, names of the top package mapped."""
    assert "rockbench.result" in imports("rockbench.compare")
    assert "rockbench.runner" in imports("rockbench.compare")          # inside compare()
    assert "rockbench.runner" not in imports("rockbench.compare", top_only=True)
    assert top_level_names()["run"] == "rockbench.runner"
    assert len(ADAPTERS) >= 4 and "rockbench.engines.pymunk" in ADAPTERS


def test_report_reads_results_and_tables_only():
    bad = violations("rockbench.report", ("rockbench.engines", "rockbench.scene",
                                          "rockbench.sweep", "rockbench.runner",
                                          "rockbench.campaign"))
    assert not bad, "\n".join(bad)


def test_compare_imports_no_backend():
    bad = sorted(f"rockbench.compare imports {i}" for i in imports("rockbench.compare")
                 if under(i, *ADAPTERS))
    assert not bad, "\n".join(bad)


def test_importing_compare_imports_no_runner_engine_or_scene():
    """What the report may import must not pull the runner, the engines or the scenes in."""
    bad = violations("rockbench.compare", ("rockbench.runner", "rockbench.engines",
                                           "rockbench.scene"), top_only=True)
    assert not bad, "\n".join(bad)


def test_backends_never_import_each_other():
    bad = sorted(f"{a} imports {i}" for a in ADAPTERS for i in imports(a)
                 if i in ADAPTERS and i != a)
    assert not bad, "\n".join(bad)


def test_scene_imports_nothing_above_it():
    above = tuple(f"rockbench.{p}" for p in ("analytic", "engines", "runner", "compare",
                                             "sweep", "campaign", "report", "testing", "cli"))
    bad = violations("rockbench.scene", above)
    assert not bad, "\n".join(bad)


def test_no_overstuffed_rooms():
    sizes = {m: len(p.read_text(encoding="utf-8").splitlines()) for m, p in modules().items()}
    big = sorted(f"{m}: {n} lines" for m, n in sizes.items()
                 if n > MAX_LINES and m not in LONG_ALLOWED)
    assert not big, f"modules over {MAX_LINES} lines:\n" + "\n".join(big)


# -----------------------------------------------------------------------------------------
@pytest.mark.skipif("pymunk" not in rb.available_backends(), reason="pymunk not installed")
def test_an_engine_run_builds_one_reference_once(monkeypatch):
    from rockbench.analytic import reference

    built = []
    real_init = reference.Reference.__init__

    def counting(self, scene):
        built.append(scene.name)
        real_init(self, scene)

    monkeypatch.setattr(reference.Reference, "__init__", counting)
    reference.reference_of.cache_clear()
    try:
        scene = rb.load_scene("housner-block")
        r = rb.run(scene, engine="pymunk", duration=1.5, phi0=0.5 * scene.alpha)
        assert r.ok and r.summary.n_impacts >= 1
        assert len(built) <= 1, f"one pymunk run built {len(built)} References"
        rb.run(scene, engine="pymunk", duration=1.5, phi0=0.5 * scene.alpha)
        assert len(built) <= 1, f"two runs of one scene built {len(built)} References"
    finally:
        reference.reference_of.cache_clear()   # no counting Reference left in the cache
