"""Property-based fuzzing of every entry point (issue 15): the command line (``run``, ``info``,
``compare``) and the Python API (``rb.run``, ``compare``, the map's ``run_case``, pulses,
record files, scene files, settings).

Strategies draw every parameter kind from valid values, values at and beyond their limits
(:mod:`rockbench.limits`), NaN, infinities, wrong types and malformed files, and know for each
draw whether it is valid (``True``), invalid (``False``) or at a bound where either answer is
right (``None``). A case passes if

* valid input: the command exits 0 / the call returns, with a sane result (finite, and for a
  record the PGA it was given);
* invalid input: the command exits 2 with one line ``rockbench: error: ...`` / the call raises a
  :class:`rockbench.errors.RockbenchError`;

and fails on any traceback (another exception), any hang (each case runs under a hard timeout,
SIGALRM), or a silent result (exit 0 / a return on an invalid input).

Two profiles: the fast one runs in ``make test`` (seconds); the slow one (``-m slow
--run-slow``, CI's slow tests) tries many more inputs. ``pytest -s`` prints how many inputs each
test tried and what they got.
"""

from __future__ import annotations

import contextlib
import io
import math
import re
import signal
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import rockbench as rb
from rockbench.cli.main import main
from rockbench.errors import RockbenchError

#: Seconds a single case may take before it counts as a hang.
CASE_TIMEOUT = 30.0
FAST = settings(max_examples=12, deadline=None, derandomize=True, database=None,
                suppress_health_check=list(HealthCheck))
SLOW = settings(max_examples=150, deadline=None, database=None,
                suppress_health_check=list(HealthCheck))

NAN, INF = math.nan, math.inf
ENGINES = ("pymunk", "mujoco", "pybullet")
TALLY: Counter = Counter()


# ==============================================================================================
# Harness
# ==============================================================================================
class Hang(BaseException):
    """Raised by SIGALRM when a case exceeds CASE_TIMEOUT (a BaseException, so that no
    ``except Exception`` in the code under test swallows it)."""


@contextlib.contextmanager
def hard_timeout(seconds: float = CASE_TIMEOUT):
    def handler(signum, frame):
        raise Hang(f"case still running after {seconds:g} s")

    old = signal.signal(signal.SIGALRM, handler)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, old)


def where_stuck(e: BaseException) -> str:
    """The innermost frames of a Hang: where the case was when the timeout fired."""
    import traceback

    frames = traceback.extract_tb(e.__traceback__)[-4:]
    return "\n" + "".join(traceback.format_list(frames))


def run_cli(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), hard_timeout():
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def check_cli(test: str, argv: list[str], valid: bool | None, *, pga_g: float | None = None
              ) -> None:
    """Run ``argv``; fail on a traceback, a hang, a silent result or a refused valid input."""
    TALLY[test, "tried"] += 1
    try:
        code, out, err = run_cli(argv)
    except Hang as e:
        pytest.fail(f"hang: rockbench {' '.join(map(str, argv))}: {e}{where_stuck(e)}")
    except SystemExit as e:  # argparse must not exit by itself
        pytest.fail(f"SystemExit({e.code}) escaped main: rockbench {' '.join(map(str, argv))}")
    except Exception as e:
        pytest.fail(f"traceback: rockbench {' '.join(map(str, argv))}: "
                    f"{type(e).__name__}: {e}")
    where = f"rockbench {' '.join(map(str, argv))}"
    if code == 2:
        TALLY[test, "refused"] += 1
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("rockbench: error: "), (where, err)
        assert valid is not True, f"valid input refused: {where}: {lines[0]}"
        return
    assert code == 0, (where, code, err)
    TALLY[test, "ran"] += 1
    assert valid is not False, f"silent result (exit 0) on invalid input: {where}\n{out}"
    assert "Traceback" not in err
    sane_output(where, argv, out, pga_g)


def sane_output(where: str, argv: list[str], out: str, pga_g: float | None) -> None:
    cmd = argv[0]
    if cmd == "run":
        m = re.search(r"max \|phi\| / alpha\s+(\S+)", out)
        assert m is not None, (where, out)
        assert math.isfinite(float(m.group(1))), (where, out)
        if pga_g is not None:
            m = re.search(r"\(([-+0-9.eE]+) g\)", out)
            assert m is not None, (where, out)
            assert float(m.group(1)) == pytest.approx(pga_g, rel=6e-3, abs=1e-3), (where, out)
    elif cmd == "info":
        assert "alpha" in out, (where, out)
    elif cmd == "compare":
        assert "analytic" in out, (where, out)


def check_api(test: str, valid: bool | None, call, sane=None) -> None:
    """Call ``call()``; invalid input must raise a RockbenchError, valid input must return a
    value ``sane`` accepts (if given)."""
    TALLY[test, "tried"] += 1
    try:
        with hard_timeout():
            value = call()
    except Hang as e:
        pytest.fail(f"hang: {test}: {e}{where_stuck(e)}")
    except RockbenchError as e:
        TALLY[test, "refused"] += 1
        assert valid is not True, f"valid input refused: {test}: {e}"
        assert "\n" not in str(e).strip(), f"multi-line error: {e}"
        return
    except Exception as e:
        pytest.fail(f"traceback: {test}: {type(e).__name__}: {e}")
    TALLY[test, "ran"] += 1
    assert valid is not False, f"silent result on invalid input: {test}: {value!r}"[:400]
    if sane is not None:
        sane(value)


def sane_result(r) -> None:
    s = r.summary
    assert math.isfinite(s.max_abs_phi_over_alpha)
    assert s.status in ("ok", "diverged", "invalid")


@pytest.fixture(scope="module", autouse=True)
def report_tally():
    yield
    tests = sorted({t for t, _ in TALLY})
    lines = [f"  {t}: {TALLY[t, 'tried']} inputs, {TALLY[t, 'ran']} ran, "
             f"{TALLY[t, 'refused']} refused with one line" for t in tests]
    total = sum(TALLY[t, "tried"] for t in tests)
    print(f"\nfuzz: {total} inputs tried, 0 tracebacks, 0 hangs, 0 silent results\n"
          + "\n".join(lines))


def both(valid: bool | None, other: bool | None) -> bool | None:
    """Validity of two parts together: any False -> False, else any None -> None."""
    if valid is False or other is False:
        return False
    if valid is None or other is None:
        return None
    return True


def all_valid(*flags: bool | None) -> bool | None:
    out: bool | None = True
    for f in flags:
        out = both(out, f)
    return out


# ==============================================================================================
# Parameter strategies: (value, valid)
# ==============================================================================================
def numbers(lo: float, hi: float, *, bad: tuple = (), edge: tuple = ()):
    """Floats in [lo, hi] (valid), ``edge`` values (either answer), and invalid ones: NaN,
    +-inf and ``bad`` (beyond the limits)."""
    valid = st.floats(lo, hi).map(lambda x: (x, True))
    return st.one_of(
        valid, valid, valid, valid,
        st.sampled_from(edge or (lo,)).map(lambda x: (x, None if edge else True)),
        st.sampled_from((NAN, INF, -INF, *bad)).map(lambda x: (x, False)),
    )


def as_text(pair):
    """A number as command-line text; also non-numbers (invalid)."""
    x, valid = pair
    return repr(x) if isinstance(x, float) else str(x), valid


JUNK_TEXT = st.sampled_from(["abc", "", " ", "1,5", "0x10", "--", "1e999", "-1e999", "nan",
                             "None", "[1]", "١"]).map(lambda s: (s, False))
#: Wrong types for a number in the Python API. Numeric strings are converted like float()
#: does (rockbench.errors.check_finite), so either answer is right for them.
WRONG_TYPES = st.one_of(
    st.sampled_from([[1.0], {"x": 1}, True, object(), 1j, "abc"]).map(lambda x: (x, False)),
    st.sampled_from(["3", b"1"]).map(lambda x: (x, None)))


def valid_text(lo, hi):
    """Only valid numbers in [lo, hi], as command-line text."""
    return st.floats(lo, hi).map(lambda x: (repr(x), True))


def cli_number(lo, hi, **kw):
    n = numbers(lo, hi, **kw).map(as_text)
    return st.one_of(n, n, n, n, JUNK_TEXT)


def api_number(lo, hi, **kw):
    n = numbers(lo, hi, **kw)
    return st.one_of(n, n, n, n, WRONG_TYPES)


#: Valid A, W of the fuzz keep valid runs short; the limits are A in (0, 100], W in [0.01, 1e3].
A_VALS = dict(bad=(0.0, -1.0, 101.0, 1e3, 1e300, -INF), edge=(100.0, 1e-9))
W_VALS = dict(bad=(0.0, -3.0, 1e-6, 5e-3, 1001.0, 1e6, 1e300), edge=(1000.0, 0.01))
DURATION_VALS = dict(bad=(0.0, -1.0, 1e9, 1e300), edge=(1e-9, 1e4))
#: Engines: no long edge (1e4 s of stepping is a valid run of many minutes, not a fuzz case).
ENGINE_DURATION_VALS = dict(bad=(0.0, -1.0, 1e9, 1e300), edge=(1e-9,))
SCENES = ["housner-block", "paper-asymmetric", "paper-symmetric-hybrid"]


@st.composite
def phi0_over_alpha(draw, scene_name: str, clean: bool = False):
    """phi0 / alpha for --phi0-alpha: within the fall angle of its own direction (valid), beyond it,
    zero or non-finite (invalid)."""
    scene = rb.load_scene(scene_name)
    sign = draw(st.sampled_from([1, -1]))
    fall = scene.fall_angles[sign] / scene.alpha
    kind = "in" if clean else draw(st.sampled_from(["in", "in", "out", "zero", "nan", "edge"]))
    if kind == "in":
        x = draw(st.floats(0.05, 0.95)) * fall
        # beyond the other direction's fall angle: valid, but the analytic solver still
        # refuses it (test_bad_input.py, the xfail on solver.simulate): either answer for now
        smaller = min(scene.fall_angles.values()) / scene.alpha
        return sign * x, (True if x < smaller else None)
    if kind == "out":
        return sign * draw(st.floats(1.0, 50.0)) * fall, False
    if kind == "edge":
        return sign * fall, False
    return (0.0 if kind == "zero" else NAN), False


# --- files -----------------------------------------------------------------------------------
@st.composite
def record_files(draw, folder: Path, clean: bool = False):
    """(path, options, valid, pga_g) of a record file with its --record-* options."""
    n = draw(st.integers(3, 60))
    kind = draw(st.sampled_from(["samples", "t_a", "at2"])) if clean else \
        draw(st.sampled_from(["samples", "t_a", "t_a", "shuffled", "non_uniform", "wrong_dt",
                                 "nan", "text", "empty", "binary", "one", "at2", "at2_npts",
                                 "at2_dt", "at2_units", "at2_units", "at2_badunits",
                                 "at2_nounits", "missing", "folder"]))
    units = draw(st.sampled_from(["g", "m/s2", "cm/s2"]))
    factor = {"g": 1.0, "m/s2": 1 / 9.80665, "cm/s2": 0.01 / 9.80665}[units]
    dt = draw(st.sampled_from([0.005, 0.01, 0.02]))
    acc = np.round(np.array(draw(st.lists(st.floats(-1.5, 1.5), min_size=n, max_size=n))), 5)
    acc = acc / factor if kind in ("samples", "t_a") else acc
    acc = np.round(acc, 5)
    pga_g = float(np.max(np.abs(acc))) * factor if kind in ("samples", "t_a") else None
    t = np.round(np.arange(n) * dt, 6)
    path = folder / f"rec_{kind}.txt"
    opts = ["--record-dt", repr(float(dt)), "--record-units", units]
    valid: bool | None = False
    if kind == "samples":   # 3 per line: never a time column
        rows = [" ".join(repr(float(v)) for v in acc[i:i + 3]) for i in range(0, n, 3)]
        path.write_text("\n".join(rows) + "\n")
        valid = True
    elif kind == "t_a":
        path.write_text("".join(f"{float(ti)!r} {float(ai)!r}\n" for ti, ai in zip(t, acc)))
        valid = True
    elif kind == "shuffled":
        idx = list(range(n))
        idx[0], idx[1] = 1, 0
        path.write_text("".join(f"{float(t[i])!r} {float(acc[i])!r}\n" for i in idx))
    elif kind == "non_uniform":
        tt = t.copy()
        tt[n // 2:] += 0.37 * dt
        path.write_text("".join(f"{float(ti)!r} {float(ai)!r}\n" for ti, ai in zip(tt, acc)))
    elif kind == "wrong_dt":
        path.write_text("".join(f"{float(2 * ti)!r} {float(ai)!r}\n" for ti, ai in zip(t, acc)))
    elif kind in ("nan", "text"):
        bad = "nan" if kind == "nan" else "x1.2"
        path.write_text(" ".join(map(repr, acc[:-1].tolist())) + f" {bad}\n")
    elif kind == "empty":
        path.write_text(draw(st.sampled_from(["", "\n\n", "# only a comment\n"])))
    elif kind == "binary":
        path.write_bytes(b"\x00\xff\xfe 1 2 3\n")
    elif kind == "one":
        path.write_text("0.1\n")
    elif kind.startswith("at2"):
        path = folder / f"rec_{kind}.AT2"
        npts = n + (7 if kind == "at2_npts" else 0)
        hdr_dt = 5.0 if kind == "at2_dt" else dt
        # issue 22: the header's units, in the spellings agencies use (or unknown, or none)
        spelled, per_g = "UNITS OF G", 1.0
        if kind == "at2_units":
            spelled, per_g = draw(st.sampled_from([
                ("UNITS: CM/S^2", 980.665), ("UNITS OF CM/SEC/SEC", 980.665),
                ("Units: gal", 980.665), ("UNITS = m/s^2", 9.80665), ("units: mm/s2", 9806.65),
                ("ACCELERATION IN CM/S/S", 980.665), ("UNITS OF g", 1.0)]))
        elif kind == "at2_badunits":
            spelled = draw(st.sampled_from(["UNITS: CM/S", "UNITS OF KG", "UNITS: furlong/s^2",
                                            "UNITS = mgal"]))
        elif kind == "at2_nounits":
            spelled = "ACCELERATION TIME SERIES"
        values = acc * per_g
        body = "\n".join(" ".join(f"{v:.5f}" for v in values[i:i + 5])
                         for i in range(0, n, 5))
        path.write_text(f"PEER\nfuzz\n{spelled}\n"
                        f"NPTS= {npts}, DT= {hdr_dt:.4f} SEC\n{body}\n")
        opts = []
        valid = kind in ("at2", "at2_units")
        pga_g = float(np.max(np.abs(np.round(values, 5)))) / per_g if valid else None
    elif kind == "missing":
        path = folder / "nowhere.txt"
    elif kind == "folder":
        path = folder
    return path, opts, valid, pga_g


@st.composite
def scene_files(draw, folder: Path):
    """(path, valid) of a scene TOML file: valid blocks, and every way of being wrong."""
    w = draw(st.floats(0.5, 2.0))
    h = draw(st.floats(3.0, 8.0))
    value = draw(st.sampled_from([repr(w), '"wide"', "true", "[1, 2]", "{a = 1}", "nan", "inf",
                                  "-1.0", "0.0", "1979-05-27"]))
    kind = draw(st.sampled_from(["block", "block", "bad_width", "no_structure", "no_type",
                                 "unknown_key", "unknown_table", "not_toml", "structure_value",
                                 "bad_type", "frame", "wrong_kind", "devices_on_block"]))
    text = {
        "block": f'name = "b"\n[structure]\ntype = "block"\nwidth = {w!r}\nheight = {h!r}\n',
        "bad_width": f'[structure]\ntype = "block"\nwidth = {value}\nheight = {h!r}\n',
        "no_structure": 'name = "b"\ndescription = "no structure"\nfall_angle = 0.5\n',
        "no_type": f'[structure]\nwidth = {w!r}\n',
        "unknown_key": f'[structure]\ntype = "block"\nwidht = {w!r}\n',
        "unknown_table": '[structure]\ntype = "block"\n[material]\ndensity = 2500\n',
        "not_toml": draw(st.sampled_from(["[structure\n", "type = \n", "= 3\n", "\x00\x01",
                                          "[structure]\ntype = block\n"])),
        "structure_value": f"structure = {value}\n",
        "bad_type": f'[structure]\ntype = {value}\n',
        "frame": 'preset = "paper"\n[structure]\ntype = "frame"\ncolumn_height_right = 6.0\n',
        "wrong_kind": 'kind = "case-catalogue"\n[structure]\ntype = "block"\n',
        "devices_on_block": '[structure]\ntype = "block"\n[devices]\ndamping = 1e6\n',
    }[kind]
    valid = kind in ("block", "frame") or (kind == "bad_width" and value == repr(w))
    path = folder / f"scene_{kind}.toml"
    path.write_text(text)
    return path, valid


# ==============================================================================================
# The command line
# ==============================================================================================
@st.composite
def cli_cases(draw, folder: Path):
    """(argv, valid, pga_g) of one ``rockbench run | info | compare`` command. Half the cases
    are drawn ``clean`` (every part from its valid values), so that valid input is tried as
    often as invalid input."""
    clean = draw(st.booleans())

    def pick(valid, anything):
        return draw(valid if clean else anything)

    cmd = draw(st.sampled_from(["run", "run", "run", "run", "info", "compare"]))
    flags: list[bool | None] = []
    if not clean and draw(st.integers(0, 4)) == 0:
        scene_arg, ok = draw(scene_files(folder))
        scene_name = "housner-block"
        if ok:  # a valid scene file: its own fall angles decide phi0
            scene_name = str(scene_arg)
    else:
        scene_arg, ok = pick(st.sampled_from([(s, True) for s in SCENES]),
                             st.sampled_from([(s, True) for s in SCENES]
                                             + [("nosuch", False), ("", False)]))
        scene_name = scene_arg if ok else "housner-block"
    flags.append(ok)
    argv = [cmd, scene_arg]
    if not clean and draw(st.integers(0, 5)) == 0:   # a scene override
        key, ok = draw(st.sampled_from([("width=1.2", None), ("span=9", None), ("nope=1", False),
                                        ("width=nan", False), ("width=-1", False),
                                        ("width", False), ("devices=none", None)]))
        argv += ["--set", key]
        flags.append(ok)
        if key == "devices=none" and flags[0] is False:
            flags[0] = None   # removing the devices may repair a file (devices on a block)
        if (key == "width=1.2" and flags[0] is False
                and str(scene_arg).endswith("scene_bad_width.toml")):
            flags[0] = None   # setting the width repairs a file whose only fault is its width
        if ok is not False:
            scene_name = None  # the override changes the scene: either answer for phi0
    if cmd == "info":
        return argv, all_valid(*flags), None
    engine = "analytic"
    if cmd == "run":
        engine, ok = pick(st.sampled_from([("analytic", True)] * 4 + [(e, True) for e in ENGINES]),
                          st.sampled_from([("analytic", True)] * 4
                                          + [(e, True) for e in ENGINES] + [("bullet", False)]))
        argv += ["--engine", engine]
        flags.append(ok)
    else:
        engines, ok = pick(st.sampled_from([("analytic,pymunk", True), ("analytic", True)]),
                           st.sampled_from([("analytic,pymunk", True), ("analytic", True),
                                            ("nope", False), (",", False)]))
        argv += ["--engines", engines]
        flags.append(ok)
        engine = "pymunk"
    pga_g = None
    motion = pick(st.sampled_from(["pulse", "record", "phi0"]),
                  st.sampled_from(["pulse", "pulse", "record", "phi0", "phi0", "none", "mixed"]))
    if motion == "pulse":
        shape, ok = pick(st.sampled_from([("symmetric", True), ("antisymmetric", True)]),
                         st.sampled_from([("symmetric", True), ("antisymmetric", True),
                                          ("triangle", False)]))
        argv += ["--pulse", shape]
        flags.append(ok)
        if draw(st.booleans()):
            sign, ok = pick(st.sampled_from([("1", True), ("-1", True)]),
                            st.sampled_from([("1", True), ("-1", True), ("0", False),
                                             ("2", False), ("x", False)]))
            argv += ["--sign", sign]
            flags.append(ok)
        for opt, strat, good in (
                ("--amplitude", cli_number(0.5, 10.0, **A_VALS), valid_text(0.5, 10.0)),
                ("--frequency", cli_number(1.0, 20.0, **W_VALS), valid_text(1.0, 20.0))):
            if clean or draw(st.integers(0, 9)):
                text, ok = pick(good, strat)
                argv += [opt, text]
                flags.append(ok)
            else:
                flags.append(False)  # missing
    elif motion == "record":
        path, opts, ok, pga_g = draw(record_files(folder, clean))
        argv += ["--record", path, *opts]
        flags.append(ok)
        if draw(st.integers(0, 4)) == 0:
            text, ok = pick(st.sampled_from([("1", True), ("-2", True)]),
                            st.sampled_from([("1", True), ("-2", True), ("0", False),
                                             ("nan", False), ("x", False)]))
            argv += ["--scale", text]
            flags.append(ok)
            if ok and pga_g is not None:
                pga_g *= abs(float(text))
        if not clean and draw(st.integers(0, 5)) == 0:
            text, ok = draw(st.sampled_from([("5", False), ("1e-5", False), ("-0.01", False)]))
            i = argv.index("--record-dt") if "--record-dt" in argv else None
            if i is not None:
                argv[i + 1] = text
            else:
                argv += ["--record-dt", text]
            flags.append(ok)
    elif motion == "phi0":
        if scene_name is None or not flags[0]:
            x, ok = draw(st.floats(-3.0, 3.0).filter(lambda v: abs(v) > 0.1)), None
        else:
            x, ok = draw(phi0_over_alpha(scene_name, clean))
        argv += ["--phi0-alpha", repr(x)]
        flags.append(ok)
    elif motion == "none":
        flags.append(False)
    else:  # two motions at once, or pulse options without --pulse
        argv += draw(st.sampled_from([["--pulse", "symmetric", "--phi0", "1"],
                                      ["--amplitude", "2", "--phi0", "1"],
                                      ["--record-dt", "0.01", "--phi0", "1"]]))
        flags.append(False)
    # duration: engines always get a short one (a valid engine run stays fast)
    if engine != "analytic" or draw(st.booleans()):
        vals = DURATION_VALS if engine == "analytic" else ENGINE_DURATION_VALS
        text, ok = pick(valid_text(0.2, 1.5), cli_number(0.2, 1.5, **vals))
        argv += ["--duration", text]
        # a pulse run starts 3 T_g before the pulse centre: a duration that ends before it is
        # refused (exit 2, one line), one that reaches it runs; which depends on T_g
        flags.append(None if (ok and motion == "pulse") else ok)
    if not clean and draw(st.integers(0, 3)) == 0:   # settings
        if engine == "analytic":
            name, strat = draw(st.sampled_from([
                ("rtol", cli_number(1e-11, 1e-5, bad=(2.0, 1.0, 0.5, 0.0, -1.0, 1e-20))),
                ("atol", cli_number(1e-14, 1e-8, bad=(0.0, -1.0, 1.0))),
                ("output_dt", cli_number(1e-3, 0.05, bad=(0.0, -1e-3, 10.0, 1e-9))),
                ("method", st.sampled_from([("RK45", True), ("DOP853", True),
                                            ("Euler", False), ("", False)])),
                ("iterations", st.just(("20", False)))]))
        else:
            name, strat = draw(st.sampled_from([
                ("friction", cli_number(0.5, 2.0, bad=(0.0, -1.0))),
                ("output_dt", cli_number(2e-3, 0.02, bad=(0.0, 10.0, 1e-9))),
                ("dt", cli_number(5e-4, 2e-3, bad=(0.0, 0.5, 1e-9))),
                ("bogus", st.just(("1", False)))]))
        text, ok = draw(strat)
        argv += ["--setting", f"{name}={text}"]
        flags.append(ok if cmd == "run" or ok is False else None)
    if cmd == "run" and draw(st.integers(0, 4)) == 0:
        out, ok = pick(st.just((folder / "out" / "h.csv", True)),
                       st.sampled_from([(folder / "out" / "h.csv", True),
                                        (Path("/proc/nope/x.csv"), False),
                                        (folder / "rec_folder_is_a_file.txt" / "x.csv", False)]))
        (folder / "rec_folder_is_a_file.txt").write_text("x")
        argv += ["--out", out]
        flags.append(ok)
    if cmd == "run" and engine != "analytic" and draw(st.integers(0, 4)) == 0:
        text, ok = pick(valid_text(5e-4, 2e-3), cli_number(5e-4, 2e-3, bad=(0.0, 0.5, 1e-9)))
        argv += ["--dt", text]
        flags.append(ok)
        if ok is True and "--setting" in argv and str(argv[argv.index("--setting") + 1]).startswith("dt="):
            flags.append(False)
        if ok is True and any(str(a).startswith("output_dt=") for a in argv):
            flags.append(None)  # output_dt must stay >= dt
    return argv, all_valid(*flags), pga_g


def cli_test(data, tmp_path_factory):
    folder = tmp_path_factory.mktemp("fuzz_cli")
    argv, valid, pga_g = data.draw(cli_cases(folder))
    check_cli("cli", argv, valid, pga_g=pga_g if valid else None)


@FAST
@given(data=st.data())
def test_fuzz_cli(data, tmp_path_factory):
    cli_test(data, tmp_path_factory)


@pytest.mark.slow
@SLOW
@given(data=st.data())
def test_fuzz_cli_slow(data, tmp_path_factory):
    cli_test(data, tmp_path_factory)


# ==============================================================================================
# The Python API
# ==============================================================================================
@st.composite
def api_motions(draw, scene):
    """(motion object or junk, valid)."""
    kind = draw(st.sampled_from(["pulse", "pulse", "none", "junk", "dimensional"]))
    if kind == "none":
        return None, True
    if kind == "junk":
        return draw(st.sampled_from(["pulse", 3.0, {"kind": "ricker"}, [1.0, 2.0], scene])), False
    if kind == "dimensional":
        a, ok_a = draw(api_number(0.5, 10.0, bad=(0.0, -1.0, 1e5)))
        T, ok_t = draw(api_number(0.2, 3.0, bad=(0.0, -1.0, 1e-6, 1e6)))
        ok = both(ok_a, ok_t)
        try:
            return rb.RickerPulse(a, T), ok
        except RockbenchError:
            assert ok is not True
            return None, False   # refused at construction: nothing more to run
    A, ok_a = draw(api_number(0.5, 10.0, **A_VALS))
    W, ok_w = draw(api_number(1.0, 20.0, **W_VALS))
    ok = both(ok_a, ok_w)
    check_api("api.pulse", ok, lambda: rb.RickerPulse.dimensionless(A, W, scene.structure))
    try:
        return rb.RickerPulse.dimensionless(A, W, scene.structure), ok
    except RockbenchError:
        return None, False


def api_run_test(data):
    name = data.draw(st.sampled_from(SCENES))
    scene = rb.load_scene(name)
    motion, ok_m = data.draw(api_motions(scene))
    if ok_m is False and motion is None:
        return   # refused when the motion was built: checked there
    engine, ok_e = data.draw(st.sampled_from([("analytic", True)] * 3 + [("pymunk", True),
                                              ("nope", False), (None, False)]))
    sign = data.draw(st.sampled_from([1, -1]))
    fall = scene.fall_angles[sign]
    if motion is None:
        phi0, ok_p = data.draw(st.one_of(
            st.floats(0.05, 0.95).map(lambda f: (sign * f * fall, True)),
            st.sampled_from([(sign * fall, False), (sign * 2 * fall, False), (0.0, False),
                             (NAN, False), ("0.1", None), (None, False)])))
    else:
        phi0, ok_p = 0.0, True
    if engine != "analytic":
        duration, ok_d = data.draw(st.one_of(st.floats(0.1, 1.0).map(lambda d: (d, True)),
                                             st.sampled_from([(0.0, False), (1e9, False),
                                                              (NAN, False), ("1", None)])))
    else:
        duration, ok_d = data.draw(st.one_of(st.just((None, True)),
                                             api_number(0.2, 3.0, **DURATION_VALS)))
    over, ok_s = data.draw(st.sampled_from([
        ({}, True), ({"rtol": 2.0}, False), ({"rtol": 1e-8}, True), ({"output_dt": 0.0}, False),
        ({"output_dt": 1e9}, False), ({"nope": 1}, False), ({"method": 3}, False),
        ({"atol": NAN}, False), ({"rtol": "1e-8"}, None)]))
    if engine == "pymunk" and over:
        over, ok_s = data.draw(st.sampled_from([({"friction": 0.0}, False), ({"dt": 5e-4}, True),
                                                ({"output_dt": 1e-9}, False),
                                                ({"uplift_tol": 5.0}, False)]))
    valid = all_valid(ok_m, ok_e, ok_p, ok_d, ok_s)
    check_api("api.run", valid,
              lambda: rb.run(scene, motion, engine=engine, duration=duration, phi0=phi0, **over),
              sane_result)


@FAST
@given(data=st.data())
def test_fuzz_api_run(data):
    api_run_test(data)


@pytest.mark.slow
@SLOW
@given(data=st.data())
def test_fuzz_api_run_slow(data):
    api_run_test(data)


def api_files_test(data, tmp_path_factory):
    folder = tmp_path_factory.mktemp("fuzz_api")
    path, opts, valid, pga_g = data.draw(record_files(folder))
    kw = {}
    if opts:
        kw = {"dt": float(opts[1]), "units": opts[3]}
    if data.draw(st.integers(0, 4)) == 0:
        bad, ok = data.draw(st.one_of(WRONG_TYPES, st.sampled_from([(5.0, False), (1e-5, False),
                                                                    (NAN, False)])))
        kw["dt"] = bad
        valid = both(valid, ok) if opts else both(valid, None)

    def pga(record):
        if pga_g is not None:
            assert record.peak / 9.80665 == pytest.approx(pga_g, rel=1e-9, abs=1e-9)

    check_api("api.load_record", valid, lambda: rb.load_record(path, **kw), pga)
    spath, svalid = data.draw(scene_files(folder))
    check_api("api.load_scene", svalid, lambda: rb.load_scene(spath))
    junk = data.draw(st.sampled_from([None, 3, "x", [], {"structure": None},
                                      {"structure": {"type": "block"}, "name": 3},
                                      {"structure": {"type": "block", "width": "1"}},
                                      {"structure": {"type": ["block"]}},
                                      {"version": "1", "structure": {"type": "block"}}]))
    check_api("api.scene_from_dict", False, lambda: rb.Scene.from_dict(junk))


@FAST
@given(data=st.data())
def test_fuzz_api_files(data, tmp_path_factory):
    api_files_test(data, tmp_path_factory)


@pytest.mark.slow
@SLOW
@given(data=st.data())
def test_fuzz_api_files_slow(data, tmp_path_factory):
    api_files_test(data, tmp_path_factory)


def api_compare_and_map_test(data):
    from rockbench.comparison import compare
    from rockbench.sweep.runs import run_case

    scene = rb.load_scene("housner-block")
    engines, ok_e = data.draw(st.sampled_from([(["analytic"], True), ("analytic", True),
                                               (["nope"], False), (3, False), ([None], False),
                                               ([["analytic"]], False)]))
    phi0, ok_p = data.draw(st.sampled_from([(0.1, True), (-0.1, True), (0.0, False),
                                            (5.0, False), (NAN, False)]))
    duration, ok_d = data.draw(api_number(0.2, 1.0, **DURATION_VALS))
    check_api("api.compare", all_valid(ok_e, ok_p, ok_d),
              lambda: compare(scene, None, engines=engines, phi0=phi0, duration=duration))
    # one case of a map: a failing case is a row with status "error", never an exception
    A, ok_a = data.draw(numbers(0.5, 10.0, **A_VALS))
    W, ok_w = data.draw(numbers(1.0, 20.0, **W_VALS))
    case = {"scene": "housner-block", "engine": "analytic", "duration": 1.0,
            "motion": {"kind": "ricker", "shape": "symmetric", "sign": 1, "A": A, "W": W}}
    valid = both(ok_a, ok_w)
    TALLY["api.map_case", "tried"] += 1
    with hard_timeout():
        try:
            row = run_case(case)
        except RockbenchError:
            TALLY["api.map_case", "refused"] += 1
            assert valid is not True
            return
    if row["status"] == "error":
        TALLY["api.map_case", "refused"] += 1
        assert valid is not True, row["reason"]
        assert row["reason"].startswith(("ParameterError", "SceneError", "RecordError")), row
    else:
        TALLY["api.map_case", "ran"] += 1
        assert valid is not False, f"silent result on invalid map case: {case}"


@FAST
@given(data=st.data())
def test_fuzz_api_compare_and_map(data):
    api_compare_and_map_test(data)


@pytest.mark.slow
@SLOW
@given(data=st.data())
def test_fuzz_api_compare_and_map_slow(data):
    api_compare_and_map_test(data)


# ==============================================================================================
# Engine settings at and beyond what each engine can take (issue 22)
# ==============================================================================================
#: (engine, setting, its valid range [lo, hi], integer?): the ranges of the Settings classes
#: (docs/engines/<engine>.md). Values past a C int (2^31) were OverflowErrors and "XML number
#: too large" reported as "diverged"; a tolerance below round-off never converged.
SETTING_RANGES = [
    ("pymunk", "iterations", 1, 10_000, True),
    ("mujoco", "iterations", 1, 10_000, True),
    ("mujoco", "noslip_iterations", 0, 10_000, True),
    ("mujoco", "impedance", 1e-4, 0.9999, False),
    ("mujoco", "tolerance", 0.0, 1e-3, False),
    ("pybullet", "solver_iterations", 1, 10_000, True),
    ("opensees", "iterations", 1, 10_000, True),
    ("opensees", "tolerance", 1e-12, 1e-4, False),
    ("opensees", "springs", 2, 101, True),
]
#: Settings whose None is a documented value (OpenSees' tolerance: its default, which depends
#: on whether the scene gives a friction).
NONE_IS_DEFAULT = {("opensees", "tolerance")}
#: A run that returns must not have "diverged" because the engine refused a value.
ENGINE_REFUSAL = re.compile(r"^(\w*Error|\w*Exception|XML)|too large|does not fit|"
                            r"greater than maximum")


@st.composite
def setting_values(draw):
    engine, key, lo, hi, integer = draw(st.sampled_from(SETTING_RANGES))
    value = draw(st.sampled_from([lo, hi, 2 ** 31 - 1, 2 ** 31, 10 ** 12, -1, 0, 1e300, 1e-300,
                                  NAN, INF, "abc", None, True, 2.5, hi * 1.5 + 1]))
    if value is None and (engine, key) in NONE_IS_DEFAULT:
        return engine, key, value, True          # None: the documented default
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != value:
        return engine, key, value, False
    inside = lo <= value <= hi and (not integer or float(value).is_integer())
    if integer and isinstance(value, float) and inside:
        return engine, key, value, None        # 2.0 for an integer: either answer is right
    return engine, key, value, inside


def api_settings_test(data):
    engine, key, value, valid = data.draw(setting_values())
    from rockbench.engines import get_backend

    ok, why = get_backend(engine).available()
    if not ok:
        pytest.skip(why)
    scene = rb.load_scene("housner-block")

    def sane(result):
        reason = result.summary.reason or ""
        assert not (result.status == "diverged" and ENGINE_REFUSAL.search(reason)), (
            f"{engine} {key}={value!r}: the engine refused a value the settings accepted: "
            f"{reason}")

    check_api("api.settings", valid,
              lambda: rb.run(scene, None, engine=engine, phi0=0.3 * scene.alpha,
                             duration=0.02, **{key: value}), sane)


@FAST
@given(data=st.data())
def test_fuzz_engine_settings(data):
    api_settings_test(data)


@pytest.mark.slow
@SLOW
@given(data=st.data())
def test_fuzz_engine_settings_slow(data):
    api_settings_test(data)
