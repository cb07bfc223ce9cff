"""A sixth engine by one file: an adapter registered from outside the package, through an entry
point of its own distribution (``rockbench.engines``), reaches every command with no edit of
rockbench.

The distribution is written into a temporary folder at test time (a module and its
``.dist-info`` with ``entry_points.txt``) and put on ``sys.path`` and ``PYTHONPATH`` (worker
processes find it too). Its engine, ``softmunk``, is pymunk with other defaults (a finer time
step): a second name for an existing engine, so that it runs everywhere pymunk does.
"""

from __future__ import annotations

import math
import os
import sys
import textwrap
from pathlib import Path

import pytest

import rockbench as rb

NAME = "softmunk"

_MODULE = '''
"""A backend registered from outside rockbench: pymunk with a finer default time step."""
from dataclasses import dataclass

from rockbench.engines.pymunk import PymunkBackend, PymunkSettings


@dataclass(frozen=True)
class SoftSettings(PymunkSettings):
    dt: float = 5e-4


class SoftBackend(PymunkBackend):
    name = "softmunk"
    package = "pymunk"
    Settings = SoftSettings
'''


@pytest.fixture(scope="module")
def sixth(tmp_path_factory):
    pytest.importorskip("pymunk")
    from rockbench import engines

    root = tmp_path_factory.mktemp("sixth")
    (root / "rockbench_sixth.py").write_text(textwrap.dedent(_MODULE), encoding="utf-8")
    info = root / "rockbench_sixth-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: rockbench-sixth\n"
                                   "Version: 0.1\n", encoding="utf-8")
    (info / "entry_points.txt").write_text(
        f"[{engines.ENTRY_POINT_GROUP}]\n{NAME} = rockbench_sixth:SoftBackend\n",
        encoding="utf-8")
    old_path, old_env = list(sys.path), os.environ.get("PYTHONPATH")
    sys.path.insert(0, str(root))
    os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(root), old_env) if p)
    added = engines.discover_engines()
    try:
        yield added
    finally:
        engines.REGISTRY.pop(NAME, None)
        sys.path[:] = old_path
        if old_env is None:
            os.environ.pop("PYTHONPATH", None)
        else:
            os.environ["PYTHONPATH"] = old_env


def test_the_entry_point_registers_it_once(sixth):
    from rockbench import engines

    assert sixth == {NAME: "rockbench_sixth:SoftBackend"}
    assert NAME in rb.backend_names() and NAME in rb.available_backends()
    assert engines.discover_engines() == {}               # a second discovery adds nothing
    cls = rb.get_backend(NAME)
    assert cls.Settings().dt == 5e-4 and cls.contact_variants   # pymunk's contact search


def test_a_name_taken_by_the_package_is_refused(tmp_path, monkeypatch):
    from rockbench import engines
    from rockbench.errors import RockbenchWarning

    info = tmp_path / "rogue-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: rogue\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(
        f"[{engines.ENTRY_POINT_GROUP}]\npymunk = rogue:Fake\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.warns(RockbenchWarning, match="rogue:Fake"):
        assert engines.discover_engines() == {}
    assert engines.REGISTRY["pymunk"] == "rockbench.engines.pymunk:PymunkBackend"


def _pulse_case():
    scene = rb.load_scene("paper-asymmetric")
    return scene, rb.RickerPulse.dimensionless(A=3.0, W=4.0, structure=scene.structure)


def test_run_and_compare_include_it(sixth):
    scene, pulse = _pulse_case()
    r = rb.run(scene, pulse, engine=NAME, duration=4.0)
    ref = rb.run(scene, pulse, engine="analytic", duration=4.0)
    assert r.ok and r.backend == NAME
    assert abs(r.summary.max_abs_phi / ref.summary.max_abs_phi - 1) < 0.02
    c = rb.compare(scene, pulse, engines=[NAME], duration=4.0)
    row = c.table.set_index("backend").loc[NAME]
    assert row["status"] == "ok" and bool(row["verdict_agrees"])
    assert NAME in repr(c)


def test_the_engines_command_lists_it(sixth, capsys):
    from rockbench.cli.main import main

    assert main(["engines"]) == 0
    assert NAME in capsys.readouterr().out


def test_a_map_includes_it(sixth, tmp_path):
    from rockbench.studies.maps import run_map

    df = run_map("housner-block", NAME, grid=(3, 2), amplitude="1:6", frequency="3:6",
                 pulses="symmetric+", tail=0.5, store=tmp_path / "m.parquet", progress=False,
                 workers=1)
    assert len(df) == 6 and (df["status"] == "ok").all()
    assert df["overturned"].astype(bool).any() and not df["overturned"].astype(bool).all()


@pytest.mark.slow
def test_advise_stress_fragility_and_the_report_include_it(sixth, tmp_path):
    from rockbench.campaign.run import run_campaign
    from rockbench.studies.advise import advise
    from rockbench.studies.fragility import run_fragility
    from rockbench.studies.robustness import stress

    a = advise("housner-block", tolerance=0.05, engines=[NAME], quick=True, contact=True,
               store=tmp_path / "advise", workers=1)
    assert NAME in set(a.decision.outcomes["engine"])
    # its contact variants (pymunk's, inherited) were searched, with no edit of the search
    assert set(a.decision.contact["engine"]) == {NAME} and len(a.decision.contact) > 1
    s = stress([NAME], axes=["dt"], workers=1)
    assert set(s.table["engine"]) == {NAME}
    recs = sorted((Path(__file__).resolve().parents[2] / "shared" / "records").glob("*.AT2"))
    if not recs:
        pytest.skip("no records in ../shared/records")
    f = run_fragility("housner-block", [str(p) for p in recs[:2]], engines=[NAME],
                      scales="0.5:2:3", store=tmp_path / "frag", progress=False, workers=1)
    assert NAME in set(f.runs["backend"])
    page = run_campaign(tmp_path / "report", engines=[NAME], quick=True, progress=False)
    html = page.read_text(encoding="utf-8")
    assert html.count(NAME) > 3 and not math.isnan(len(html))
