"""The shipped ensemble and the report's fragility section (issue 39, docs/fragility.md): the
synthetic ensemble by name, the section judging every engine it runs, the exports it writes and
the command's ``--export``.

The runs are planted (:func:`_planted_run_cases` replaces the one executor): each record has a
known capacity in PGA and a run overturns iff its scaled PGA reaches it, the same rule for
every backend, so the section's plumbing (the ensemble, the ladder found per frame, the
engines' steps, the verdicts, the table, the exports) is tested in seconds; the slow test at
the end runs it for real.
"""

from __future__ import annotations

import hashlib
import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rockbench.errors import ParameterError
from rockbench.studies.ensembles import (describe_ensemble, parse_synthetic, record_ims,
                                         resolve_records)
from rockbench.studies.fragility_stats import MIN_RECORDS


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """One cache folder for the module: the 20 default records are written once (about 2 s)."""
    return tmp_path_factory.mktemp("records")


def test_the_synthetic_ensemble_resolves_to_20_distinct_records(cache, monkeypatch):
    recs = resolve_records("synthetic", cache=cache)
    assert len(recs) == 20
    assert len({r["name"] for r in recs}) == len({r["path"] for r in recs}) == 20
    digests = {hashlib.sha256(Path(r["path"]).read_bytes()).hexdigest() for r in recs}
    assert len(digests) == 20                                     # 20 different motions
    assert all(r["dt"] == 0.01 for r in recs)
    ens = describe_ensemble(recs)
    assert ens["kind"] == "synthetic" and ens["seed"] == 0 and ens["n"] == 20
    assert "Rezaeian" in ens["text"] and "seed 0" in ens["text"]
    # found again, not written again
    import rockbench.scene.synthetic as S
    monkeypatch.setattr(S, "ensemble", lambda *a, **k: pytest.fail("regenerated"))
    assert [r["path"] for r in resolve_records("synthetic", cache=cache)] == \
        [r["path"] for r in recs]
    monkeypatch.undo()
    # record i does not depend on n; another seed gives other records
    three = resolve_records("synthetic:n=3", cache=cache)
    assert [Path(r["path"]).read_text() for r in three] == [Path(r["path"]).read_text()
                                                             for r in recs[:3]]
    other = resolve_records("synthetic:n=2,seed=5", cache=cache)
    assert Path(other[0]["path"]).read_text() != Path(recs[0]["path"]).read_text()
    assert parse_synthetic("synthetic").name == "synthetic"
    assert parse_synthetic("synthetic:seed=5,n=2").name == "synthetic:n=2,seed=5"
    assert parse_synthetic("bundled") is None
    for bad in ("synthetic:n=0", "synthetic:seed=-1", "synthetic:x=1", "synthetic:n=2,n=3",
                "synthetic:n=a"):
        with pytest.raises(ParameterError, match="records"):
            parse_synthetic(bad)


def test_real_records_say_so():
    ens = describe_ensemble(resolve_records("bundled"))
    assert ens["kind"] == "bundled" and "recorded" in ens["text"]


# ---------------------------------------------------------------------------------------------
# planted runs
# ---------------------------------------------------------------------------------------------
def _planted_run_cases(capacity_of_scene, monkeypatch):
    """Replace the one executor: a case overturns iff |scale| x the record's PGA >= the
    record's capacity (``capacity_of_scene[scene]`` [m/s^2] x a spread fixed per record);
    every backend alike (the spread by the record's file name, not its folder: the same on any
    run); survivors peak at 0.8 x PGA / capacity."""
    import rockbench.sweep as SW
    from rockbench.scene.records import load_record

    pga: dict[str, float] = {}

    def fake(cases, **kw):
        rows = []
        for c in cases:
            m = c["motion"]
            if m["path"] not in pga:
                pga[m["path"]] = float(np.max(np.abs(load_record(
                    m["path"], dt=m.get("dt"), units=m.get("units")).samples)))
            k = int(hashlib.sha256(Path(m["path"]).name.encode()).hexdigest(), 16) % 1000 / 1000.0
            cap = capacity_of_scene[c["scene"]] * math.exp(0.4 * (2.0 * k - 1.0))
            x = abs(m["scale"]) * pga[m["path"]]
            rows.append({"engine": c["engine"], "motion.path": m["path"],
                         "motion.scale": m["scale"], "max_abs_phi_over_alpha":
                             6.8 if x >= cap else 0.8 * x / cap,
                         "overturned": x >= cap, "status": "ok", "cpu_s": 0.001})
        return pd.DataFrame(rows)

    monkeypatch.setattr(SW, "run_cases", fake)


def test_the_section_judges_every_engine_it_runs(cache, tmp_path, monkeypatch):
    """The default size on the synthetic ensemble: both frames found their ladder (the second,
    far above the coarse steps, by extending them), the engines ran >= MIN_RECORDS records at
    steps where the analytic verdicts are mixed, and each engine has a verdict; the page and
    the table say which ensemble; the curves are written and read back."""
    from rockbench.campaign import fragility as CF
    from rockbench.report.fragility_figures import fragility_html

    _planted_run_cases({"paper-asymmetric": 12.0, "paper-asymmetric-hybrid-eps1": 300.0},
                       monkeypatch)
    monkeypatch.setitem(CF.REPORT_SIZES["default"], "records", "synthetic")
    monkeypatch.setitem(CF.REPORT_SIZES["default"], "n_boot", 50)     # the plumbing, not bands
    store = tmp_path / "store"
    (store / "records").mkdir(parents=True)
    for p in cache.iterdir():                   # the module's records, not written again
        (store / "records" / p.name).symlink_to(p)
    sec = CF.fragility_section({"free": "paper-asymmetric",
                                "hybrid": "paper-asymmetric-hybrid-eps1"},
                               ["analytic", "pymunk", "mujoco"], store=store,
                               numerical={"pymunk": 0.01, "mujoco": 0.02},
                               executor="serial", progress=False)
    assert "error" not in sec, sec.get("error")
    assert sec["ensemble"]["kind"] == "synthetic" and len(sec["records"]) >= 20
    assert "synthetic ensemble" in sec["what"] and "seed 0" in sec["what"]
    for fr in sec["frames"]:
        a, runs = fr["analysis"], fr["runs"]
        st = fr["stripes"]
        ref = st[st["backend"] == "analytic"].set_index("scale")["p_overturn"]
        assert all(0.0 < ref[s] < 1.0 for s in fr["engine_scales"])     # mixed verdicts
        for e in ("pymunk", "mujoco"):
            v = a["backends"][e]
            assert v["records"] >= MIN_RECORDS
            assert v["indistinguishable"] is True, v["verdict"]        # the same rule
            assert v["dispersion_total"] == pytest.approx(
                math.hypot(v["dispersion"], v["dispersion_numerical"]))
        assert set(a["measures"]["backends"]) == {"analytic", "pymunk", "mujoco"}
    hybrid = sec["frames"][1]
    assert max(hybrid["scales"]) * np.median(record_ims(sec["records"])["pga"]) > 96.0
    tab = CF.section_table(sec)
    assert set(tab["ensemble"]) == {"synthetic: synthetic"}
    assert {"dispersion_numerical", "dispersion_total", "im_best"} <= set(tab.columns)
    html = fragility_html(sec, tmp_path / "figures")
    assert "synthetic ensemble" in html and "beta_total" in html
    assert "Sa(T_<wbr>p)" in html                      # a column of the measures table
    # the exports: each frame's curves read back to the fitted medians and dispersions
    xml = store / "export" / "paper-asymmetric.xml"
    assert set(sec["exports"]) >= {"paper-asymmetric.xml", "paper-asymmetric.csv",
                                   "measures.csv"}
    a = sec["frames"][0]["analysis"]
    q = "{http://openquake.org/xmlns/nrml/0.5}"
    ff = {f.get("id"): f for f in ET.parse(xml).getroot().iter(q + "fragilityFunction")}
    full = a["reference_full"]
    for b in ("analytic", "pymunk"):
        v = full if b == "analytic" else a["backends"][b]
        p = ff[b].find(q + "params")
        mean, std = float(p.get("mean")), float(p.get("stddev"))
        beta = math.sqrt(math.log1p((std / mean) ** 2))
        assert beta == pytest.approx(v["dispersion"], rel=1e-9)
        assert mean / math.sqrt(1 + (std / mean) ** 2) * 9.80665 == pytest.approx(
            v["median"], rel=1e-9)
    csv = pd.read_csv(store / "export" / "paper-asymmetric.csv").set_index("ID")
    assert csv.loc["pymunk", "LS1-Theta_0"] == pytest.approx(a["backends"]["pymunk"]["median"])
    assert csv.loc["pymunk", "LS1-Theta_1"] == pytest.approx(
        a["backends"]["pymunk"]["dispersion"])


def test_the_slower_engines_come_from_their_measured_runs_or_are_named_left_out(
        cache, tmp_path, monkeypatch):
    """An engine without a compiled stepping loop (here mujoco, declared so) is in the default
    section only through the runs kept in ``measured``: measured there once (``measure``,
    what ``report --full`` does), then reused by a later section after its check re-run; with
    no folder it is left out, and the section says so per frame."""
    import rockbench.sweep as SW
    from rockbench.campaign import fragility as CF
    from rockbench.report.fragility_figures import fragility_html

    _planted_run_cases({"paper-asymmetric": 12.0}, monkeypatch)
    monkeypatch.setattr(CF, "_fast", lambda names: [n for n in names if n == "pymunk"])
    monkeypatch.setattr("rockbench.sweep.runs.run_case",
                        lambda case, keep="all": SW.run_cases([case]).iloc[0].to_dict())
    monkeypatch.setattr("rockbench.studies.fragility.numerical_evidence",
                        lambda *a, **k: pd.DataFrame())
    monkeypatch.setitem(CF.REPORT_SIZES["default"], "records", "synthetic")
    monkeypatch.setitem(CF.REPORT_SIZES["default"], "n_boot", 20)
    store = tmp_path / "store"
    (store / "records").mkdir(parents=True)
    for p in cache.iterdir():
        (store / "records" / p.name).symlink_to(p)
    frames = {"free": "paper-asymmetric"}
    engines = ["analytic", "pymunk", "mujoco"]
    opts = dict(store=store, numerical={"pymunk": 0.01, "mujoco": 0.02}, executor="serial",
                progress=False)

    alone = CF.fragility_section(frames, engines, **opts)
    assert "error" not in alone, alone.get("error")
    assert set(alone["frames"][0]["analysis"]["backends"]) == {"analytic", "pymunk"}
    assert alone["provenance"] == ["mujoco on free: left out (no folder of measured runs)"]

    measured = tmp_path / "fragility-engines"
    first = CF.fragility_section(frames, engines, measured=measured, measure=True, **opts)
    assert (measured / "paper-asymmetric_mujoco.parquet").is_file()
    again = CF.fragility_section(frames, engines, measured=measured, **opts)
    for sec in (first, again):
        assert "error" not in sec, sec.get("error")
        v = sec["frames"][0]["analysis"]["backends"]["mujoco"]
        assert v["records"] >= MIN_RECORDS and v["indistinguishable"] is True, v["verdict"]
        (line,) = sec["provenance"]
        assert line.startswith("mujoco on free: measured earlier (32 runs")
        assert "mujoco" in sec["what"]
    assert "measured earlier" in fragility_html(again, tmp_path / "figures")


def test_the_command_exports_and_prints_the_new_numbers(cache, tmp_path, monkeypatch, capsys):
    """``rockbench fragility --records synthetic:n=8 --export DIR --json``: the JSON has the
    ensemble, the measures table, beta_num and beta_total, and the two files (which read
    back); a run with no regular fit says so instead of failing."""
    from rockbench.cli.main import main

    _planted_run_cases({"paper-asymmetric": 3.0}, monkeypatch)
    store = tmp_path / "store"
    (store / "records").mkdir(parents=True)
    out = tmp_path / "export"
    argv = ["fragility", "paper-asymmetric", "--records", "synthetic:n=8", "--engine",
            "pymunk", "--scales", "0.5:4:6", "--store", str(store), "--boot", "30",
            "--no-numerical", "--tail", "10", "--export", str(out), "--json"]
    assert main(argv) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["ensemble"]["kind"] == "synthetic" and j["ensemble"]["n"] == 8
    assert j["tail"] == 10.0 and j["structure"]["sa_period"] == pytest.approx(
        2 * math.pi / j["structure"]["p"])
    pm = j["backends"]["pymunk"]
    assert pm["dispersion_numerical"] is None and pm["dispersion_total"] is None  # not measured
    assert j["backends"]["analytic"]["dispersion_total"] == pytest.approx(
        j["backends"]["analytic"]["dispersion"])
    assert set(j["measures"]["measures"]) == {"pga", "pgv", "pga_norm", "pgv_norm", "sa"}
    assert set(j["export"]) == {"fragility.xml", "fragility.csv"}
    tab = pd.read_csv(out / "fragility.csv").set_index("ID")
    assert tab.loc["analytic", "LS1-Theta_0"] == pytest.approx(j["backends"]["analytic"]["median"])
    assert ET.parse(out / "fragility.xml").getroot().tag.endswith("nrml")
    # no run overturns: nothing to export, said in words
    assert main(argv[:6] + ["--scales", "0.01:0.02:2"] + argv[8:-1]) == 0
    text = capsys.readouterr().out
    assert "export: not written" in text and "no backend with a regular fit" in text


def test_bad_tail_and_synthetic_names_fail_before_any_work(tmp_path, capsys):
    """A negative --tail or a bad synthetic name is one line naming it, before any record is
    written or any run made."""
    from rockbench.cli.main import main

    store = tmp_path / "store"
    assert main(["fragility", "paper-asymmetric", "--records", "synthetic", "--tail", "-1",
                 "--store", str(store)]) == 2
    assert "tail" in capsys.readouterr().err
    assert main(["fragility", "paper-asymmetric", "--records", "synthetic:n=0",
                 "--store", str(store)]) == 2
    assert "synthetic:n=N" in capsys.readouterr().err
    assert not store.exists()
