"""The command line: commands, JSON keys, physics through the CLI, and one-line errors."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

import rockbench as rb
from rockbench.testing import needs_engine
from rockbench.cli.main import main
from rockbench.result import HISTORY_COLUMNS

RECORDS = Path(__file__).resolve().parents[2] / "shared" / "records"
EL_CENTRO = RECORDS / "IV1940_ElCentro_180.AT2"
needs_pymunk = needs_engine("pymunk")

INFO_KEYS = {"alpha", "p", "eta_ccw", "eta_cw", "lambda_ccw", "lambda_cw", "phi_cr_ccw",
             "phi_cr_cw"}
RUN_KEYS = {"max_abs_phi_over_alpha", "overturned", "exceeded_critical", "uplifted", "n_impacts",
            "fractured", "status", "wall_s", "real_time_factor", "eta_measured"}


def cli_json(capsys, *argv):
    """Run ``rockbench argv --json`` in-process; return the parsed JSON."""
    rc = main([*argv, "--json"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    return json.loads(out)


# --- scenes, info, engines ---------------------------------------------------------------------
def test_scenes_lists_every_builtin_scene(capsys):
    assert main(["scenes"]) == 0
    text = capsys.readouterr().out
    for name in rb.builtin_scenes():
        assert name in text
    rows = cli_json(capsys, "scenes")
    kinds = {r["name"]: r["type"] for r in rows}
    assert set(kinds) == set(rb.builtin_scenes())
    assert kinds["housner-block"] == "block"
    assert kinds["paper-asymmetric"] == "frame"
    assert all(r["description"] for r in rows)


def test_info_symmetric_frame_matches_closed_forms(capsys):
    d = cli_json(capsys, "info", "paper-symmetric")
    assert INFO_KEYS <= set(d)
    # Eq. 28 for the paper's symmetric frame
    assert d["eta_ccw"] == pytest.approx(0.960625, abs=1e-9)
    assert d["eta_cw"] == pytest.approx(d["eta_ccw"], abs=1e-12)
    # symmetric frame uplifts at a_g = g tan(alpha), signed by direction
    assert d["lambda_ccw"] == pytest.approx(math.tan(d["alpha"]), rel=1e-12)
    assert d["lambda_cw"] == pytest.approx(-d["lambda_ccw"], rel=1e-12)
    # free-standing: the critical angle is alpha itself
    assert d["phi_cr_ccw"] == pytest.approx(d["alpha"], rel=1e-9)
    assert d["phi_cr_cw"] == pytest.approx(-d["alpha"], rel=1e-9)
    assert d["alpha"] == pytest.approx(math.atan(0.5 / 3.5), rel=1e-12)


def test_info_set_override_changes_the_block(capsys):
    d = cli_json(capsys, "info", "housner-block", "--set", "width=2")
    alpha = math.atan(1.0 / 2.5)
    assert d["alpha"] == pytest.approx(alpha, rel=1e-12)
    assert d["eta_ccw"] == pytest.approx(1 - 1.5 * math.sin(alpha) ** 2, rel=1e-9)
    assert d["p"] == pytest.approx(math.sqrt(3 * 9.81 / (4 * math.hypot(1.0, 2.5))), rel=1e-12)


def test_info_human_table_has_units(capsys):
    assert main(["info", "paper-asymmetric"]) == 0
    lines = capsys.readouterr().out.splitlines()
    row = {ln.split()[0]: ln.split() for ln in lines if ln.strip()}
    assert row["alpha"][2] == "rad"
    assert row["p"][2] == "rad/s"
    assert row["mass_beam"][2] == "kg"
    consts = rb.info(rb.load_scene("paper-asymmetric"))
    assert float(row["eta_cw"][1]) == pytest.approx(consts["eta_cw"], rel=1e-5)


def test_engines_json(capsys):
    rows = cli_json(capsys, "engines")
    by_name = {r["name"]: r for r in rows}
    assert list(by_name) == rb.backend_names()
    assert by_name["analytic"]["available"] is True
    for r in rows:
        assert ("version" in r) if r["available"] else ("reason" in r and "remedy" in r)


@needs_engine("pymunk")
def test_engines_json_names_the_installed_version(capsys):
    import pymunk

    by_name = {r["name"]: r for r in cli_json(capsys, "engines")}
    assert by_name["pymunk"]["available"] is True
    assert pymunk.version in by_name["pymunk"]["version"]


# --- run -------------------------------------------------------------------------------------
def test_run_pulse_json_keys_and_values(capsys):
    argv = ["run", "paper-asymmetric", "--engine", "analytic", "--pulse", "symmetric",
            "--sign", "1", "--amplitude", "3", "--frequency", "4"]
    d = cli_json(capsys, *argv)
    assert RUN_KEYS <= set(d)
    assert d["status"] == "ok" and d["uplifted"] is True and d["n_impacts"] > 0
    assert d["real_time_factor"] > 0
    # the CLI's dimensionless pulse is the library's
    scene = rb.load_scene("paper-asymmetric")
    pulse = rb.RickerPulse.dimensionless(3.0, 4.0, scene.structure, "symmetric", 1)
    ref = rb.run(scene, pulse)
    assert d["max_abs_phi_over_alpha"] == pytest.approx(ref.summary.max_abs_phi_over_alpha,
                                                        rel=1e-9)
    assert d["motion"]["amplitude_m_s2"] == pytest.approx(3 * 9.81 * math.tan(scene.alpha))


def test_run_pulse_sign_mirror_on_symmetric_frame(capsys):
    base = ["run", "paper-symmetric", "--pulse", "antisymmetric", "--amplitude", "2.5",
            "--frequency", "3", "--duration", "8"]
    plus = cli_json(capsys, *base, "--sign", "1")
    minus = cli_json(capsys, *base, "--sign", "-1")
    assert plus["max_abs_phi_over_alpha"] > 0.05
    assert minus["max_abs_phi_over_alpha"] == pytest.approx(plus["max_abs_phi_over_alpha"],
                                                            rel=1e-6)
    assert minus["n_impacts"] == plus["n_impacts"]
    assert (plus["motion"]["sign"], minus["motion"]["sign"]) == (1, -1)


def test_run_pulse_below_uplift_threshold_does_not_rock(capsys):
    # symmetric frame: lambda = tan(alpha), so A < 1 never uplifts
    d = cli_json(capsys, "run", "paper-symmetric", "--pulse", "symmetric", "--amplitude", "0.95",
                 "--frequency", "2")
    assert d["uplifted"] is False and d["n_impacts"] == 0
    assert d["max_abs_phi_over_alpha"] == 0.0


@pytest.mark.skipif(not EL_CENTRO.is_file(), reason="shared records not available")
def test_run_record(capsys):
    d = cli_json(capsys, "run", "paper-asymmetric", "--record", str(EL_CENTRO),
                 "--duration", "5")
    assert d["status"] == "ok"
    assert d["motion"]["kind"] == "record" and d["motion"]["npts"] == 4000
    assert d["motion"]["dt_s"] == pytest.approx(0.01)
    assert d["sim_time"] == pytest.approx(5.0, abs=1e-9)
    # PGA 0.313 g > lambda: the frame uplifts within the first 5 s
    assert d["uplifted"] is True
    scaled = cli_json(capsys, "run", "paper-asymmetric", "--record", str(EL_CENTRO),
                      "--duration", "5", "--scale", "0.25")
    assert scaled["motion"]["pga_m_s2"] == pytest.approx(0.25 * d["motion"]["pga_m_s2"])
    assert scaled["uplifted"] is False   # 0.078 g < lambda g


def test_run_record_fixtures(capsys):
    """The record fixtures shipped with the tests (never skipped on a fresh clone)."""
    data = Path(__file__).resolve().parent / "data" / "records"
    d = cli_json(capsys, "run", "paper-asymmetric", "--record",
                 str(data / "IV1940_ElCentro_180_5s.AT2"), "--duration", "5")
    assert d["status"] == "ok" and d["motion"]["npts"] == 500
    assert d["motion"]["pga_m_s2"] == pytest.approx(0.31288 * 9.80665, abs=1e-4)
    assert d["uplifted"] is True          # PGA 0.313 g > lambda g, as with the whole record
    h = cli_json(capsys, "run", "paper-asymmetric", "--record", str(data / "LA21_6s.dat"),
                 "--record-dt", "0.02", "--record-units", "cm/s2")
    assert h["motion"]["npts"] == 300 and h["motion"]["dt_s"] == 0.02
    assert h["motion"]["pga_m_s2"] == pytest.approx(0.74112, abs=1e-9)
    assert h["uplifted"] is False         # 0.076 g < lambda g


def test_run_csv_writes_history_and_events(tmp_path, capsys):
    out = tmp_path / "sub" / "history.csv"
    d = cli_json(capsys, "run", "paper-symmetric", "--phi0-alpha", "0.5", "--duration", "4",
                 "--csv", str(out))
    hist = pd.read_csv(out)
    assert list(hist.columns)[: len(HISTORY_COLUMNS)] == list(HISTORY_COLUMNS)
    assert len(hist) == round(4.0 / d["settings"]["output_dt"]) + 1   # fixed output grid
    alpha = rb.info(rb.load_scene("paper-symmetric"))["alpha"]
    assert hist["phi"].iloc[0] == pytest.approx(0.5 * alpha, rel=1e-12)
    assert hist["phi"].abs().max() / alpha == pytest.approx(d["max_abs_phi_over_alpha"],
                                                            rel=1e-6)
    events = pd.read_csv(tmp_path / "sub" / "history_events.csv")
    assert (events["kind"] == "impact").sum() == d["n_impacts"] > 0
    assert d["history_csv"] == str(out)


def test_run_out_is_a_folder(tmp_path, capsys):
    out = tmp_path / "run1"
    d = cli_json(capsys, "run", "housner-block", "--phi0-alpha", "0.5", "--duration", "2",
                 "--out", str(out))
    hist, events = pd.read_csv(out / "history.csv"), pd.read_csv(out / "events.csv")
    assert len(hist) == round(2.0 / d["settings"]["output_dt"]) + 1
    assert (events["kind"] == "impact").sum() == d["n_impacts"] > 0
    assert d["history_csv"] == str(out / "history.csv")
    (tmp_path / "a_file").write_text("x")
    assert main(["run", "housner-block", "--phi0-alpha", "0.5", "--out",
                 str(tmp_path / "a_file")]) == 2
    assert "--out" in capsys.readouterr().err


def test_phi0_is_radians_as_in_python(capsys):
    """--phi0 is in radians, as rb.run(phi0=...); --phi0-alpha in multiples of alpha."""
    scene = rb.load_scene("housner-block")
    rad = cli_json(capsys, "run", "housner-block", "--phi0", "0.05", "--duration", "2")
    ref = rb.run(scene, None, phi0=0.05, duration=2)
    assert rad["phi0"] == 0.05
    assert rad["max_abs_phi_over_alpha"] == pytest.approx(ref.summary.max_abs_phi_over_alpha,
                                                          rel=1e-12)
    alpha = cli_json(capsys, "run", "housner-block", "--phi0-alpha", str(0.05 / scene.alpha),
                     "--duration", "2")
    assert alpha["phi0"] == pytest.approx(0.05, rel=1e-12)
    assert alpha["max_abs_phi_over_alpha"] == pytest.approx(rad["max_abs_phi_over_alpha"],
                                                            rel=1e-9)
    # beyond the fall angle: refused in the unit it was given
    assert main(["run", "housner-block", "--phi0", "2"]) == 2
    assert "rad" in capsys.readouterr().err
    assert main(["run", "housner-block", "--phi0", "0.1", "--phi0-alpha", "0.5"]) == 2
    assert "--phi0" in capsys.readouterr().err


def test_run_human_summary_has_units(capsys):
    assert main(["run", "housner-block", "--phi0-alpha", "-0.3", "--duration", "2"]) == 0
    text = capsys.readouterr().out
    assert "free rocking from phi0 = -0.3 alpha" in text
    assert "rad" in text and "s wall" in text and "real-time factor" in text


@needs_pymunk
def test_run_pymunk_free_rocking(capsys):
    d = cli_json(capsys, "run", "paper-symmetric", "--engine", "pymunk", "--phi0-alpha", "0.5",
                 "--duration", "1")
    assert RUN_KEYS <= set(d)
    assert isinstance(d["eta_measured"], list)
    assert d["real_time_factor"] > 0
    assert d["max_abs_phi_over_alpha"] == pytest.approx(0.5, rel=1e-3)
    assert d["steps"] == round(1.0 / d["settings"]["dt"])


@needs_pymunk
def test_run_pymunk_eta_and_settings(capsys):
    d = cli_json(capsys, "run", "housner-block", "--engine", "pymunk", "--phi0-alpha", "0.5",
                 "--duration", "3", "--dt", "5e-4", "--setting", "iterations=20")
    assert d["settings"]["dt"] == 5e-4 and d["settings"]["iterations"] == 20
    assert d["steps"] == 6000
    alpha = math.atan(0.5 / 2.5)
    housner = 1 - 1.5 * math.sin(alpha) ** 2
    assert len(d["eta_measured"]) >= 2
    for eta in d["eta_measured"]:
        assert eta == pytest.approx(housner, rel=5e-3)


@needs_pymunk
def test_run_coarse_dt_raises_output_interval(capsys):
    d = cli_json(capsys, "run", "housner-block", "--engine", "pymunk", "--phi0-alpha", "0.5",
                 "--duration", "1", "--dt", "2e-3")
    assert d["settings"]["output_dt"] == 2e-3 and d["steps"] == 500


# --- bad input: one line, exit 2 ---------------------------------------------------------------
BAD = [
    (["info", "no-such-scene"], "no-such-scene"),
    (["info", "paper-symmetric", "--set", "no_such_key=1"], "no_such_key"),
    (["info", "paper-symmetric", "--set", "span=abc"], "span"),
    (["info", "paper-symmetric", "--set", "span=nan"], "span"),
    (["info", "paper-symmetric", "--set", "column_height_right=9"], "column_height_right"),
    (["info", "paper-symmetric", "--set", "span"], "--set"),
    (["run", "paper-symmetric", "--engine", "no-such-engine", "--phi0-alpha", "0.5"], "engine"),
    (["run", "paper-symmetric", "--pulse", "symmetric", "--frequency", "2"], "--amplitude"),
    (["run", "paper-symmetric", "--pulse", "symmetric", "--amplitude", "2"], "--frequency"),
    (["run", "paper-symmetric", "--pulse", "symmetric", "--amplitude", "nan", "--frequency",
      "2"], "--amplitude"),
    (["run", "paper-symmetric", "--pulse", "symmetric", "--amplitude", "-1", "--frequency",
      "2"], "--amplitude"),
    (["run", "paper-symmetric", "--pulse", "sym", "--amplitude", "1", "--frequency", "2"],
     "--pulse"),
    (["run", "paper-symmetric", "--pulse", "symmetric", "--amplitude", "2", "--frequency", "2",
      "--sign", "2"], "--sign"),
    (["run", "paper-symmetric", "--phi0-alpha", "0.5", "--duration", "-5"], "--duration"),
    (["run", "paper-symmetric", "--phi0-alpha", "0.5", "--duration", "inf"], "--duration"),
    (["run", "paper-symmetric", "--phi0-alpha", "0"], "--phi0-alpha"),
    (["run", "paper-symmetric", "--phi0-alpha", "50"], "--phi0-alpha"),
    (["run", "paper-symmetric", "--phi0", "0"], "--phi0"),
    (["run", "paper-symmetric", "--phi0", "1.6"], "--phi0"),
    (["run", "paper-symmetric", "--phi0", "0.01", "--engine", "pymunk", "--engine", "mujoco"],
     "--engine"),
    (["run", "paper-symmetric", "--phi0", "0.01", "--engine", "pymunk", "--setting",
      "mujoco.impratio=2"], "mujoco.impratio"),
    (["run", "paper-symmetric", "--phi0", "0.01", "--setting", "nosuch.rtol=1"], "ENGINE.KEY"),
    (["run", "paper-symmetric", "--phi0", "0.01", "--setting", "rtol"], "ENGINE.KEY=VALUE"),
    (["run", "paper-symmetric", "--phi0-alpha", "0.5", "--pulse", "symmetric"], "--pulse"),
    (["run", "paper-symmetric", "--phi0-alpha", "0.5", "--amplitude", "2"], "--amplitude"),
    (["run", "paper-symmetric", "--phi0-alpha", "0.5", "--scale", "2"], "--scale"),
    (["run", "paper-symmetric"], "--phi0"),
    (["run", "paper-symmetric", "--record", "no/such/file.AT2"], "no/such/file.AT2"),
    (["run", "paper-symmetric", "--phi0-alpha", "0.5", "--dt", "1e-3"], "--dt"),
    (["run", "paper-symmetric", "--phi0-alpha", "0.5", "--setting", "no_such_setting=1"],
     "no_such_setting"),
    (["run", "paper-symmetric", "--phi0-alpha", "0.5", "--setting", "rtol=-1"], "rtol"),
    (["run", "paper-symmetric", "--phi0-alpha", "0.5", "--setting", "method=Euler"], "method"),
    (["no-such-command"], "no-such-command"),
    ([], "COMMAND"),
]


@pytest.mark.parametrize("argv,name", BAD, ids=[" ".join(a) or "<none>" for a, _ in BAD])
def test_bad_input_one_line_exit_2(capsys, argv, name):
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("rockbench: error: ")
    assert name in lines[0]


@pytest.mark.parametrize("extra,name", [([], "--record-dt"),
                                        (["--record-dt", "0.02"], "--record-units"),
                                        (["--record-dt", "0.02", "--record-units", "furlong/s2"],
                                         "record-units")])
def test_headerless_record_needs_dt_and_units(tmp_path, capsys, extra, name):
    """A headerless file that no records.csv lists needs --record-dt and --record-units."""
    data = Path(__file__).resolve().parent / "data" / "records" / "LA21_6s.dat"
    alone = tmp_path / "LA21_6s.dat"
    alone.write_bytes(data.read_bytes())
    assert main(["run", "paper-symmetric", "--record", str(alone), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and name in err[0]


def test_headerless_record_reads_the_records_csv_beside_it(tmp_path, capsys):
    """``run --record FILE`` takes dt and units from the records.csv beside FILE, as
    rb.load_record does (issue 23: the CLI refused what Python read)."""
    data = Path(__file__).resolve().parent / "data" / "records" / "LA21_6s.dat"
    (tmp_path / "LA21_6s.dat").write_bytes(data.read_bytes())
    (tmp_path / "records.csv").write_text("record,dt_s,units\nLA21_6s,0.02,cm/s^2\n")
    d = cli_json(capsys, "run", "paper-asymmetric", "--record", str(tmp_path / "LA21_6s.dat"),
                 "--duration", "2")
    rec = rb.load_record(tmp_path / "LA21_6s.dat")
    assert d["motion"]["dt_s"] == rec.dt == 0.02
    assert d["motion"]["pga_m_s2"] == pytest.approx(0.74112, abs=1e-9)   # cm/s^2 read as such
    # given options still win over the listing (and must agree with nothing else)
    g = cli_json(capsys, "run", "paper-asymmetric", "--record", str(tmp_path / "LA21_6s.dat"),
                 "--record-units", "m/s2", "--duration", "2")
    assert g["motion"]["pga_m_s2"] == pytest.approx(74.112, abs=1e-7)


@needs_pymunk
def test_pymunk_bad_settings(capsys):
    for argv, name in ((["--dt", "0.5"], "dt"), (["--setting", "iterations=abc"], "iterations"),
                       (["--setting", "friction=nan"], "friction")):
        assert main(["run", "housner-block", "--engine", "pymunk", "--phi0-alpha", "0.5", *argv]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and name in err[0] and err[0].startswith("rockbench: error: ")


def test_unexpected_errors_keep_their_traceback(monkeypatch):
    import rockbench.runner

    def broken(*args, **kwargs):
        raise RuntimeError("a bug")

    monkeypatch.setattr(rockbench.runner, "run", broken)
    with pytest.raises(RuntimeError, match="a bug"):
        main(["run", "housner-block", "--phi0-alpha", "0.5"])


def test_help_exits_0(capsys):
    assert main(["run", "--help"]) == 0
    assert "--amplitude" in capsys.readouterr().out


# --- compare and report (modules of their own: an import error fails, never skips) ----------
@needs_pymunk
def test_compare_table(tmp_path, capsys):
    csv = tmp_path / "table.csv"
    d = cli_json(capsys, "compare", "housner-block", "--engines", "pymunk", "--phi0-alpha", "0.5",
                 "--duration", "2", "--csv", str(csv))
    rows = {r["backend"]: r for r in d["table"]}
    assert list(rows) == ["analytic", "pymunk"]
    assert rows["analytic"]["nrmse"] == 0.0
    assert rows["pymunk"]["status"] == "ok"
    assert rows["pymunk"]["nrmse"] < 0.005
    assert pd.read_csv(csv)["backend"].tolist() == ["analytic", "pymunk"]
    assert main(["compare", "housner-block", "--engines", "pymunk", "--phi0-alpha", "0.5",
                 "--duration", "2"]) == 0
    text = capsys.readouterr().out
    assert "pymunk" in text and "nrmse" in text and "units:" in text


@needs_pymunk
def test_compare_settings_reach_the_backend(capsys, monkeypatch):
    import rockbench.comparison as compare_mod

    seen = {}
    real = compare_mod.compare

    def spy(*args, **kwargs):
        seen.update(kwargs)
        return real(*args, **kwargs)

    monkeypatch.setattr(compare_mod, "compare", spy)
    cli_json(capsys, "compare", "housner-block", "--engines", "pymunk", "--phi0-alpha", "0.5",
             "--duration", "0.5", "--dt", "5e-4", "--setting", "pymunk.iterations=20",
             "--setting", "analytic.rtol=1e-9")
    assert seen["settings"] == {"analytic": {"rtol": 1e-9},
                                "pymunk": {"iterations": 20, "dt": 5e-4}}
    assert seen["engines"] == ["pymunk"]
    assert main(["compare", "housner-block", "--engines", "pymunk", "--phi0-alpha", "0.5",
                 "--setting", "no_such=1"]) == 2
    assert "no_such" in capsys.readouterr().err


@needs_pymunk
def test_compare_report(tmp_path, capsys):
    assert main(["compare", "housner-block", "--engines", "pymunk", "--phi0-alpha", "0.5",
                 "--duration", "1", "--report", str(tmp_path / "case")]) == 0
    out = capsys.readouterr().out
    path = Path(out.strip().splitlines()[-1].removeprefix("report: "))
    assert path.exists()
    page = path.read_text(encoding="utf-8")
    # the analytic constants come with the comparison (the report does not call the runner)
    consts = rb.info(rb.load_scene("housner-block"))
    assert "Analytic constants" in page and f"{consts['eta_ccw']:.4g}" in page


def test_report_passes_options_to_run_campaign(tmp_path, capsys, monkeypatch):
    import rockbench.campaign.run as campaign

    seen = {}

    def fake(out_dir="reports", **kwargs):
        seen.update(kwargs, out_dir=out_dir)
        return Path(out_dir) / "index.html"

    monkeypatch.setattr(campaign, "run_campaign", fake)
    assert main(["report", "--out", str(tmp_path), "--quick", "--engines", "pymunk",
                 "--dask", "tcp://127.0.0.1:8786", "--store", str(tmp_path / "s.parquet"),
                 "--records", str(tmp_path), "--workers", "3"]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert out[-1] == f"report: {tmp_path / 'index.html'}"
    # the constants table of the campaign's scenes is printed first and saved beside the page
    assert out[0].startswith("Analytic constants") and "paper-asymmetric-hybrid-eps1" in "".join(out)
    constants = pd.read_csv(tmp_path / "constants.csv")
    sym = constants.set_index("scene").loc["paper-symmetric"]
    assert sym["eta_ccw"] == pytest.approx(0.960625) and sym["lambda_ccw"] == pytest.approx(1 / 7)
    assert seen["out_dir"] == str(tmp_path) and seen["quick"] is True
    assert seen["engines"] == ["pymunk"] and seen["records_dir"] == str(tmp_path)
    assert seen["executor"] == "dask" and seen["dask_address"] == "tcp://127.0.0.1:8786"
    assert seen["workers"] == 3
    assert main(["report", "--records", str(tmp_path / "missing")]) == 2
    assert "--records" in capsys.readouterr().err


def test_a_broken_compare_module_fails_loudly(monkeypatch):
    """An import error in the package is a bug: the command shows it, it never prints
    "unavailable" (and the tests above never skip on it)."""
    import builtins

    real_import = builtins.__import__

    def broken(name, globals=None, locals=None, fromlist=(), level=0):
        if level == 2 and name == "" and fromlist and "comparison" in fromlist:
            raise ImportError("simulated: rockbench.comparison is broken")
        return real_import(name, globals, locals, fromlist, level)

    monkeypatch.setattr(builtins, "__import__", broken)
    with pytest.raises(ImportError, match="simulated"):
        main(["compare", "housner-block", "--engines", "analytic", "--phi0-alpha", "0.5",
              "--duration", "0.5"])


# --- entry point -------------------------------------------------------------------------------
def test_python_dash_m_entry_point():
    proc = subprocess.run([sys.executable, "-m", "rockbench", "scenes"], check=False, capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "paper-asymmetric-hybrid-eps1" in proc.stdout
    proc = subprocess.run([sys.executable, "-m", "rockbench", "info", "nope"],
                          check=False, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [proc.stderr.strip()]
    assert "Traceback" not in proc.stderr


# --- one grammar (issue 23 §4) -----------------------------------------------------------------
GRAMMAR_BAD = [
    # before: tradeoff exited 0 with a row "invalid, inf" for a key pymunk has not
    (["tradeoff", "paper-symmetric", "--engine", "pymunk", "--setting", "pymunk.iterationz=20"],
     "pymunk.iterationz"),
    (["tradeoff", "paper-symmetric", "--engine", "pymunk", "--setting", "pymunk.iterations=x"],
     "pymunk.iterations"),
    # before: tradeoff wanted pymunk:iterations=60; the colon form is refused with the right one
    (["tradeoff", "paper-symmetric", "--engine", "pymunk", "--engine", "mujoco", "--setting",
      "iterations=60"], "pymunk.iterations=60"),
    (["compare", "housner-block", "--phi0-alpha", "0.5", "--engine", "pymunk", "--engine",
      "mujoco", "--setting", "iterations=20"], "pymunk.iterations=20"),
    (["compare", "housner-block", "--phi0-alpha", "0.5", "--engine", "pymunk", "--setting",
      "mujoco.impratio=2"], "mujoco.impratio"),
    (["map", "paper-symmetric", "--grid", "2x2", "--setting", "rtol=abc"], "rtol"),
    (["map", "paper-symmetric", "--grid", "2x2", "--engine", "pymunk", "--setting",
      "iterationz=3"], "iterationz"),
    (["advise", "paper-symmetric", "--tolerance", "0.02", "--engine", "nope"], "--engine"),
    (["stress", "--engine", "pymunk", "--engine", "nope"], "--engine"),
]


@pytest.mark.parametrize("argv,name", GRAMMAR_BAD, ids=[" ".join(a) for a, _ in GRAMMAR_BAD])
def test_one_setting_grammar_refuses_before_running(capsys, tmp_path, monkeypatch, argv, name):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert out == "" and len(lines) == 1 and lines[0].startswith("rockbench: error: "), err
    assert name in lines[0]


def test_tradeoff_settings_reach_the_sweep_in_the_one_grammar(capsys, monkeypatch):
    import rockbench.studies.tradeoff as tradeoff_mod

    seen = {}

    def fake(scene, engines, **kwargs):
        seen.update(kwargs, engines=engines)
        raise rb.RockbenchError("stop here")

    monkeypatch.setattr(tradeoff_mod, "tradeoff", fake)
    assert main(["tradeoff", "paper-symmetric", "--engine", "pymunk", "--engine", "mujoco",
                 "--setting", "pymunk.iterations=30,collision_slop=1e-4",
                 "--setting", "mujoco.impratio=10"]) == 2
    assert seen["engines"] == ["pymunk", "mujoco"]
    from rockbench.engines.setting_text import Overrides
    assert seen["settings"] == [Overrides("pymunk", (("iterations", 30),
                                                     ("collision_slop", 1e-4))),
                                Overrides("mujoco", (("impratio", 10.0),))]


def test_engine_option_repeatable_and_comma_lists_are_one_option(capsys, monkeypatch):
    import rockbench.campaign.run as campaign

    seen = {}
    monkeypatch.setattr(campaign, "run_campaign",
                        lambda out_dir="reports", **kw: seen.update(kw) or Path(out_dir))
    monkeypatch.setattr("rockbench.cli.main._print_constants", lambda out, scenes=None: None)
    assert main(["report", "--engine", "pymunk", "--engines", "mujoco,pymunk"]) == 0
    assert seen["engines"] == ["pymunk", "mujoco"]


@needs_pymunk
def test_output_dt_follows_dt_in_python_as_on_the_command_line(capsys):
    """One rule (EngineSettings): the default output interval follows a coarser dt, in
    rb.run as with --dt; an explicit finer output_dt is still refused."""
    scene = rb.load_scene("housner-block")
    r = rb.run(scene, None, engine="pymunk", phi0=0.05, duration=1, dt=2e-3)
    assert r.settings["output_dt"] == 2e-3 and len(r.history) == 501
    d = cli_json(capsys, "run", "housner-block", "--engine", "pymunk", "--phi0", "0.05",
                 "--duration", "1", "--dt", "2e-3")
    assert d["settings"]["output_dt"] == 2e-3
    with pytest.raises(rb.ParameterError, match="output_dt"):
        rb.run(scene, None, engine="pymunk", phi0=0.05, duration=1, dt=2e-3, output_dt=1.5e-3)


def test_a_pulse_run_that_ends_before_the_pulse_is_refused():
    """A pulse run starts 3 T_g before the pulse centre: a --duration that ends before it is
    refused in one line naming the shortest useful one, not run as a structure that never
    moved."""
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-m", "rockbench", "run", "paper-asymmetric",
                        "--pulse", "antisymmetric", "--sign", "-1", "--amplitude", "4",
                        "--frequency", "2", "--duration", "4"], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 2 and "--duration" in r.stderr and "pulse centre" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
