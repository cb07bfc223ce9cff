"""The house rules on concepts (``docs/architecture.md``, "one home per concept"): a rule may be
written once even where the folders are clean. Checked on the source with :mod:`ast`:

* **the verdict** - no module but ``rockbench/verdict.py`` compares an angle against a
  critical angle (a comparison with a critical-angle name or with a value taken from one) or
  finishes a fall (``FALL_EXTENSION``): they call ``past_critical`` / ``fall_under_way`` /
  ``finish_fall``;
* **the run length** - no module but ``rockbench/run_length.py`` adds the free-rocking tail
  (``FREE_TAIL``, or its value 10 as a tail or added to a time) or writes a pulse window
  (6, 4.5 or 1.5 times a pulse period): they call ``run_length`` / ``pulse_run_length``;
* **the store's path** - no module but ``rockbench/sweep/store.py`` and
  ``rockbench/sweep/map_store.py`` joins a path with the segment ``"store"``, a ``.parquet``
  name or the code fingerprint: they call ``store_path`` / ``default_store`` /
  ``map_store_path``.

The known exceptions are listed with their reasons (:data:`ALLOWED`); each checker is shown to
fail on a planted violation (a synthetic source).
"""

from __future__ import annotations

import ast
import re

from test_architecture import modules, tree_of, under

#: The home of each concept (modules where it may be written).
HOMES = {
    "verdict": ("rockbench.verdict", "rockbench.constants"),
    "run length": ("rockbench.run_length", "rockbench.constants"),
    "store path": ("rockbench.sweep.store", "rockbench.sweep.map_store"),
}

#: Known exceptions, (module, concept) -> why.
ALLOWED: dict[tuple[str, str], str] = {
    ("rockbench.analytic.solver", "verdict"):
        "the solve_ivp model's own event 'critical' (the root of s phi - phi_cr in its "
        "integrator), not a judgement of samples",
    ("rockbench.analytic.kernel_run", "verdict"):
        "the compiled model's own event 'critical' (numba: it cannot call Python)",
    ("rockbench.analytic.kernel_grid", "run length"):
        "the map kernel's default length in numba (it cannot call Python); "
        "tests/test_run_length.py checks it runs a cell for run_length's value",
    ("rockbench.scene.synthetic", "run length"):
        "TAIL: a synthetic record's own padding after its excitation (its filter's decay), "
        "not a run's free rocking",
    ("rockbench.sweep.adaptive", "verdict"):
        "a heuristic band below the critical angle (NEAR_CRITICAL x) where an adaptive map "
        "refines, not a verdict",
}

_CRIT = re.compile(r"crit|phi_cr", re.IGNORECASE)
_TIMEISH = re.compile(r"t_end|t_start|t0|duration|period|window|tail|t_g|length", re.IGNORECASE)
_TAIL_TARGET = re.compile(r"tail|duration", re.IGNORECASE)
_PERIODISH = re.compile(r"period|^t_?g$|^per$", re.IGNORECASE)
#: The free-rocking tail's value [s] and the pulse windows' factors of T_g.
TAIL_VALUE = 10.0
WINDOW_FACTORS = (6.0, 4.5, 1.5)
FUNCTIONS = (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)


def _names(node: ast.AST) -> list[str]:
    """Identifiers in ``node``: names, attributes, and the string keys it reads."""
    out = []
    for n in ast.walk(node):
        if isinstance(n, ast.Name):
            out.append(n.id)
        elif isinstance(n, ast.Attribute):
            out.append(n.attr)
        elif isinstance(n, ast.Constant) and isinstance(n.value, str) and len(n.value) < 30:
            out.append(n.value)
    return out


def _is_number(node: ast.AST, values) -> bool:
    return (isinstance(node, ast.Constant) and isinstance(node.value, (int, float))
            and not isinstance(node.value, bool) and float(node.value) in values)


def _scopes(tree: ast.AST):
    """The module and each function: (scope node, its own statements' nodes)."""
    yield tree
    yield from (n for n in ast.walk(tree) if isinstance(n, FUNCTIONS))


def _own_nodes(scope: ast.AST):
    """Nodes of ``scope`` outside its nested functions."""
    stack = list(ast.iter_child_nodes(scope))
    while stack:
        n = stack.pop()
        yield n
        if not isinstance(n, FUNCTIONS):
            stack.extend(ast.iter_child_nodes(n))


#: Calls whose value is taken from their arguments (a critical angle stays one through them).
_PASS_THROUGH = ("min", "max", "abs", "float", "sorted", "list", "tuple", "values", "get")
_API = ("past_critical", "fall_under_way", "exceeded_critical")


def _critical(node: ast.AST | None, tainted: set[str]) -> bool:
    """Whether the value of ``node`` is (taken from) a critical angle: a name that says so
    (``crit``, ``critical``, ``phi_cr...``) or a local value taken from one, through
    subscripts, arithmetic, conditionals, comprehensions and ``min``/``max``/``abs``/...; a
    call to any other function gives a value of its own."""
    if node is None:
        return False
    if isinstance(node, ast.Name):
        return node.id not in _API and (bool(_CRIT.search(node.id)) or node.id in tainted)
    if isinstance(node, ast.Attribute):
        return node.attr not in _API and (bool(_CRIT.search(node.attr))
                                          or _critical(node.value, tainted))
    if isinstance(node, ast.Constant):
        return isinstance(node.value, str) and node.value.startswith("phi_cr")
    if isinstance(node, ast.Call):
        f = node.func
        name = getattr(f, "id", None) or getattr(f, "attr", None)
        if name not in _PASS_THROUGH:
            return False
        return any(_critical(a, tainted) for a in node.args) or (
            isinstance(f, ast.Attribute) and _critical(f.value, tainted))
    if isinstance(node, (ast.Lambda, *FUNCTIONS)):
        return False
    return any(_critical(c, tainted) for c in ast.iter_child_nodes(node)
               if isinstance(c, ast.expr) or isinstance(c, ast.comprehension))


def verdict_violations(tree: ast.AST) -> list[tuple[int, str]]:
    """(line, what) of every comparison with a critical angle (a name that says so, or a
    local value taken from one) and every use of FALL_EXTENSION."""
    out = []
    for scope in _scopes(tree):
        nodes = list(_own_nodes(scope))
        tainted: set[str] = set()
        for _ in range(3):                 # values taken from values taken from ...
            for n in nodes:
                if isinstance(n, (ast.Assign, ast.AnnAssign)) and _critical(n.value, tainted):
                    targets = n.targets if isinstance(n, ast.Assign) else [n.target]
                    tainted |= {t.id for t in targets if isinstance(t, ast.Name)}
                elif isinstance(n, (ast.comprehension, ast.For)) and _critical(n.iter, tainted):
                    tainted |= {t.id for t in ast.walk(n.target) if isinstance(t, ast.Name)}
        if isinstance(scope, ast.Lambda):
            for a, d in zip(scope.args.args[::-1], scope.args.defaults[::-1]):
                if _critical(d, tainted):
                    tainted.add(a.arg)
        for n in nodes:
            if isinstance(n, ast.Compare) and any(
                    _critical(x, tainted) for x in [n.left, *n.comparators]):
                out.append((n.lineno, "compares with a critical angle"))
    for n in ast.walk(tree):
        if (isinstance(n, ast.Name) and n.id == "FALL_EXTENSION") or (
                isinstance(n, ast.alias) and n.name == "FALL_EXTENSION"):
            out.append((getattr(n, "lineno", 0), "FALL_EXTENSION: finishes a fall"))
    return sorted(set(out))


def _values(node: ast.AST):
    """A value and, through conditional expressions and boolean operators, its parts."""
    yield node
    if isinstance(node, ast.IfExp):
        yield from _values(node.body)
        yield from _values(node.orelse)
    elif isinstance(node, ast.BoolOp):
        for v in node.values:
            yield from _values(v)


def run_length_violations(tree: ast.AST) -> list[tuple[int, str]]:
    """(line, what) of every FREE_TAIL, every 10 s added to a time or given as a tail or a
    duration, and every pulse window written as a factor of a pulse period."""
    out = []
    for n in ast.walk(tree):
        if (isinstance(n, ast.Name) and n.id == "FREE_TAIL") or (
                isinstance(n, ast.alias) and n.name == "FREE_TAIL"):
            out.append((getattr(n, "lineno", 0), "FREE_TAIL: the default tail"))
        elif isinstance(n, ast.BinOp) and isinstance(n.op, (ast.Add, ast.Sub)):
            for a, b in ((n.left, n.right), (n.right, n.left)):
                if _is_number(a, (TAIL_VALUE,)) and any(_TIMEISH.search(x)
                                                          for x in _names(b)):
                    out.append((n.lineno, "10 s added to a time: the default tail"))
        elif isinstance(n, ast.BinOp) and isinstance(n.op, (ast.Mult, ast.Div)):
            chain = _product(n)
            if any(_is_number(c, WINDOW_FACTORS) for c in chain) and any(
                    any(_PERIODISH.search(x) for x in _names(c)) or _has_pi(c)
                    for c in chain if not isinstance(c, ast.Constant)):
                out.append((n.lineno, "a pulse window: a factor of the pulse period"))
        targets: list[tuple[str, ast.AST]] = []
        if isinstance(n, ast.Assign):
            targets = [(t.id, n.value) for t in n.targets if isinstance(t, ast.Name)]
        elif isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name) and n.value:
            targets = [(n.target.id, n.value)]
        elif isinstance(n, ast.keyword) and n.arg:
            targets = [(n.arg, n.value)]
        elif isinstance(n, ast.arguments):
            pos = [*n.posonlyargs, *n.args]
            targets = [(a.arg, d) for a, d in zip(pos[::-1], n.defaults[::-1])]
            targets += [(a.arg, d) for a, d in zip(n.kwonlyargs, n.kw_defaults) if d]
        for name, value in targets:
            if _TAIL_TARGET.search(name) and any(_is_number(v, (TAIL_VALUE,))
                                                 for v in _values(value)):
                out.append((value.lineno, f"{name} = 10 s: the default tail"))
    return sorted(set(out))


def _product(node: ast.AST) -> list[ast.AST]:
    """The factors of a chain of products and quotients."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.Div)):
        return _product(node.left) + _product(node.right)
    return [node]


def _has_pi(node: ast.AST) -> bool:
    return any(isinstance(x, ast.Attribute) and x.attr == "pi" for x in ast.walk(node))


_STORE_JOINS = ("joinpath", "with_name", "join")


def _store_segment(node: ast.AST) -> bool:
    """A path segment that makes a store's path: "store", a .parquet name, the fingerprint."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        v = node.value.strip("/")
        return v == "store" or v.startswith("store/") or v.endswith(".parquet")
    if isinstance(node, ast.JoinedStr):
        last = node.values[-1] if node.values else None
        return isinstance(last, ast.Constant) and str(last.value).endswith(".parquet")
    return any(isinstance(c, ast.Call) and (getattr(c.func, "id", None) == "code_fingerprint"
                                            or getattr(c.func, "attr", None)
                                            == "code_fingerprint") for c in ast.walk(node))


def store_path_violations(tree: ast.AST) -> list[tuple[int, str]]:
    """(line, what) of every path joined with a store's segment (``/``, ``Path(...)``,
    ``os.path.join``, ``joinpath``, ``with_name``)."""
    out = []
    for n in ast.walk(tree):
        parts: list[ast.AST] = []
        if isinstance(n, ast.BinOp) and isinstance(n.op, ast.Div):
            parts = [n.left, n.right]
        elif isinstance(n, ast.Call) and (getattr(n.func, "id", None) in ("Path", "PurePath")
                                          or getattr(n.func, "attr", None) in _STORE_JOINS):
            if getattr(n.func, "attr", None) == "join" and not (
                    isinstance(n.func.value, ast.Attribute) and n.func.value.attr == "path"):
                continue                   # str.join, not os.path.join
            parts = list(n.args)
        if any(_store_segment(p) for p in parts):
            out.append((n.lineno, "a store's path built here"))
    return sorted(set(out))


CHECKERS = {"verdict": verdict_violations, "run length": run_length_violations,
            "store path": store_path_violations}


def _found() -> dict[tuple[str, str], list[tuple[int, str]]]:
    out = {}
    for m in modules():
        for concept, check in CHECKERS.items():
            if under(m, *HOMES[concept]):
                continue
            got = check(tree_of(m))
            if got:
                out[(m, concept)] = got
    return out


def test_every_concept_is_written_in_its_one_home():
    bad = [f"{m}:{line}: {what} (home: {', '.join(HOMES[c][:1])})"
           for (m, c), hits in sorted(_found().items()) if (m, c) not in ALLOWED
           for line, what in hits]
    assert not bad, "a concept written outside its home:\n" + "\n".join(bad)


def test_the_concept_allow_list_is_not_stale():
    assert set(ALLOWED) <= set(_found()), set(ALLOWED) - set(_found())


# --- the checkers fail on planted violations ---------------------------------------------
def _lines(check, src: str) -> list[int]:
    return [line for line, _ in check(ast.parse(src))]


def test_the_verdict_checker_catches_a_planted_comparison_and_a_planted_finish():
    src = ("def f(r, phi, ref, s):\n"
           "    c = ref.critical[(s, True)]\n"                     # a value taken from one
           "    if s * phi > c:\n"                                 # 3
           "        return 1\n"
           "    return abs(phi) >= r.theta_crit\n"                 # 5
           "def g(run, d):\n"
           "    return run(d + FALL_EXTENSION)\n"                  # 7
           "def h(phi, crit):\n"
           "    return [x for x in crit.values() if phi > x]\n"    # 9
           "def ok(phi, ref, s):\n"
           "    return past_critical(phi, True, ref.critical) and s.exceeded_critical == 1\n")
    assert _lines(verdict_violations, src) == [3, 5, 7, 9]


def test_the_run_length_checker_catches_planted_lengths():
    src = ("from ..constants import FREE_TAIL\n"                   # 1
           "def f(m, W, p, tail=None, plan=None):\n"
           "    a = m.t_end - m.t_start + 10.0\n"                  # 3
           "    b = 6.0 * 2.0 * math.pi / (W * p) + tail\n"        # 4
           "    c = round(1.5 * m.period + tail - m.t_start, 4)\n"  # 5
           "    tail = plan['tail'] if plan else 10.0\n"           # 6
           "    d = 4.5 * m.period\n"                              # 7
           "    return g(duration=10)\n"                           # 8
           "def ok(m, n):\n"
           "    return 3.0 * m.period, n + 10, 10.0 * m.peak, 6 * n\n")
    assert _lines(run_length_violations, src) == [1, 3, 4, 5, 6, 7, 8]


def test_the_store_path_checker_catches_planted_paths():
    src = ("def f(out, lab, eng, g):\n"
           "    a = out / 'store'\n"                               # 2
           "    b = Path(out, 'store')\n"                          # 3
           "    c = out / f'{lab}_{eng}_{g}.parquet'\n"            # 4
           "    d = out / code_fingerprint() / 'maps'\n"           # 5
           "    e = os.path.join(out, 'store')\n"                  # 6
           "    ok = ', '.join(['store', 'x']), out / 'figures', {'store': 1}\n"
           "    return a, b, c, d, e, ok\n")
    assert _lines(store_path_violations, src) == [2, 3, 4, 5, 6]
