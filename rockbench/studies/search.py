"""The one search for a decision: which engine, at which setting, meets each tolerance on a
scene at the least cost - shared by ``rockbench advise`` and the report, so that the same scene
and evidence give the same answer.

The evidence (:func:`rockbench.studies.validation.validation_set`, its choice and held-out
parts, every case labelled by its own conditioning) is fixed per size. Every engine climbs down
its precision knob from the coarsest value (:func:`rockbench.studies.advise.precision_knob`:
the time step, or an error-controlled integrator's accuracy). Every engine's coarsest rung runs
first (cheapest engine first, by its backend's ``relative_cost``); after that the search always
runs the cheapest next rung of any engine still in the race (its cost estimated from the
engine's last rung), so that the cheap engines go finer first and an expensive rung runs only
when nothing cheaper is left. At each rung the choice part runs; then, for every tolerance not
yet settled for the engine:

1. **converge** (:func:`rockbench.studies.decide.convergence`): the largest value within the
   tolerance whose next finer value is within it too is accepted (a lucky value is not);
2. **confirm**: the accepted value runs on the held-out part; within the tolerance there, the
   engine **meets** it at that value; beyond it, the engine goes on to its next finer accepted
   value (a held-out failure is never the end of an engine's race while finer values remain).

An engine leaves the race when every tolerance is settled for it, when its next rung is
estimated to cost more than the cheapest confirmed answer of every open tolerance (it cannot
win: **dearer**), or when its ladder ends (a finest value within the tolerance is confirmed by
one finer value first). The whole search stops when its CPU budget would be exceeded; the answer
then says, for each tolerance nothing meets, what to run next and its estimated CPU cost.

The fate of an engine at a tolerance is one of :data:`rockbench.fates.FATES` (defined once;
the command line, JSON and the report use these words). Cost: steady-state process CPU seconds per simulated
second over the setting's runs (choice and held-out). Runs are kept in the one store and reused:
a search is resumable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
import pandas as pd

from ..constants import BUDGETS
from ..errors import ParameterError
from .decide import TIE, _check_tolerance, convergence
from .search_outcomes import fate, finer, next_step, outcome_rows

__all__ = ["TOLERANCE_LADDER", "BUDGETS", "Decision", "search", "coverage"]

#: The tolerances the report decides, loosest first (relative errors: 0.02 = 2 %).
TOLERANCE_LADDER: tuple[float, ...] = (0.10, 0.05, 0.02, 0.005)

#: Simulated seconds are spent at this many CPU seconds per simulated second on an engine's
#: first rung when nothing is measured yet (its relative_cost scales it): only the budget's
#: first estimate uses it.
_FIRST_GUESS = 0.01


@dataclass
class _Rung:
    value: float
    setting: str
    choice_error: float
    cost: float                       # CPU s per simulated s on the choice part
    held_error: float = math.nan      # when run


@dataclass
class Decision:
    """What :func:`search` found.

    scene, size (evidence size), tolerances (loosest first);
    outcomes : one row per (tolerance, engine): ``tolerance``, ``engine``, ``status`` (a key
        of :data:`FATES`), ``setting`` (label), ``knob``, ``value``, ``worst_error_choice``,
        ``worst_error_heldout`` [-], ``cpu_per_sim_s`` [s/s], ``reason`` (words),
        ``recommended`` (the cheapest that meets it; among those within :data:`TIE` of the
        cheapest, all noted in ``tie_with_cheapest``, the most accurate);
    evidence : one row per setting run (:data:`rockbench.studies.tradeoff.TABLE_COLUMNS`);
    runs : one row per run; cases : the evidence with its labels;
    coverage : what the held-out part holds (``counted``, ``overturning``, ``near_boundary``,
        ``records``, ``outside``: left out), and ``thin`` (a sentence, "" when it is not thin);
    next_steps : tolerance -> what to run next when nothing meets it (engine, setting,
        ``cpu_s`` estimate, command line), or None;
    engines : every registered engine's state; cpu_s : the CPU the search spent [s] (process
    CPU of the search and its workers); runs_cpu_s : the CPU of the runs it measured [s] (0
    when every run came from the store);
    stopped : why the search stopped early ("" when it did not); machine;
    vertical : r [-] of the evidence's vertical motion (a_v = r x horizontal; 0: none).
    """

    scene: str
    size: str
    tolerances: tuple[float, ...]
    outcomes: pd.DataFrame
    evidence: pd.DataFrame
    runs: pd.DataFrame
    cases: list[Any]
    coverage: dict[str, Any]
    next_steps: dict[float, dict[str, Any] | None]
    engines: list[dict[str, Any]]
    cpu_s: float
    stopped: str = ""
    knobs: dict[str, str] = field(default_factory=dict)
    machine: dict[str, Any] = field(default_factory=dict)
    contact: pd.DataFrame = field(default_factory=pd.DataFrame)
    vertical: float = 0.0
    runs_cpu_s: float = 0.0

    def at(self, tolerance: float) -> pd.DataFrame:
        """The outcomes at one tolerance, recommended first, then in rank order."""
        o = self.outcomes
        return o[np.isclose(o["tolerance"].astype(float), float(tolerance))].sort_values(
            "rank")

    def recommended(self, tolerance: float) -> dict[str, Any] | None:
        """The cheapest engine and setting that meets ``tolerance`` (None: none does)."""
        g = self.at(tolerance)
        g = g[g["recommended"].astype(bool)]
        return g.iloc[0].to_dict() if len(g) else None


# =========================================================================================
# Helpers
# =========================================================================================
def _order(names: Sequence[str]) -> list[str]:
    """Engines cheapest first (their backend's ``relative_cost``), the given order on ties."""
    from ..engines import get_backend

    return sorted(names, key=lambda n: (float(get_backend(n).relative_cost), names.index(n)))


def _worst(rows: pd.DataFrame) -> float:
    """The worst counted error of some runs (NaN: none counted)."""
    e = rows["error"].to_numpy(dtype=float)
    e = e[~np.isnan(e)]
    return float(e.max()) if e.size else math.nan


def _cost(rows: pd.DataFrame) -> float:
    """Steady CPU s per simulated s of runs (their median CPU over their simulated time)."""
    sim = rows["sim_time"].to_numpy(dtype=float)
    cpu = rows["cpu_s_median"].to_numpy(dtype=float)
    ok = np.isfinite(sim) & np.isfinite(cpu)
    return float(cpu[ok].sum() / sim[ok].sum()) if ok.any() and sim[ok].sum() > 0 else math.nan


def coverage(cases: Sequence[Any]) -> dict[str, Any]:
    """What the held-out part of an evidence holds: ``held_out`` cases, ``counted`` (not near
    the boundary), ``overturning``, ``near_boundary`` (reported, not counted), ``records``,
    and ``thin``: a sentence saying why an answer confirmed on it is weak ("" when it is not)."""
    held = [c for c in cases if c.part == "held-out"]
    near = [c for c in held if c.near_boundary]
    counted = [c for c in held if not c.near_boundary]
    over = [c for c in counted if c.kind == "overturn"]
    recs = [c for c in counted if c.kind == "record"]
    lacks = [w for w, n in (("an overturning case", len(over)), ("a record", len(recs))) if not n]
    thin = ""
    if len(counted) < 6 or lacks:
        thin = (f"thin held-out evidence: {len(counted)} counted case(s)"
                + (f", without {' or '.join(lacks)}" if lacks else "")
                + "; a larger evidence size (--full) confirms on more")
    return {"held_out": len(held), "counted": len(counted), "overturning": len(over),
            "near_boundary": len(near), "records": len(recs), "thin": thin}


# =========================================================================================
# The search
# =========================================================================================
def search(scene, tolerances: Iterable[float] = TOLERANCE_LADDER,
           engines: Sequence[str] | None = None, *, size: str = "default", store=None,
           budget_cpu_s: float | None | str = "auto", dts: Iterable[float] | None = None,
           contact: bool = False, seed: int | None = None, vertical: float = 0.0,
           executor: str = "process", workers: int | None = None,
           progress: bool = False) -> Decision:
    """Search the cheapest confirmed engine and setting for each of ``tolerances`` on
    ``scene`` (module docstring).

    Parameters
    ----------
    scene : a Scene, a built-in name or a scene file.
    tolerances : relative errors in (0, 1) (default :data:`TOLERANCE_LADDER`).
    engines : backend names (default every registered engine; those that cannot run here are
        listed "not installed", those not selected "left out").
    size : the evidence ("quick", "default" or "full").
    store : a folder: runs are kept there and reused (a search resumes).
    budget_cpu_s : the most CPU seconds the search may spend ("auto": :data:`BUDGETS` of the
        size; None: no limit).
    dts : the time-step ladder [s] of engines whose knob is dt (default
        :data:`rockbench.constants.DT_LADDER`).
    contact : measure each engine's contact variants (its backend's ``contact_variants``)
        first, and search the helpful ones too (``rockbench advise --full``).
    seed : the evidence's split (default :data:`rockbench.studies.validation.SEED`).
    vertical : r in [0, 3]: every pulse and record of the evidence also moves the ground
        vertically, a_v = r times its horizontal acceleration (in phase;
        :func:`rockbench.studies.validation.validation_set`); 0: horizontal only.
    """
    from ..engines import engine_states, get_backend
    from ..runner import REFERENCE, resolve_engines
    from ..scene.scene import load_scene
    from ..sweep.executors import kept_pools
    from .advise import precision_knob
    from .tradeoff import machine_info, summarize, tradeoff
    from .validation import SEED, SIZES, validation_set

    if size not in SIZES:
        raise ParameterError("size", size, f"one of {', '.join(SIZES)}")
    tols = tuple(sorted({_check_tolerance(t) for t in tolerances}, reverse=True))
    if not tols:
        raise ParameterError("tolerances", tolerances, "at least one relative error in (0, 1)")
    budget = _auto_budget(size) if budget_cpu_s == "auto" else budget_cpu_s
    if budget is not None and not (isinstance(budget, (int, float)) and budget > 0):
        raise ParameterError("budget_cpu_s", budget_cpu_s, "> 0 CPU seconds, 'auto' or None")
    scene_arg = str(scene) if isinstance(scene, (str, Path)) else None
    scene = load_scene(scene)
    selected = None if engines is None else [n for n in resolve_engines(engines)
                                             if n != REFERENCE]
    if selected is not None and not selected:
        raise ParameterError("engines", engines, "at least one engine besides the analytic model")
    states = [r for r in engine_states(selected) if r["name"] != REFERENCE]
    names = _order([r["name"] for r in states if r["state"] == "ran"])
    vset = validation_set(scene, size=size, seed=SEED if seed is None else seed,
                          vertical=vertical)
    choice = [c for c in vset if c.part == "choice"]
    held = [c for c in vset if c.part == "held-out"]
    sim_choice = sum(c.duration for c in choice)
    sim_held = sum(c.duration for c in held)

    from ..progress import bar as progress_bar

    from ..machine import tree_cpu_s

    track = progress_bar(None, "search", "CPU s", show=progress)
    ledger: dict[str, float] = {"spent": 0.0, "runs": 0.0, "tree0": tree_cpu_s()}
    frames: list[pd.DataFrame] = []

    def measure(eng: str, over: dict[str, Any], cases, label: str) -> pd.DataFrame:
        if progress:
            track.set_postfix_str(f"{eng} {label}")

        def on_row(row: dict[str, Any]) -> None:
            c = sum(row.get("cpu_s") or [])
            ledger["runs"] += c
            track.update(round(c, 3))

        r = tradeoff(scene, [eng], exact=[over], cases=cases, repeat=1,
                     self_consistency="none", executor=executor, workers=workers,
                     store=store, progress=False, on_row=on_row).runs
        frames.append(r)
        _account(ledger)
        shown = getattr(track, "n", None)
        if isinstance(shown, (int, float)) and ledger["spent"] > shown:
            track.update(round(ledger["spent"] - shown, 3))   # the builds and pools too
        return r

    best: dict[float, tuple[float, str]] = {}          # tolerance -> (cost, engine) confirmed
    outcome: dict[tuple[float, str], dict[str, Any]] = {}
    knobs: dict[str, str] = {}
    contact_rows: list[dict[str, Any]] = []
    ladders: list[_Ladder] = []
    ctx = dict(tols=tols, choice=choice, held=held, measure=measure, best=best)
    with kept_pools():
        for n in names:
            knob, values = precision_knob(n)
            knobs[n] = knob
            if dts is not None and knob == "dt":
                values = tuple(sorted({float(d) for d in dts}, reverse=True))
            variants: list[dict[str, Any]] = [{}]
            if contact and get_backend(n).contact_variants and choice:
                variants += _contact_search(n, knob, values, choice, measure, contact_rows)
            ladders += [_Ladder(n, knob, values, v, float(get_backend(n).relative_cost), ctx)
                        for v in variants]
        stopped = _race(ladders, ledger, budget, sim_choice, sim_held, track)
    for lad in ladders:
        lad.finish(outcome, stopped)
    track.close()
    runs = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
    evidence = summarize(runs) if len(runs) else pd.DataFrame()
    rows = outcome_rows(tols, names, states, outcome)
    overhead = max(ledger["spent"] / ledger["runs"], 1.0) if ledger["runs"] > 0 else 1.0
    finest: dict[str, tuple[float, float]] = {}
    for lad in ladders:               # the finest rung each engine ran (any contact variant)
        if lad.rungs and (lad.engine not in finest
                          or lad.rungs[-1].value < finest[lad.engine][0]):
            finest[lad.engine] = (lad.rungs[-1].value, lad.rungs[-1].cost)
    nexts = {t: next_step(t, rows, knobs, scene_arg or scene.name, sim_choice + sim_held,
                           size, float(vertical), overhead, finest)
             for t in tols}
    return Decision(scene=scene.name, size=size, tolerances=tols, outcomes=rows,
                    evidence=evidence, runs=runs, cases=vset, coverage=coverage(vset),
                    next_steps=nexts, engines=states, cpu_s=ledger["spent"], stopped=stopped,
                    knobs=knobs, machine=machine_info(), contact=pd.DataFrame(contact_rows),
                    vertical=float(vertical), runs_cpu_s=ledger["runs"])


def _auto_budget(size: str) -> float | None:
    """The default budget of an evidence size: :data:`BUDGETS`, or every size's the
    environment variable ``ROCKBENCH_SEARCH_BUDGET`` gives (CPU seconds, or ``none``: no
    limit; e.g. a test suite whose answer must not depend on the machine's load)."""
    import os

    env = os.environ.get("ROCKBENCH_SEARCH_BUDGET", "").strip().lower()
    if not env:
        return BUDGETS[size]
    if env == "none":
        return None
    try:
        value = float(env)
    except ValueError:
        value = math.nan
    if not value > 0:
        raise ParameterError("ROCKBENCH_SEARCH_BUDGET", env, "> 0 CPU seconds or 'none'")
    return value


def _label(engine: str, knob: str, value: float, variant: Mapping[str, Any]) -> str:
    """The setting's label as every table writes it (:attr:`rockbench.studies.tradeoff.
    Setting.label`)."""
    from .tradeoff import Setting

    return Setting(engine, tuple(sorted({knob: value, **variant}.items()))).label


def _account(ledger: dict[str, float]) -> None:
    """What the search has spent so far [CPU s]: the process CPU of this process and its
    workers since it started (the runs, the model builds, the warm-ups, the pools and the
    store: what the user waits for), or the runs' own CPU when that is more (workers this
    machine does not see, e.g. a Dask cluster's)."""
    from ..machine import tree_cpu_s

    ledger["spent"] = max(tree_cpu_s() - ledger["tree0"], ledger["runs"])


def _rung_cpu_s(lad: "_Ladder", ledger: dict[str, float], sim_choice: float,
                sim_held: float) -> float:
    """The estimated CPU [s] of a ladder's next rung as the budget counts it: its choice part,
    plus its held-out part when that rung may be confirmed (a tolerance still open whose
    last rung is within it), each at the rung's estimated cost per simulated second, scaled by
    what the search has spent so far over its runs' own CPU (the model builds, warm-ups and
    pools around them)."""
    per = lad.estimate()
    if not math.isfinite(per):
        return 0.0
    sim = sim_choice
    if lad.rungs and any(lad.rungs[-1].choice_error <= t for t in lad.open()):
        sim += sim_held
    overhead = ledger["spent"] / ledger["runs"] if ledger["runs"] > 0 else 1.0
    return per * sim * max(overhead, 1.0)


def _race(ladders: list["_Ladder"], ledger: dict[str, float], budget: float | None,
          sim_choice: float, sim_held: float, track) -> str:
    """Run the ladders' rungs: every coarsest rung first (in the ladders' order), then always
    the cheapest next rung of a ladder still in the race; returns why the search stopped early
    ("" when it did not). A rung whose estimated CPU (:func:`_rung_cpu_s`) would take the
    search past its budget is not started."""
    first = True
    while True:
        alive = [lad for lad in ladders if lad.alive()]
        if not alive:
            return ""
        if first:
            fresh = [lad for lad in alive if not lad.rungs]
            if fresh:
                lad = fresh[0]
            else:
                first = False
                continue
        else:
            lad = min(alive, key=lambda x: x.estimate())
        if lad.rungs and lad.cannot_win():
            continue                       # cannot_win marks it dearer: out of the race
        _account(ledger)
        est = _rung_cpu_s(lad, ledger, sim_choice, sim_held)
        if budget is not None and ledger["spent"] + est > budget:
            why = f"the search's CPU budget ({budget:g} s) ended"
            for x in alive:
                x.stop = why
            return f"CPU budget of {budget:g} s reached"
        if track is not None:
            left = sum(_rung_cpu_s(x, ledger, sim_choice, sim_held) for x in alive)
            track.total = round(min(ledger["spent"] + left, budget or math.inf), 1)
        lad.step()


class _Ladder:
    """One engine (and contact variant) going down its precision knob: its rungs so far, the
    tolerances settled for it, its held-out failures; :meth:`step` runs its next rung."""

    def __init__(self, engine: str, knob: str, values, variant: Mapping[str, Any],
                 relative_cost: float, ctx: dict[str, Any]):
        self.engine, self.knob, self.variant = engine, knob, dict(variant)
        self.values = list(values)
        self.rel = relative_cost
        self.ctx = ctx
        self.rungs: list[_Rung] = []
        self.failed: dict[float, list[float]] = {t: [] for t in ctx["tols"]}
        self.held_err: dict[float, tuple[float, float]] = {}
        self.settled: dict[float, dict[str, Any] | None] = {t: None for t in ctx["tols"]}
        self.dearer: dict[float, str] = {}
        self.stop = ""
        self.i = 0

    def open(self) -> list[float]:
        return [t for t in self.ctx["tols"] if self.settled[t] is None and t not in self.dearer]

    def alive(self) -> bool:
        return bool(self.open()) and not self.stop and self.i < len(self.values)

    def value(self) -> float:
        return self.values[self.i]

    def estimate(self) -> float:
        """CPU s per simulated s of the next rung: the last rung's, scaled by the step ratio
        for a time step (a first rung: a guess from the backend's relative cost)."""
        if not self.rungs:
            return _FIRST_GUESS * self.rel
        last = self.rungs[-1]
        ratio = (last.value / self.value()) if self.knob == "dt" else 1.0
        return last.cost * ratio if math.isfinite(last.cost) else _FIRST_GUESS * self.rel

    def candidate_cost(self, t: float) -> float:
        """The least this ladder's answer at ``t`` could cost [CPU s per simulated s]: its last
        rung's, when that rung is within ``t`` and only awaits a finer one to confirm it;
        else the next rung's estimate (a finer answer costs at least that)."""
        last = self.rungs[-1]
        if last.choice_error <= t and last.value not in self.failed[t]:
            return last.cost
        return self.estimate()

    def cannot_win(self) -> bool:
        """True (and every open tolerance marked dearer) when, for every open tolerance, a
        confirmed answer already costs less than the least this ladder could still be
        recommended at (beyond the tie margin: a tie is still searched and reported)."""
        best = self.ctx["best"]
        open_t = self.open()
        costs = {t: self.candidate_cost(t) for t in open_t}
        if not all(t in best and math.isfinite(costs[t]) and best[t][0] * TIE < costs[t]
                   for t in open_t):
            return False
        for t in open_t:
            self.dearer[t] = (f"stopped before {self.knob}={self.value():g}: its answer would "
                              f"cost at least {costs[t]:.3g} CPU s/s, more than "
                              f"{best[t][1]}'s confirmed {best[t][0]:.3g}")
        return True

    def step(self) -> None:
        value = self.value()
        setting = _label(self.engine, self.knob, value, self.variant)
        r = self.ctx["measure"](self.engine, {self.knob: value, **self.variant},
                                self.ctx["choice"], setting + " (choice)")
        self.rungs.append(_Rung(value, setting, _worst_or_inf(r), _cost(r)))
        for t in self.open():
            self._settle(t)
        last = self.i == len(self.values) - 1
        self.i += 1
        if last and any(self.settled[t] is None and self.rungs[-1].choice_error <= t
                        for t in self.open()):
            nxt = finer(self.knob, value)        # confirm the finest value by a finer one
            if nxt is not None:
                self.values.append(nxt)

    def _settle(self, t: float) -> None:
        """The convergence rule at ``t`` on the rungs finer than its last held-out failure;
        an accepted value confirmed on the held-out part."""
        floor = min(self.failed[t]) if self.failed[t] else math.inf
        pts = [(r.value, r.choice_error) for r in self.rungs if r.value < floor]
        conv = convergence(pts, t)
        if conv["index"] is None:
            return
        value = conv["step"]
        rung = next(r for r in self.rungs if r.value == value)
        held = self.ctx["held"]
        if value not in self.held_err:
            h = self.ctx["measure"](self.engine, {self.knob: value, **self.variant}, held,
                                    rung.setting + " (held-out)")
            self.held_err[value] = (_worst(h), _cost(h))
        h_err, h_cost = self.held_err[value]
        rung.held_error = h_err
        if not held or math.isnan(h_err) or h_err <= t:
            cost = _mean_cost(rung.cost, h_cost)
            self.settled[t] = {
                "status": "meets", "setting": rung.setting, "value": value,
                "worst_error_choice": rung.choice_error, "worst_error_heldout": h_err,
                "cpu_per_sim_s": cost, "erratic": conv["erratic"],
                "reason": f"converged: {conv['note']}"
                + ("; held out: no counted case" if math.isnan(h_err) else "")}
            best = self.ctx["best"]
            if t not in best or cost < best[t][0]:
                best[t] = (cost, self.engine)
        else:
            self.failed[t].append(value)

    def finish(self, outcome: dict, stopped: str) -> None:
        """This ladder's outcome at every tolerance (the engine's best ladder wins: a meets
        over any other fate, then the cheaper)."""
        for t in self.ctx["tols"]:
            o = self.settled[t]
            if o is None:
                o = fate(self.engine, self.knob, t, self.rungs, self.failed, self.held_err,
                          self.dearer.get(t))
                if self.stop and t in self.open():
                    o["reason"] = f"{o['reason']}; {self.stop}"
                    if o["status"] in ("not converged", "not reached"):
                        o["status"] = "budget ended"      # the search, not the engine
            if self.variant:
                o["reason"] = f"{o['reason']} (contact settings: " + ", ".join(
                    f"{k}={v}" for k, v in sorted(self.variant.items())) + ")"
            prev = outcome.get((t, self.engine))
            if prev is None or _better(o, prev):
                outcome[(t, self.engine)] = o


def _better(a: dict[str, Any], b: dict[str, Any]) -> bool:
    """Whether outcome ``a`` of an engine beats ``b`` (two contact variants of it)."""
    if (a["status"] == "meets") != (b["status"] == "meets"):
        return a["status"] == "meets"
    if a["status"] == "meets":
        return a["cpu_per_sim_s"] < b["cpu_per_sim_s"]
    ea, eb = a.get("worst_error_choice", math.inf), b.get("worst_error_choice", math.inf)
    return (ea if ea == ea else math.inf) < (eb if eb == eb else math.inf)


def _worst_or_inf(r: pd.DataFrame) -> float:
    e = _worst(r)
    if math.isnan(e):
        return math.inf if len(r) and not r["near_boundary"].astype(bool).all() else math.nan
    return e


def _mean_cost(a: float, b: float) -> float:
    vals = [v for v in (a, b) if math.isfinite(v)]
    return float(np.mean(vals)) if vals else math.nan


def _contact_search(n, knob, ladder, choice, measure, rows) -> list[dict[str, Any]]:
    """The engine's contact variants (backend ``contact_variants``) measured one at a time from
    its defaults on the impact probes of the choice part (the two largest free-rocking cases
    and the smallest-uplift record); the helpful ones (error below 0.9 x the defaults'), alone
    and combined, are returned to be searched like the defaults."""
    from ..engines import get_backend

    free = sorted([c for c in choice if c.kind == "free"], key=lambda c: -abs(c.phi0))
    recs = sorted([c for c in choice if c.kind == "record"],
                  key=lambda c: abs(dict(c.motion)["scale"]))
    probes = free[:2] + recs[:1]
    if not probes:
        return []
    cls = get_backend(n)
    default = getattr(cls.Settings(), knob, ladder[len(ladder) // 2])
    names = {c.name for c in probes}

    def probe(over):
        r = measure(n, {knob: default, **over}, probes, "contact probe")
        r = r[r["case"].isin(names)]
        eta = r.loc[r["kind"] == "free", "error"].to_numpy(dtype=float)
        rec = r.loc[r["kind"] != "free", "error"].to_numpy(dtype=float)
        e1 = float(np.nanmax(eta)) if eta.size else math.nan
        e2 = float(np.nanmax(rec)) if rec.size else math.nan
        return max(e1, e2), e1, e2

    b, b1, b2 = probe({})
    rows.append({"engine": n, "variant": "", knob: default, "probe_error": b, "eta_error": b1,
                 "record_error": b2, "change": 1.0})
    helpful = []
    for v in cls.contact_variants:
        try:
            cls.Settings(**{knob: default, **v})
        except Exception as e:  # noqa: BLE001 - a variant this version refuses
            rows.append({"engine": n, "variant": str(v), "reason": str(e)})
            continue
        e, e1, e2 = probe(dict(v))
        rows.append({"engine": n, "variant": ",".join(f"{k}={v[k]}" for k in sorted(v)),
                     knob: default, "probe_error": e, "eta_error": e1, "record_error": e2,
                     "change": e / b if 0 < b < math.inf and math.isfinite(e) else math.nan})
        if e < 0.9 * b:
            helpful.append((e, dict(v)))
    helpful.sort(key=lambda x: x[0])
    out = [helpful[0][1]] if helpful else []
    combo: dict[str, Any] = {}
    for _, v in helpful:
        if not set(v) & set(combo):
            combo.update(v)
    if helpful and len(combo) > len(helpful[0][1]):
        try:
            cls.Settings(**{knob: default, **combo})
            out.append(combo)
        except Exception:  # noqa: BLE001
            pass
    return out
