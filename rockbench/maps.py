"""Overturning maps (the paper's Figs. 4-7) for any backend: grids of Ricker pulses, a resumable
Parquet store, and the agreement of two maps.

A map is one row per cell (:data:`MAP_COLUMNS`): the pulse (``pulse`` shape, ``sign``) at
``amplitude`` A = a_g / (g tan alpha) and ``frequency`` W = omega_g / p (alpha and p of the
taller column), each run from rest for the pulse window (6 T_g) plus 10 s.

* :func:`map_cells` - the grid (inclusive ranges, ``grid=(nA, nW)``, the pulses selected);
* :func:`run_map` - run every cell with one backend: the analytic model through its compiled
  path (:mod:`rockbench.analytic.compiled`, ``method="compiled"``, the default for maps) or the
  ``solve_ivp`` reference (``method="solve_ivp"``); engines through :func:`rockbench.sweep.run_cases`
  (MuJoCo batched in ``mujoco.rollout``), on a local process pool or a Dask cluster. With a
  ``store`` (a Parquet dataset: a folder ``NAME.parquet`` of parts plus ``_inputs.json``) every
  finished chunk is written at once; a rerun skips the stored cells, and a store written for
  other inputs is refused;
* :func:`map_agreement` - two maps cell by cell: fraction of agreeing verdicts, Cohen's kappa,
  and the shift of the minimum-overturning boundary along A, per frequency.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pandas as pd

from .errors import ParameterError, RockbenchError

__all__ = ["MAP_COLUMNS", "PULSES", "map_cells", "run_map", "load_map", "reuse_map",
           "map_agreement", "boundary"]

#: The pulses of a map: name -> (shape, sign).
PULSES: dict[str, tuple[str, int]] = {"symmetric+": ("symmetric", 1),
                                      "symmetric-": ("symmetric", -1),
                                      "antisymmetric+": ("antisymmetric", 1),
                                      "antisymmetric-": ("antisymmetric", -1)}

#: Columns of a map, with unit and meaning.
MAP_COLUMNS: dict[str, str] = {
    "amplitude": "-, A = a_g / (g tan alpha), alpha of the taller column",
    "frequency": "-, W = omega_g / p, p of the taller column",
    "pulse": "-, symmetric | antisymmetric Ricker pulse (paper Eqs. 29, 30)",
    "sign": "-, +1 the pulse as printed, -1 mirrored",
    "overturned": "-, |phi| reached the fall angle (engines: or came to rest beyond the critical angle)",
    "exceeded_critical": "-, |phi| exceeded the critical angle of its potential",
    "max_abs_phi_over_alpha": "-, max |phi| / alpha",
    "n_impacts": "-, impacts of the run",
    "fractured": "-, tendons fractured",
    "status": "-, ok | diverged | invalid | error",
    "wall_s": "s, wall time of the integration or stepping (batched: the cell's share)",
}

_KEY = ("pulse", "sign", "amplitude", "frequency")


def _range(text_or_pair: Any, name: str) -> tuple[float, float]:
    if isinstance(text_or_pair, str):
        parts = text_or_pair.split(":")
        if len(parts) != 2:
            raise ParameterError(name, text_or_pair, "LO:HI (inclusive), e.g. 0.5:8")
        try:
            lo, hi = float(parts[0]), float(parts[1])
        except ValueError:
            raise ParameterError(name, text_or_pair, "LO:HI with two numbers") from None
    else:
        lo, hi = (float(x) for x in text_or_pair)
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi):
        raise ParameterError(name, text_or_pair, "0 < LO <= HI, both finite")
    return lo, hi


def _grid(text_or_pair: Any) -> tuple[int, int]:
    if isinstance(text_or_pair, str):
        try:
            na, nw = (int(x) for x in text_or_pair.lower().split("x"))
        except ValueError:
            raise ParameterError("grid", text_or_pair, "NAxNW, e.g. 100x100") from None
    else:
        na, nw = (int(x) for x in text_or_pair)
    if not (1 <= na <= 1000 and 1 <= nw <= 1000):
        raise ParameterError("grid", text_or_pair, "NAxNW with 1 <= NA, NW <= 1000")
    return na, nw


def _pulses(pulses: str | Sequence[str]) -> list[str]:
    names = list(PULSES) if pulses in ("all", None) else (
        [p.strip() for p in pulses.split(",")] if isinstance(pulses, str) else list(pulses))
    bad = [p for p in names if p not in PULSES]
    if bad or not names:
        raise ParameterError("pulses", pulses, f"all, or a comma-separated subset of "
                                               f"{', '.join(PULSES)}")
    return names


def map_cells(*, grid: Any = (100, 100), amplitude: Any = (0.5, 8.0),
              frequency: Any = (0.5, 10.0), pulses: str | Sequence[str] = "all"
              ) -> list[tuple[str, int, float, float]]:
    """The cells (shape, sign, A, W) of a map: ``grid`` = (nA, nW) points spread evenly over
    the inclusive ranges ``amplitude`` and ``frequency`` ("LO:HI" or a pair), for each selected
    pulse. ``grid=(8, 8), amplitude="1:8"`` gives A = 1, 2, ..., 8."""
    na, nw = _grid(grid)
    a0, a1 = _range(amplitude, "amplitude")
    w0, w1 = _range(frequency, "frequency")
    As = np.linspace(a0, a1, na) if na > 1 else np.array([a0])
    Ws = np.linspace(w0, w1, nw) if nw > 1 else np.array([w0])
    As, Ws = np.round(As, 12), np.round(Ws, 12)
    return [(PULSES[p][0], PULSES[p][1], float(A), float(W))
            for p in _pulses(pulses) for W in Ws for A in As]


# ------------------------------------------------------------------------------------------
# The store: a Parquet dataset folder with the inputs it was written for
# ------------------------------------------------------------------------------------------
def _inputs(scene, scene_ref: str, engine: str, settings: dict, method: str,
            tail: float | None, keyed_by_code: bool = True) -> dict[str, Any]:
    """What a store was written for. ``keyed_by_code``: include rockbench's code fingerprint
    (a store written by other code is refused); without it the store is keyed by the inputs
    and the engine's version only, and its reuse must be verified by re-running sample cells
    (:func:`verify_map`)."""
    from .engines import engine_info
    from .sweep.store import code_fingerprint

    out = {"scene": scene.to_dict(), "scene_ref": scene_ref, "engine": engine,
           "engine_version": next((str(r.get("version", r.get("reason")))
                                   for r in engine_info() if r["name"] == engine), ""),
           "settings": {k: settings[k] for k in sorted(settings)}, "method": method,
           "duration": f"pulse window (6 T_g) + {10.0 if tail is None else tail:g} s"}
    if keyed_by_code:
        out["code"] = code_fingerprint()
    return out


def _open_store(path: Path, inputs: dict[str, Any]) -> pd.DataFrame:
    """Rows already in the store at ``path`` (created if missing); refuse a store written for
    other inputs (scene, engine, settings, method or code)."""
    meta = path / "_inputs.json"
    if path.exists() and not path.is_dir():
        raise ParameterError("store", str(path), "a map store folder (NAME.parquet), not a file")
    if meta.is_file():
        old = json.loads(meta.read_text())
        diff = [k for k in inputs if old.get(k) != inputs[k]]
        if diff:
            raise RockbenchError(
                f"map store {path} was written for other inputs ({', '.join(diff)} differ: "
                f"{', '.join(f'{k}={old.get(k)!r}' for k in diff if k != 'scene')}); use "
                f"another --store, or delete it to start again")
        return load_map(path)
    path.mkdir(parents=True, exist_ok=True)
    tmp = path / f".tmp-inputs-{os.getpid()}"
    tmp.write_text(json.dumps(inputs, indent=1, sort_keys=True))
    os.replace(tmp, meta)
    return pd.DataFrame(columns=list(MAP_COLUMNS))


def _write_chunk(path: Path, rows: pd.DataFrame) -> None:
    import uuid

    name = f"part-{uuid.uuid4().hex[:16]}.parquet"
    tmp = path / f".tmp-{name}"
    rows.to_parquet(tmp, index=False)
    os.replace(tmp, path / name)


def load_map(store: str | os.PathLike) -> pd.DataFrame:
    """Every cell of a map store (columns :data:`MAP_COLUMNS`, one row per cell; a cell
    written twice keeps its last row)."""
    path = Path(store)
    if not path.is_dir():
        raise ParameterError("store", str(store), "an existing map store folder")
    parts = sorted(path.glob("part-*.parquet"), key=lambda p: p.stat().st_mtime)
    frames = [pd.read_parquet(p) for p in parts]
    frames = [f for f in frames if len(f)]
    if not frames:
        return pd.DataFrame(columns=list(MAP_COLUMNS))
    df = pd.concat(frames, ignore_index=True)
    return df.drop_duplicates(list(_KEY), keep="last").reset_index(drop=True)


# ------------------------------------------------------------------------------------------
# Running a map
# ------------------------------------------------------------------------------------------
def _duration(scene, W: float, tail: float | None) -> float | None:
    """Run length [s] of a cell: the pulse window 6 T_g plus ``tail`` (None: the default, + 10 s)."""
    if tail is None:
        return None
    return 6.0 * 2.0 * math.pi / (W * scene.p) + tail


def _analytic_chunk(args: tuple) -> pd.DataFrame:
    """One chunk of analytic cells (in a worker): compiled path or the solve_ivp reference."""
    scene_ref, overrides, cells, method, tail = args
    from .scene.scene import load_scene

    scene = load_scene(scene_ref, overrides or None)
    if method == "compiled":
        from .analytic.compiled import run_pulse_grid
        if tail is None:
            df = run_pulse_grid(scene, cells)
        else:
            byw: dict[float, list] = {}
            for c in cells:
                byw.setdefault(c[3], []).append(c)
            df = pd.concat([run_pulse_grid(scene, cs, duration=_duration(scene, w, tail))
                            for w, cs in byw.items()], ignore_index=True)
        df["wall_s"] = df["cpu_s"]
        return df[list(MAP_COLUMNS)]
    from .runner import run
    rows = []
    for shape, sign, A, W in cells:
        from .scene.motion import RickerPulse
        pulse = RickerPulse.dimensionless(A, W, scene.structure, shape, sign)
        r = run(scene, pulse, history="minimal", duration=_duration(scene, W, tail))
        s = r.summary
        rows.append({"amplitude": A, "frequency": W, "pulse": shape, "sign": sign,
                     "overturned": s.overturned, "exceeded_critical": s.exceeded_critical,
                     "max_abs_phi_over_alpha": s.max_abs_phi_over_alpha,
                     "n_impacts": s.n_impacts, "fractured": s.fractured, "status": s.status,
                     "wall_s": r.cost.wall_s})
    return pd.DataFrame(rows, columns=list(MAP_COLUMNS))


def _tidy(df: pd.DataFrame) -> pd.DataFrame:
    df = df.copy()
    for c in ("amplitude", "frequency", "max_abs_phi_over_alpha", "wall_s"):
        df[c] = df[c].astype("float64")
    df["sign"] = df["sign"].astype("int64")
    df["n_impacts"] = pd.array([None if pd.isna(v) else int(v) for v in df["n_impacts"]],
                               dtype="Int64")
    for c in ("overturned", "exceeded_critical", "fractured"):
        df[c] = pd.array([None if v is None or v is pd.NA or (isinstance(v, float)
                                                              and math.isnan(v)) else bool(v)
                          for v in df[c]], dtype="boolean")
    df["pulse"] = df["pulse"].astype(str)
    df["status"] = df["status"].astype(str)
    return df[list(MAP_COLUMNS)]


def run_map(scene: str, engine: str = "analytic", *, grid: Any = (100, 100),
            amplitude: Any = (0.5, 8.0), frequency: Any = (0.5, 10.0),
            pulses: str | Sequence[str] = "all", overrides: dict | None = None,
            settings: dict | None = None, method: str | None = None,
            store: str | os.PathLike | None = None, workers: int | None = None,
            scheduler: str | None = None, progress: bool = True,
            chunk: int | None = None, tail: float | None = None,
            keyed_by_code: bool = True) -> pd.DataFrame:
    """Run an overturning map of ``scene`` (a built-in name or a .toml path, with scene
    ``overrides``) with backend ``engine`` (and its ``settings`` overrides) and return it
    (:data:`MAP_COLUMNS`, sorted by pulse, sign, frequency, amplitude).

    ``method`` (analytic only): "compiled" (default when numba imports) or "solve_ivp".
    ``store``: a Parquet dataset folder (created; resumed when it exists for the same inputs;
    refused for other inputs). ``workers``: local processes (default: the cores);
    ``scheduler``: the address of a running Dask scheduler (``tcp://host:port``).
    ``progress``: a tqdm bar with cells done, rate, time left and how many were reused.
    ``tail``: free rocking after the pulse window [s] (default None: 10 s, the package
    default); shorter tails are for quick looks and tests (a frame that falls later is missed).
    ``keyed_by_code``: False keys the store by its inputs and the engine version only (not by
    rockbench's code), for measured maps kept across code changes that are checked with
    :func:`verify_map` before they are reused.
    """
    from .runner import resolve_engines
    from .scene.scene import load_scene
    from .sweep.executors import check_options, execute

    sc = load_scene(scene, overrides or None)
    (engine,) = resolve_engines([engine], name="engine")
    settings = dict(settings or {})
    if engine == "analytic":
        method = method or _default_method()
        if method not in ("compiled", "solve_ivp"):
            raise ParameterError("method", method, "'compiled' or 'solve_ivp'")
        if method == "compiled" and settings:
            raise ParameterError("settings", settings, "none with method='compiled'")
    elif method is not None:
        raise ParameterError("method", method, "given only for the analytic backend")
    executor = "dask" if scheduler else "process"
    check_options(executor, workers, scheduler)
    cells = map_cells(grid=grid, amplitude=amplitude, frequency=frequency, pulses=pulses)
    path = Path(store) if store is not None else None
    done = pd.DataFrame(columns=list(MAP_COLUMNS))
    if path is not None:
        done = _open_store(path, _inputs(sc, str(scene), engine, settings, method or "", tail,
                                        keyed_by_code))
    have = {(p, int(s), round(float(a), 9), round(float(w), 9))
            for p, s, a, w in zip(done["pulse"], done["sign"], done["amplitude"],
                                  done["frequency"])}
    todo = [c for c in cells if (c[0], c[1], round(c[2], 9), round(c[3], 9)) not in have]
    reused = len(cells) - len(todo)
    frames = [done]

    def on_result(_key: str, df: pd.DataFrame) -> None:
        frames.append(df)
        if path is not None:
            _write_chunk(path, _tidy(df))

    n_workers = workers or (os.cpu_count() or 1)
    if engine == "analytic":
        size = chunk or (max(1, min(200, math.ceil(len(todo) / (4 * n_workers)))))
        items = [(f"chunk-{i}", (str(scene), overrides or {}, todo[i:i + size], method, tail))
                 for i in range(0, len(todo), size)]
        execute(_analytic_chunk, items, on_result=on_result,
                crashed=lambda item, why: _crashed(item[2], why),
                label=lambda item: f"{len(item[2])} cells",
                executor=executor, workers=workers, dask_address=scheduler,
                progress=progress and bool(items),
                desc=f"map {sc.name} analytic ({reused} reused)", unit="chunk")
    elif todo:
        size = chunk or 64
        for i in range(0, len(todo), size):
            on_result("", _engine_rows(str(scene), overrides, engine, settings, todo[i:i + size],
                                       tail, executor=executor, workers=workers,
                                       dask_address=scheduler, progress=progress))
    out = pd.concat([f for f in frames if len(f)], ignore_index=True) if any(
        len(f) for f in frames) else pd.DataFrame(columns=list(MAP_COLUMNS))
    out = _tidy(out).drop_duplicates(list(_KEY), keep="last")
    keep = {(c[0], c[1], round(c[2], 9), round(c[3], 9)) for c in cells}
    mask = [(p, int(s), round(a, 9), round(w, 9)) in keep for p, s, a, w in
            zip(out["pulse"], out["sign"], out["amplitude"], out["frequency"])]
    out = out[mask].sort_values(["pulse", "sign", "frequency", "amplitude"],
                                ascending=[True, False, True, True]).reset_index(drop=True)
    out.attrs.update(scene=sc.name, engine=engine, method=method or "", reused=reused)
    return out


def _engine_rows(scene_ref: str, overrides: dict | None, engine: str, settings: dict,
                 cells: Sequence, tail: float | None, **execution) -> pd.DataFrame:
    """Map rows of engine ``cells`` (shape, sign, A, W), run through
    :func:`rockbench.sweep.run_cases` (MuJoCo batched) with ``execution`` options."""
    from .scene.scene import load_scene
    from .sweep import run_cases

    sc = load_scene(scene_ref, overrides or None)
    cases = [{"scene": scene_ref, "overrides": overrides or {}, "engine": engine,
              "settings": settings, "duration": _duration(sc, W, tail),
              "motion": {"kind": "ricker", "shape": sh, "sign": sg, "A": A, "W": W}}
             for sh, sg, A, W in cells]
    rows = run_cases(cases, **execution)
    return pd.DataFrame({
        "amplitude": rows["motion.A"], "frequency": rows["motion.W"],
        "pulse": rows["motion.shape"], "sign": rows["motion.sign"],
        "overturned": rows["overturned"], "exceeded_critical": rows["exceeded_critical"],
        "max_abs_phi_over_alpha": rows["max_abs_phi_over_alpha"],
        "n_impacts": rows["n_impacts"], "fractured": rows["fractured"],
        "status": rows["status"], "wall_s": rows["wall_s"]})


# ------------------------------------------------------------------------------------------
# Reusing a measured map: verified by re-running sample cells
# ------------------------------------------------------------------------------------------
#: Relative tolerance on max |phi| / alpha when a stored cell is re-run (the engines are
#: deterministic: the same wheel on the same kind of CPU reproduces a run bit for bit).
VERIFY_RTOL = 1e-6


def _check_cells(df: pd.DataFrame, n: int) -> pd.DataFrame:
    """Up to ``n`` stored cells to re-run: short runs (the highest frequencies), one per pulse
    and sign, alternately a survivor that rocked (the median rocking amplitude of the
    survivors) and an overturning cell far from the boundary (the largest A)."""
    top = df[df["frequency"] >= df["frequency"].quantile(0.66)]
    picks = []
    for i, ((_p, _s), g) in enumerate(top.groupby(["pulse", "sign"], sort=True)):
        g = g[g["status"] == "ok"]
        ot = g[g["overturned"].astype(bool)]
        sv = g[~g["overturned"].astype(bool) & (g["max_abs_phi_over_alpha"] > 0.05)]
        if i % 2 == 0 and len(sv):
            sv = sv.sort_values("max_abs_phi_over_alpha")
            picks.append(sv.iloc[len(sv) // 2])
        elif len(ot):
            picks.append(ot.sort_values(["amplitude", "frequency"]).iloc[-1])
        elif len(g):
            picks.append(g.iloc[len(g) // 2])
        if len(picks) >= n:
            break
    return pd.DataFrame(picks).reset_index(drop=True)


def reuse_map(store: str | os.PathLike, scene: str, engine: str, *, grid: Any,
              amplitude: Any, frequency: Any, pulses: str | Sequence[str] = "all",
              tail: float | None = None, check: int = 4,
              rtol: float = VERIFY_RTOL) -> tuple[pd.DataFrame | None, str]:
    """A measured map (a store written with ``keyed_by_code=False``) if it can be trusted on
    this code and machine: written for the same scene, engine version, default settings and
    run length, complete for the grid, and reproduced at ``check`` cells re-run now (verdicts,
    status and impacts equal, max |phi| / alpha within ``rtol``). Returns (map, how it was
    verified) or (None, why it is not reused)."""
    path = Path(store)
    meta = path / "_inputs.json"
    if not meta.is_file():
        return None, f"no measured map at {path}"
    from .scene.scene import load_scene

    sc = load_scene(scene)
    want = _inputs(sc, str(scene), engine, {}, "", tail, keyed_by_code=False)
    old = json.loads(meta.read_text())
    diff = [k for k in want if old.get(k) != want[k]]
    if diff:
        return None, (f"the measured map {path.name} was written for other inputs "
                      f"({', '.join(diff)} differ)")
    cells = map_cells(grid=grid, amplitude=amplitude, frequency=frequency, pulses=pulses)
    df = load_map(path)
    keys = {(p, int(s), round(float(a), 9), round(float(w), 9))
            for p, s, a, w in zip(df["pulse"], df["sign"], df["amplitude"], df["frequency"])}
    missing = [c for c in cells if (c[0], c[1], round(c[2], 9), round(c[3], 9)) not in keys]
    if missing:
        return None, f"the measured map {path.name} lacks {len(missing)} of {len(cells)} cells"
    df = _tidy(df)
    keep = {(c[0], c[1], round(c[2], 9), round(c[3], 9)) for c in cells}
    df = df[[(p, int(s), round(a, 9), round(w, 9)) in keep for p, s, a, w in
             zip(df["pulse"], df["sign"], df["amplitude"], df["frequency"])]]
    df = df.sort_values(["pulse", "sign", "frequency", "amplitude"],
                        ascending=[True, False, True, True]).reset_index(drop=True)
    picks = _check_cells(df, check)
    now = _tidy(_engine_rows(str(scene), None, engine, {}, [
        (r.pulse, int(r.sign), float(r.amplitude), float(r.frequency))
        for r in picks.itertuples()], tail, executor="serial", progress=False))
    m = picks.merge(now, on=list(_KEY), suffixes=("", "_now"))
    worst = 0.0
    for r in m.itertuples():
        cell = (f"{r.pulse} {'+' if r.sign > 0 else '-'} A={r.amplitude:.4g} "
                f"W={r.frequency:.4g}")
        for c in ("status", "overturned", "exceeded_critical", "fractured", "n_impacts"):
            if getattr(r, c) != getattr(r, c + "_now"):
                return None, (f"the measured map {path.name} does not reproduce: at {cell} "
                              f"{c} was {getattr(r, c)}, is {getattr(r, c + '_now')} now")
        a, b = r.max_abs_phi_over_alpha, r.max_abs_phi_over_alpha_now
        d = abs(a - b) / max(abs(a), 1e-12)
        worst = max(worst, d)
        if not d <= rtol:
            return None, (f"the measured map {path.name} does not reproduce: at {cell} max "
                          f"|phi|/alpha was {a:.9g}, is {b:.9g} now")
    df.attrs.update(scene=sc.name, engine=engine, method="", reused=len(df))
    return df, (f"measured earlier ({len(df)} cells, {want['engine_version']}), "
                f"reproduced now at {len(m)} re-run cells (largest relative difference in "
                f"max |phi|/alpha {worst:.1e})")


def _crashed(cells, why: str) -> pd.DataFrame:
    return pd.DataFrame([{"amplitude": A, "frequency": W, "pulse": sh, "sign": sg,
                          "overturned": None, "exceeded_critical": None,
                          "max_abs_phi_over_alpha": math.nan, "n_impacts": None,
                          "fractured": None, "status": "error", "wall_s": math.nan}
                         for sh, sg, A, W in cells], columns=list(MAP_COLUMNS))


def _default_method() -> str:
    try:
        from .analytic import compiled  # noqa: F401
        compiled._require_numba()
    except Exception:
        return "solve_ivp"
    return "compiled"


# ------------------------------------------------------------------------------------------
# Agreement of two maps
# ------------------------------------------------------------------------------------------
def boundary(df: pd.DataFrame) -> pd.DataFrame:
    """The minimum-overturning boundary of a map: for each (pulse, sign, frequency), the
    smallest amplitude A that overturns (NaN if none does)."""
    ok = df[df["status"] == "ok"]
    rows = []
    for (p, s, w), g in ok.groupby(["pulse", "sign", "frequency"], sort=True):
        ot = g[g["overturned"].astype(bool)]
        rows.append({"pulse": p, "sign": int(s), "frequency": float(w),
                     "a_min": float(ot["amplitude"].min()) if len(ot) else math.nan})
    return pd.DataFrame(rows, columns=["pulse", "sign", "frequency", "a_min"])


def map_agreement(a: pd.DataFrame, b: pd.DataFrame) -> dict[str, Any]:
    """Agreement of map ``b`` with map ``a`` (normally the analytic one) on the cells both ran
    with status ok: ``n`` cells, ``fraction`` of equal verdicts, Cohen's ``kappa`` (agreement
    beyond chance; 1 perfect, 0 chance; NaN if both maps are uniform), ``b_overturns_a_survives``
    and ``a_overturns_b_survives`` counts, and ``shift``: a frame per (pulse, sign, frequency)
    of the boundary A_min of each and ``shift`` = A_min(b) - A_min(a) [-] (negative: b
    overturns at smaller pulses, earlier)."""
    key = list(_KEY)
    m = a.merge(b, on=key, suffixes=("_a", "_b"))
    m = m[(m["status_a"] == "ok") & (m["status_b"] == "ok")]
    va = m["overturned_a"].astype(bool).to_numpy()
    vb = m["overturned_b"].astype(bool).to_numpy()
    n = len(m)
    agree = float((va == vb).mean()) if n else math.nan
    kappa = math.nan
    if n:
        pa, pb = va.mean(), vb.mean()
        pe = pa * pb + (1 - pa) * (1 - pb)
        kappa = (agree - pe) / (1 - pe) if pe < 1 else math.nan
    ba = boundary(a).merge(boundary(b), on=["pulse", "sign", "frequency"],
                           suffixes=("_a", "_b"))
    ba["shift"] = ba["a_min_b"] - ba["a_min_a"]
    return {"n": n, "fraction": agree, "kappa": float(kappa),
            "b_overturns_a_survives": int((vb & ~va).sum()),
            "a_overturns_b_survives": int((va & ~vb).sum()), "shift": ba}


def describe_shift(shift: pd.DataFrame, name: str = "the engine") -> str:
    """Where a boundary sits relative to the reference, in words (per pulse)."""
    parts = []
    for (p, s), g in shift.groupby(["pulse", "sign"], sort=True):
        g = g.dropna(subset=["shift"])
        if not len(g):
            continue
        early = g[g["shift"] < 0]
        late = g[g["shift"] > 0]
        tag = f"{p} {'+' if s > 0 else '-'}"
        if not len(early) and not len(late):
            parts.append(f"{tag}: same boundary at every frequency")
            continue
        bits = []
        if len(early):
            bits.append(f"earlier (at smaller A, by up to {-early['shift'].min():.3g}) at W = "
                        + ", ".join(f"{w:.3g}" for w in early["frequency"]))
        if len(late):
            bits.append(f"later (by up to {late['shift'].max():.3g}) at W = "
                        + ", ".join(f"{w:.3g}" for w in late["frequency"]))
        parts.append(f"{tag}: {name} overturns " + "; ".join(bits))
    return "; ".join(parts) if parts else "no overturning boundary in both maps"
