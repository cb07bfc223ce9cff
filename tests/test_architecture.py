"""The house rules (``docs/architecture.md``), checked on the source: data flows one way.

Every module of ``rockbench/`` is parsed with :mod:`ast` and its imports collected, wherever
they stand (module level, functions, ``TYPE_CHECKING`` blocks), relative ones resolved;
``from rockbench import name`` counts as an import of the module that ``rockbench/__init__.py``
takes ``name`` from. Then:

* the report reads Results and tables only: ``rockbench.report.*`` imports nothing from
  ``engines``, ``scene``, ``sweep``, ``runner`` or ``campaign``;
* ``rockbench.comparison`` imports no backend module, and nothing of the runner, the engines or
  the scenes at module level (so that the report may import it);
* backend adapters never import each other;
* ``rockbench.scene.*`` imports nothing above it;
* no module but ``analytic/paper.py`` is over 650 lines;
* an engine run builds at most one analytic ``Reference``, once per scene;
* no engine is named outside ``engines/``: no string constant of the code (docstrings and
  comments excepted) is an engine's name; what a backend can do is a class attribute
  (``batched``, ``fast``, ``relative_cost``), read through the registry
  (:data:`ENGINE_NAME_ALLOWED`: the known exceptions, each with its reason);
* no private name (``_x``) is imported from a module of another package
  (:data:`PRIVATE_IMPORT_ALLOWED`);
* no import cycle among module-level imports (imports inside functions, the lazy ones, and
  ``if TYPE_CHECKING`` blocks may close a cycle).

Each of the last three checkers is shown to fail on a planted violation (a synthetic source).
"""

from __future__ import annotations

import ast
from functools import cache
from pathlib import Path


import rockbench as rb
from rockbench.testing import needs_engine
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


def _is_pkg(module: str) -> bool:
    return modules()[module].name == "__init__.py"


def _base(module: str, level: int, is_pkg: bool | None = None) -> str:
    """The package a relative import of ``level`` dots in ``module`` starts from."""
    parts = module.split(".")
    is_pkg = _is_pkg(module) if is_pkg is None else is_pkg
    keep = len(parts) - level + (1 if is_pkg else 0)
    return ".".join(parts[:keep])


def _from_base(module: str, node: ast.ImportFrom, is_pkg: bool | None = None) -> str:
    """The module ``from X import ...`` names, relative imports resolved."""
    base = _base(module, node.level, is_pkg) if node.level else (node.module or "")
    if node.level and node.module:
        base = f"{base}.{node.module}" if base else node.module
    return base


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


@cache
def tree_of(module: str) -> ast.Module:
    return ast.parse(modules()[module].read_text(encoding="utf-8"))


def _imports_of(module: str, *, top_only: bool = False, with_names: bool = False,
                tree: ast.Module | None = None, is_pkg: bool | None = None,
                known=is_module):
    """Modules ``module`` imports (``with_names``: (bound name, module) pairs). ``tree``,
    ``is_pkg`` and ``known`` (which dotted names are modules) default to the source tree's;
    the checkers' own tests pass synthetic ones."""
    tree = tree_of(module) if tree is None else tree
    for node in _walk(tree, top_only):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield (a.asname or a.name, a.name) if with_names else a.name
            continue
        base = _from_base(module, node, is_pkg)
        for a in node.names:
            full = f"{base}.{a.name}"
            if known(full):
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
    assert "rockbench.result" in imports("rockbench.comparison")
    assert "rockbench.runner" in imports("rockbench.comparison")          # inside compare()
    assert "rockbench.runner" not in imports("rockbench.comparison", top_only=True)
    assert top_level_names()["run"] == "rockbench.runner"
    assert len(ADAPTERS) >= 4 and "rockbench.engines.pymunk" in ADAPTERS


def test_report_reads_results_and_tables_only():
    bad = violations("rockbench.report", ("rockbench.engines", "rockbench.scene",
                                          "rockbench.sweep", "rockbench.runner",
                                          "rockbench.campaign", "rockbench.studies",
                                          "rockbench.cli"))
    assert not bad, "\n".join(bad)


def test_compare_imports_no_backend():
    bad = sorted(f"rockbench.comparison imports {i}" for i in imports("rockbench.comparison")
                 if under(i, *ADAPTERS))
    assert not bad, "\n".join(bad)


def test_importing_compare_imports_no_runner_engine_or_scene():
    """What the report may import must not pull the runner, the engines or the scenes in."""
    bad = violations("rockbench.comparison", ("rockbench.runner", "rockbench.engines",
                                           "rockbench.scene"), top_only=True)
    assert not bad, "\n".join(bad)


def test_backends_never_import_each_other():
    bad = sorted(f"{a} imports {i}" for a in ADAPTERS for i in imports(a)
                 if i in ADAPTERS and i != a)
    assert not bad, "\n".join(bad)


def test_scene_imports_nothing_above_it():
    above = tuple(f"rockbench.{p}" for p in ("analytic", "engines", "runner", "comparison",
                                             "sweep", "campaign", "studies", "report", "testing",
                                             "cli"))
    bad = violations("rockbench.scene", above)
    assert not bad, "\n".join(bad)


def test_no_overstuffed_rooms():
    sizes = {m: len(p.read_text(encoding="utf-8").splitlines()) for m, p in modules().items()}
    big = sorted(f"{m}: {n} lines" for m, n in sizes.items()
                 if n > MAX_LINES and m not in LONG_ALLOWED)
    assert not big, f"modules over {MAX_LINES} lines:\n" + "\n".join(big)


# -----------------------------------------------------------------------------------------
@needs_engine("pymunk")
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


# -----------------------------------------------------------------------------------------
# No engine named outside engines/, no private name across packages, no import cycle.
# Each checker works on a parsed tree (or a graph), so that a planted violation can be shown
# to fail it (the ``test_*_catches_a_planted_*`` tests below).
# -----------------------------------------------------------------------------------------
#: Every engine the registry knows (a new one is checked as soon as it is registered).
ENGINE_NAMES = tuple(n for n in rb.backend_names() if n != "analytic")

#: Known exceptions to "no engine name outside engines/", (module, name) -> why.
ENGINE_NAME_ALLOWED: dict[tuple[str, str], str] = {}

#: Known private imports across packages, (importer, "module:name") -> why.
PRIVATE_IMPORT_ALLOWED = {
}


def _docstrings(tree: ast.AST) -> set[int]:
    """ids of the string constants that are bare expression statements (docstrings)."""
    return {id(n.value) for n in ast.walk(tree) if isinstance(n, ast.Expr)
            and isinstance(n.value, ast.Constant) and isinstance(n.value.value, str)}


def engine_names_in(tree: ast.AST) -> list[tuple[int, str]]:
    """(line, name) of every string constant of the code that *is* an engine's name (what a
    dispatch on the engine looks like: ``engine == "mujoco"``, ``{"pybullet": 2.5}``,
    ``("pymunk", "mujoco")``). Docstrings and comments do not count, nor prose that mentions an
    engine inside a longer message (``"e.g. pymunk.iterations=20"``)."""
    doc = _docstrings(tree)
    return sorted((n.lineno, n.value) for n in ast.walk(tree)
                  if isinstance(n, ast.Constant) and isinstance(n.value, str)
                  and id(n) not in doc and n.value.lower() in ENGINE_NAMES)


def _package_of(module: str, is_pkg: bool) -> str:
    return module if is_pkg else module.rpartition(".")[0]


def _is_package(name: str) -> bool:
    return (PACKAGE.parent.joinpath(*name.split(".")) / "__init__.py").is_file()


def private_imports(module: str, tree: ast.AST, is_pkg: bool = False,
                    packages=None) -> list[str]:
    """``"source:name"`` of every ``from source import _name`` in ``tree`` (anywhere in it)
    whose source lies in another package than ``module`` (a module of rockbench; dunder names
    excepted). Within one package, modules share private helpers freely. ``packages``: the
    names that are packages (default: the source tree's)."""
    is_package = _is_package if packages is None else packages.__contains__
    here = _package_of(module, is_pkg)
    out = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.ImportFrom):
            continue
        base = _from_base(module, node, is_pkg)
        if not under(base, "rockbench"):
            continue
        there = _package_of(base, is_package(base))
        out += [f"{base}:{a.name}" for a in node.names
                if a.name.startswith("_") and not a.name.startswith("__") and there != here]
    return sorted(out)


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (or a module importing
    itself) of the graph module -> modules it imports (Tarjan's algorithm, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph.get(root, ()))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
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
                if len(comp) > 1 or v in graph.get(v, ()):
                    out.append(sorted(comp))
    return sorted(out)


def module_graph(sources: dict[str, ast.Module] | None = None,
                 packages: frozenset[str] = frozenset()) -> dict[str, set[str]]:
    """Module -> rockbench modules it imports *at module level* (on import; imports inside
    functions, the lazy ones, and ``if TYPE_CHECKING`` blocks do not count). ``sources``:
    synthetic modules (name -> tree; ``packages`` those that are packages) instead of the
    source tree."""
    if sources is None:
        return {m: {i for i in imports(m, top_only=True) if i in modules() and i != m}
                for m in modules()}

    known = sources.__contains__
    return {m: {i for i in _imports_of(m, top_only=True, tree=t, is_pkg=m in packages,
                                       known=known) if i in sources and i != m}
            for m, t in sources.items()}


def test_no_engine_named_outside_engines():
    home = ("rockbench.engines", "rockbench.registry")    # the adapters, and their names
    bad = sorted(f"{m}:{line}: {name!r}" for m in modules() if not under(m, *home)
                 for line, name in engine_names_in(tree_of(m))
                 if (m, name) not in ENGINE_NAME_ALLOWED)
    assert not bad, ("engine names outside engines/ (declare a capability on the backend "
                     "class instead):\n" + "\n".join(bad))


def test_the_engine_name_allow_list_is_not_stale():
    found = {(m, name) for m in modules() for _, name in engine_names_in(tree_of(m))}
    assert set(ENGINE_NAME_ALLOWED) <= found, set(ENGINE_NAME_ALLOWED) - found


def test_no_private_name_imported_across_packages():
    bad = sorted(f"{m} imports {x}" for m in modules()
                 for x in private_imports(m, tree_of(m), _is_pkg(m))
                 if (m, x) not in PRIVATE_IMPORT_ALLOWED)
    assert not bad, "\n".join(bad)


def test_the_private_import_allow_list_is_not_stale():
    found = {(m, x) for m in modules() for x in private_imports(m, tree_of(m), _is_pkg(m))}
    assert set(PRIVATE_IMPORT_ALLOWED) <= found, set(PRIVATE_IMPORT_ALLOWED) - found


def test_no_import_cycle_at_module_level():
    graph = module_graph()
    assert "rockbench.engines.base" in graph["rockbench.engines.mujoco_batch"] | \
        graph["rockbench.engines.mujoco"]                       # the graph sees imports
    cycles = import_cycles(graph)
    assert not cycles, "\n".join(" -> ".join(c) for c in cycles)


# --- the checkers fail on planted violations ---------------------------------------------
def _tree(src: str) -> ast.Module:
    return ast.parse(src)


def test_engine_names_catches_a_planted_dispatch():
    planted = _tree('"""Runs on mujoco, as the docstring may say."""\n'
                    '# pymunk in a comment is fine\n'
                    'def f(engine):\n'
                    '    """pybullet in a docstring is fine."""\n'
                    '    msg = "e.g. pymunk.iterations=20"\n'
                    '    return engine == "mujoco" or {"pybullet": 2.5}.get(engine)\n')
    assert engine_names_in(planted) == [(6, "mujoco"), (6, "pybullet")]
    assert engine_names_in(_tree('FAST = ("Drake",)\n')) == [(1, "Drake")]


def test_private_imports_catches_a_planted_one():
    src = _tree("from ..comparison import _peak, metrics\n"
                "from .loop import _private_helper\n"
                "def f():\n"
                "    from ..scene.records import _bundled_dir\n"
                "from ..comparison import __all__\n")
    assert private_imports("rockbench.engines.mujoco", src, packages=set()) == [
        "rockbench.comparison:_peak", "rockbench.scene.records:_bundled_dir"]
    # the same names within one package are allowed
    assert private_imports("rockbench.scene.motion",
                           _tree("from .records import _bundled_dir\n"), packages=set()) == []
    # a private module of another package is a private name too
    assert private_imports("rockbench.cli.main", _tree("from ..engines import _quiet\n"),
                           packages={"rockbench.engines"}) == ["rockbench.engines:_quiet"]


def test_import_cycles_catches_a_planted_cycle():
    sources = {
        "rockbench.a": _tree("from . import b\n"),
        "rockbench.b": _tree("from .c import x\n"),
        "rockbench.c": _tree("import rockbench.a\n"),
        "rockbench.d": _tree("from .a import y\n"
                             "def lazy():\n    from . import d2\n"),
        "rockbench.d2": _tree("from .d import z\n"),
    }
    graph = module_graph(sources)
    assert graph["rockbench.a"] == {"rockbench.b"} and graph["rockbench.d"] == {"rockbench.a"}
    assert import_cycles(graph) == [["rockbench.a", "rockbench.b", "rockbench.c"]]
    # the same cycle closed only by a function-level (lazy) import is allowed
    sources["rockbench.c"] = _tree("def f():\n    import rockbench.a\n")
    assert import_cycles(module_graph(sources)) == []
    assert import_cycles({"x": {"x"}}) == [["x"]]
