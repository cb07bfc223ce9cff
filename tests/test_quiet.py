"""Quiet and talkative at the right times (issue 22 §4): stderr carries rockbench's words only
(no engine banners, no engine imported that is not used), and long work shows progress (a
line every few seconds off a terminal, nothing with --quiet)."""

from __future__ import annotations

import io
import json
import subprocess
import sys
import textwrap

import pytest

import rockbench as rb
from rockbench.testing import needs_engine
from rockbench import progress
from rockbench.cli.main import main

ENGINE_MODULES = ("pybullet", "mujoco", "pymunk", "openseespy", "pydrake")


def _python(code: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=cwd,
                          capture_output=True, text=True, timeout=300, check=False)


def _cli(argv: list[str], cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "rockbench", *argv], cwd=cwd,
                          capture_output=True, text=True, timeout=300, check=False)


# --- no banner, no engine that is not used ------------------------------------------------------
def test_analytic_map_imports_no_engine_and_prints_nothing_on_stderr(tmp_path):
    """Before: an analytic map imported every engine (the store's fingerprint and the map's
    inputs asked every engine its version) and printed PyBullet's banner."""
    proc = _python(f"""
        import sys, json
        from rockbench.cli.main import main
        code = main(["map", "paper-symmetric", "--grid", "1x1", "--pulses", "symmetric+",
                     "--store", {str(tmp_path / "m")!r}, "--json"])
        print(json.dumps({{"code": code, "engines": [m for m in {ENGINE_MODULES!r}
                                                    if m in sys.modules]}}))
    """, tmp_path)
    assert proc.stderr == "", proc.stderr
    last = json.loads(proc.stdout.strip().splitlines()[-1])
    assert last == {"code": 0, "engines": []}


@pytest.mark.parametrize("engine", [n for n in rb.backend_names() if n != "analytic"])
def test_engine_runs_leave_stderr_empty(tmp_path, engine):
    """PyBullet prints its build time to fd 2 on import, OpenSeesPy 'Process 0 Terminating'
    from a Py_AtExit hook: both dropped (engines/_quiet.py); every engine checked in a fresh
    process."""
    if engine not in rb.available_backends():
        pytest.skip(f"{engine} is not installed")
    proc = _cli(["run", "housner-block", "--engine", engine, "--phi0-alpha", "0.3",
                 "--duration", "0.3", "--json"], tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == "", proc.stderr
    assert json.loads(proc.stdout)["status"] == "ok"


def test_engines_command_prints_only_its_table(tmp_path):
    proc = _cli(["engines"], tmp_path)
    assert proc.returncode == 0
    assert proc.stderr == "", proc.stderr


def test_silenced_drops_c_level_writes_and_restores_them(tmp_path):
    proc = _python("""
        import os
        from rockbench.engines._quiet import silenced
        os.write(2, b"before\\n")
        with silenced():
            os.write(2, b"inside-2\\n")
            os.write(1, b"inside-1\\n")
            print("python-inside")
        os.write(2, b"after\\n")
        print("python-after")
    """, tmp_path)
    assert proc.stderr == "before\nafter\n"
    assert proc.stdout == "python-after\n"


def test_exit_hook_keeps_pythons_own_stderr(tmp_path):
    """At exit the C library's descriptor 2 goes to /dev/null, but Python's sys.stderr (an
    atexit handler that runs later, a message) still reaches the real stderr."""
    proc = _python("""
        import atexit, os, sys
        atexit.register(lambda: print("python at exit", file=sys.stderr))  # runs after ours
        from rockbench.engines._quiet import quiet_import
        quiet_import("json", at_exit=True)
        import ctypes
        libc = ctypes.CDLL(None)
        atexit.register(lambda: None)
        print("done")
    """, tmp_path)
    assert proc.stdout == "done\n"
    assert proc.stderr == "python at exit\n"


# --- start-up --------------------------------------------------------------------------------
def test_import_rockbench_is_light(tmp_path):
    """``import rockbench`` and the parser load neither pandas, scipy, numba nor an engine;
    the public names still resolve on use."""
    proc = _python(f"""
        import sys
        import rockbench, rockbench.cli.main
        rockbench.cli.main.build_parser()
        heavy = [m for m in ("pandas", "scipy", "numba", *{ENGINE_MODULES!r}) if m in sys.modules]
        print(heavy)
        print(rockbench.load_scene("housner-block").name, callable(rockbench.run))
    """, tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines() == ["[]", "housner-block True"]
    assert set(rb.__all__) <= set(dir(rb))
    with pytest.raises(AttributeError):
        rb.no_such_name  # noqa: B018


def test_jit_cache_is_keyed_by_version_and_kernel_sources():
    from rockbench import _jit

    files = _jit.kernel_files()
    assert "analytic/kernels.py" in files and "engines/compiled_loop.py" in files
    assert not any(f.startswith("cli/") for f in files)
    assert _jit.cache_dir().name.startswith(f"{rb.__version__}-")


@pytest.mark.slow
def test_jit_cache_survives_a_fresh_copy_of_the_sources(tmp_path):
    """A kernel compiled by one checkout is loaded, not compiled again, by another checkout of
    the same sources (numba's in-tree cache would be empty there: issue 27 §5)."""
    import shutil
    from pathlib import Path

    src = Path(rb.__file__).resolve().parent
    for name in ("a", "b"):
        shutil.copytree(src, tmp_path / name / "rockbench",
                        ignore=shutil.ignore_patterns("__pycache__"))
    script = textwrap.dedent("""
        import sys
        sys.path.insert(0, sys.argv[1])
        import numpy as np
        import rockbench
        assert rockbench.__file__.startswith(sys.argv[1]), rockbench.__file__
        from rockbench.engines.device_kernel import _device_wrench as k
        st, p, W = np.zeros((3, 6)), np.zeros(64), np.zeros((3, 3))
        k(st, p, W)
        print(k._cache.cache_path)
        print(sum(k.stats.cache_hits.values()), sum(k.stats.cache_misses.values()))
    """)
    outs = []
    for name in ("a", "b"):
        proc = subprocess.run([sys.executable, "-c", script, str(tmp_path / name)],
                              env={**_env(), "ROCKBENCH_CACHE_DIR": str(tmp_path / "cache")},
                              capture_output=True, text=True, timeout=300, check=False)
        assert proc.returncode == 0, proc.stderr
        outs.append(proc.stdout.splitlines())
    assert outs[0][0] == outs[1][0]               # one folder for both checkouts
    assert outs[0][0].startswith(str(tmp_path / "cache"))
    assert outs[0][1] == "0 1"                    # the first checkout compiles
    assert outs[1][1] == "1 0"                    # the second loads it


def _env() -> dict:
    import os

    return {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}


# --- progress --------------------------------------------------------------------------------
def test_lines_off_a_terminal():
    out = io.StringIO()
    bar = progress._Lines(10, "map", "cell", stream=out, interval=0.0)
    for _ in range(10):
        bar.update(1)
    bar.close()
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("rockbench: map: 1/10 cell (10 %)")
    assert lines[-1].startswith("rockbench: map: 10/10 cell (100 %)")
    quiet = io.StringIO()
    bar = progress._Lines(10, "map", "cell", stream=quiet, interval=3600.0)
    bar.update(5)
    bar.close()
    assert quiet.getvalue() == ""                 # short work prints nothing


def test_quiet_makes_every_bar_silent():
    try:
        progress.configure(quiet=True)
        assert isinstance(progress.bar(5, "x"), progress._Null)
        with progress.simulated_time("x"):
            assert progress._sim is None
    finally:
        progress.configure(quiet=False)


@needs_engine("pymunk")
@pytest.mark.parametrize("quiet", [False, True])
def test_run_reports_simulated_time_from_the_stepping_loop(capsys, monkeypatch, quiet):
    """``run`` of an engine shows the simulated time (the hook in engines/loop.py, reached
    every PROBE_CHUNK samples by the Python and the compiled loop); --quiet shows nothing."""
    monkeypatch.setattr(progress, "INTERVAL", 0.0)
    argv = ["run", "housner-block", "--engine", "pymunk", "--phi0-alpha", "0.3",
            "--duration", "2", "--json"]
    try:
        assert main(argv + (["--quiet"] if quiet else [])) == 0
    finally:
        progress.configure(quiet=False)
    out, err = capsys.readouterr()
    json.loads(out)                               # stdout stays pure JSON
    lines = [ln for ln in err.splitlines() if ln]
    if quiet:
        assert lines == []
    else:
        assert lines and all(ln.startswith("rockbench: housner-block: pymunk:") for ln in lines)
        assert "s simulated" in lines[-1] and "(100 %)" in lines[-1]
        # 2 s at 1 ms samples: reports every 500 samples (0.5 s), the last at the end
        assert len(lines) >= 4
