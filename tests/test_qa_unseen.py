"""Issue 23's acceptance, as a new user: structures the project has never seen (written from
docs/scenes.md alone) through stress, map, compare and the report's pages. Each test here failed
before its fix: the stress sweep and its figures named the paper's frame for a user's scene, an
axis that made the structure impossible was a "break" of every engine, the map figure showed an
adaptive map's inferred cells as a structure at rest, the boundary words said "same boundary"
where only one map overturned, and ``--record`` took no bundled record's name."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

import rockbench as rb
from rockbench.cli.main import main
from rockbench.studies import robustness as S

#: A slender stone pier-and-lintel gateway: unequal piers, the lintel by mass and gyration
#: radius, tendons and dampers of its own (not the paper's numbers anywhere).
GATEWAY = """
name = "stone-gateway"
description = "slender stone pier-and-lintel gateway"
[structure]
type = "frame"
column_width = 0.55
column_height_left = 5.2
column_height_right = 4.9
span = 3.4
beam_width = 4.3
beam_height = 0.9
beam_mass = 9500.0
beam_gyration_radius = 1.3
depth = 0.7
density = 2650.0
[devices]
tendon_stiffness = 4.0e6
tendon_length = 5.5
fracture_strain = 0.012
damping = 3.0e5
"""

CABINET = """
name = "museum-cabinet"
description = "squat display cabinet, 1.0 x 1.6 m"
[structure]
type = "block"
width = 1.0
height = 1.6
depth = 0.8
density = 900.0
"""


@pytest.fixture
def gateway(tmp_path):
    p = tmp_path / "gateway.toml"
    p.write_text(GATEWAY)
    return str(p)


@pytest.fixture
def cabinet(tmp_path):
    p = tmp_path / "cabinet.toml"
    p.write_text(CABINET)
    return str(p)


# --- stress --------------------------------------------------------------------------------
def test_an_axis_point_whose_structure_is_impossible_is_not_run_nor_a_break(gateway):
    """alpha = 0.6 rad asks the gateway for 3.56 m wide piers on a 3.4 m span: not a structure,
    so it says nothing about an engine. It was run, and listed as every engine's first break."""
    pts = [p for p in S.stress_points(scene=gateway) if p.axis == "alpha"]
    bad = next(p for p in pts if p.value == 0.6)
    why = S.structure_refusal(bad)
    assert why is not None and "span" in why and "column_width" in why
    assert S.structure_refusal(next(p for p in pts if p.value == 0.05)) is None
    s = S.stress(["pymunk"], points=[bad], executor="serial", scene=gateway)
    assert len(s.table) == 0 and list(s.skipped) == ["alpha=0.6"]
    assert len(S.breaking_points(s.table, gateway)) == 0


def test_the_base_values_are_the_scenes_own(gateway):
    """A beam given by its mass has a mass ratio all the same (beam / left column mass): the
    side of the mass_ratio axis was lost (NaN) for it."""
    sc = rb.load_scene(gateway)
    v = S.base_values(gateway)
    assert v["mass_ratio"] == pytest.approx(9500.0 / sc.structure.mass_left, rel=1e-6)
    assert v["alpha"] == pytest.approx(sc.alpha, abs=1e-4)
    assert v["H1/H"] == pytest.approx(4.9 / 5.2, rel=1e-6)


def _rows(values, classes):
    return pd.DataFrame([{"engine": "e", "axis": "alpha", "value": v, "class": c, "status": "ok",
                          "reason": "", "flags": "", "error": 0.1 if c == "off" else 0.001}
                         for v, c in zip(values, classes)])


def test_json_breaking_points_go_away_from_the_users_scene(gateway):
    """Stress.to_json measured 'below' / 'above' from the paper's alpha (0.142 rad) even for a
    user's scene: the gateway's alpha is 0.105 rad, so 0.12 lies above it."""
    t = _rows([0.05, 0.12], ["within 1%", "off"])
    d = S.Stress(table=t, scene=gateway).to_json()
    (b,) = d["breaking_points"]
    assert b["side"] == "above" and b["value"] == 0.12
    assert d["base_values"]["alpha"] == pytest.approx(0.1054, abs=1e-4)


def test_the_stability_map_names_its_base_and_units():
    from rockbench.report.tradeoff_figures import plot_stability_map

    t = _rows([0.05, 0.12], ["within 1%", "off"])
    fig = plot_stability_map(t, "e", base="stone-gateway",
                             labels={"alpha": S.axis_label("alpha")},
                             base_values={"alpha": 0.1054})
    assert "stone-gateway" in fig._suptitle.get_text()
    assert "paper" not in fig._suptitle.get_text()
    (ax,) = fig.get_axes()
    assert ax.get_ylabel() == "alpha [rad]"
    assert any(np.allclose(line.get_xdata(), 0.1054) for line in ax.get_lines())
    assert "paper" not in plot_stability_map(t, "e")._suptitle.get_text()


def test_the_choice_section_of_a_users_report_never_says_the_paper():
    from rockbench.report.choice_page import choice_html

    t = _rows([0.05, 0.12], ["within 1%", "off"])
    breaks = S.breaking_points(t, None)
    html = choice_html({"scene": "stone-gateway", "stress": t, "breaks": breaks,
                        "stress_base": "stone-gateway",
                        "stress_labels": {"alpha": "alpha [rad]"},
                        "stress_base_values": {"alpha": 0.1054},
                        "stress_skipped": {"alpha=0.6": "ParameterError: span"}},
                       None)
    assert "stone-gateway" in html and "paper" not in html.lower()
    assert "alpha=0.6" in html


def test_cli_stress_names_the_scene_and_what_it_skipped(gateway, capsys):
    """The breaking-point heading named the file path; the skipped point is said."""
    assert main(["stress", gateway, "--engine", "pymunk", "--axes", "alpha", "-q"]) == 0
    out = capsys.readouterr().out
    assert "first break away from stone-gateway" in out and gateway not in out
    assert "not run: alpha=0.6" in out and "alpha [rad]" in out


# --- maps ----------------------------------------------------------------------------------
def test_the_map_figure_shows_inferred_cells_as_inferred():
    """An adaptive map's inferred cells have a verdict but no max |phi|: they were drawn white,
    as a structure at rest."""
    from rockbench.report.map_figures import plot_map_panels

    rows = []
    for a in (1.0, 2.0):
        for w in (1.0, 2.0):
            inf = a == 2.0 and w == 2.0
            rows.append({"pulse": "symmetric", "sign": 1, "amplitude": a, "frequency": w,
                         "overturned": False, "status": "ok", "inferred": inf,
                         "max_abs_phi_over_alpha": math.nan if inf else 0.5})
    fig = plot_map_panels(pd.DataFrame(rows), title="stone-gateway, analytic")
    text = fig._suptitle.get_text()
    assert "inferred" in text and "frame" not in text
    ax = fig.get_axes()[0]
    grey = [m for m in ax.collections if np.ma.count(m.get_array()) == 1]
    assert grey, "the inferred cell is not drawn"


def test_boundary_words_say_where_only_one_map_overturns():
    from rockbench.studies.map_agreement import describe_shift

    shift = pd.DataFrame({"pulse": ["symmetric"] * 2, "sign": [1, 1], "frequency": [1.0, 3.7],
                          "a_min_a": [2.0, math.nan], "a_min_b": [2.0, 8.0]})
    shift["shift"] = shift["a_min_b"] - shift["a_min_a"]
    words = describe_shift(shift, "pymunk")
    assert "same boundary at every frequency" not in words
    assert "pymunk overturns where the reference survives every A, at W = 3.7" in words


def test_cli_map_names_the_scene(cabinet, tmp_path, capsys):
    assert main(["map", cabinet, "--grid", "2x2", "--pulses", "symmetric+", "-q",
                 "--store", str(tmp_path / "m.parquet")]) == 0
    out = capsys.readouterr().out
    assert out.startswith("museum-cabinet, analytic:")


# --- records -------------------------------------------------------------------------------
def test_record_option_takes_a_bundled_records_name(cabinet, capsys):
    """A user who installed the package does not know where its records live: --record takes a
    bundled record's name as rb.load_bundled does; an unknown name lists the bundled ones."""
    assert main(["run", cabinet, "--record", "IV1940_ElCentro_180", "--duration", "3",
                 "--json"]) == 0
    import json

    d = json.loads(capsys.readouterr().out)
    assert d["motion"]["dt_s"] == 0.01
    assert main(["run", cabinet, "--record", "no-such-record"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--record" in err[0] and "IV1940_ElCentro_180" in err[0]


# --- the broken file -----------------------------------------------------------------------
def test_a_devices_table_without_damping_is_refused_in_one_line(tmp_path, capsys):
    p = tmp_path / "broken.toml"
    p.write_text(GATEWAY.replace("damping = 3.0e5\n", ""))
    assert main(["info", str(p)]) == 2
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert out == "" and len(lines) == 1
    assert "missing damping" in lines[0] and "N s/m" in lines[0] and "1e+12" in lines[0]


def test_cli_fragility_names_the_scene_and_the_notes_unit(cabinet, tmp_path, capsys):
    """The summary was headed by the file name (cabinet.toml) and its note's intensities had no
    unit."""
    assert main(["fragility", cabinet, "--records", "bundled", "--engine", "analytic",
                 "--scales", "1:8:2", "--boot", "20", "-q", "--store",
                 str(tmp_path / "f")]) == 0
    out = capsys.readouterr().out
    assert out.startswith("museum-cabinet: 2 records")
    assert "cabinet.toml" not in out
    notes = [line for line in out.splitlines() if "median" in line and "(" in line]
    assert notes and all("intensities in m/s^2" in line for line in notes)


# --- the report: a scene by its name, its fields on the page -------------------------------
def test_a_scene_file_is_labelled_by_the_scenes_name(gateway, tmp_path):
    """The report labelled a user's structure by its file's stem ('gateway') or its path, in
    case names, map captions, tables and findings; its own name is 'stone-gateway'."""
    from rockbench.campaign.maps import scene_label

    assert scene_label(gateway) == "stone-gateway"
    nameless = tmp_path / "plinth.toml"
    nameless.write_text(CABINET.replace('name = "museum-cabinet"\n', ""))
    assert scene_label(str(nameless)) == "plinth"             # no name: the file's stem
    assert scene_label("paper-asymmetric") == "paper-asymmetric"


def test_the_structure_table_gives_every_field_with_its_unit(gateway, cabinet):
    from rockbench.campaign.plan import structure_table

    t = structure_table([gateway, cabinet])
    gw = t[t["scene"] == "stone-gateway"].set_index("field")
    assert gw.loc["column_height_right", "value"] == "4.9"
    assert gw.loc["column_height_right", "unit"] == "m"
    assert gw.loc["beam_mass", "unit"] == "kg" and gw.loc["damping", "unit"] == "N s/m"
    assert float(gw.loc["alpha", "value"]) == pytest.approx(math.atan(0.55 / 5.2), rel=1e-5)
    cab = t[t["scene"] == "museum-cabinet"].set_index("field")
    assert set(cab["part"]) == {"block", "derived"}
    assert "column" not in " ".join(cab["meaning"])          # a block has no columns


def test_a_users_maps_section_does_not_claim_the_papers_figures():
    from rockbench.report.maps_page import maps_html

    rows = [{"pulse": "symmetric", "sign": 1, "amplitude": a, "frequency": 1.0,
             "overturned": a > 1, "status": "ok", "max_abs_phi_over_alpha": 0.5}
            for a in (1.0, 2.0)]
    maps = {"analytic": {"stone-gateway": pd.DataFrame(rows)}, "agreement": None}
    html = maps_html(maps, None, analytic_grid="2 x 1", axes="", paper=False)
    assert "stone-gateway" in html and "paper" not in html.lower()
    assert "Figs. 4-7" in maps_html(maps, None, analytic_grid="2 x 1", axes="")


@pytest.mark.slow
def test_the_quick_report_on_the_gateway_is_about_it(gateway, tmp_path):
    """rockbench report SCENE --quick (pymunk only): every label is the scene's name, its
    fields are on the page, and nothing claims the paper's frame or figures."""
    pytest.importorskip("pymunk")
    out = tmp_path / "rep"
    assert main(["report", gateway, "--quick", "--engine", "pymunk", "--out", str(out),
                 "-q"]) == 0
    page = (out / "index.html").read_text(encoding="utf-8")
    body = page.split('id="settings-section"')[0]            # settings list the file itself
    assert "stone-gateway" in body and "column_height_right" in body
    import re

    assert gateway not in body
    labels = body.replace("pier-and-lintel gateway", "")      # its description says it
    assert not re.findall(r"(?<!stone-)gateway\b(?!\.toml)", labels)  # never the file's stem
    assert "Figs. 4-7" not in body and "the paper&#x27;s frame" not in body
    eta = pd.read_csv(out / "eta.csv")
    assert set(eta["scene"]) == {"stone-gateway"}


def test_findings_call_a_block_a_structure_not_a_frame(gateway, cabinet):
    """With the cabinet (a block) in the report, the findings grouped it under "free-standing
    frames"."""
    from rockbench.campaign.page import _all_frames
    from rockbench.report.conclusions import _groups

    assert _all_frames([gateway]) and not _all_frames([gateway, cabinet])
    df = pd.DataFrame({"scene": ["stone-gateway", "museum-cabinet"], "x": [1.0, 2.0]})
    labels = [k for k, _ in _groups(df, {"stone-gateway": True, "museum-cabinet": False},
                                    "structures")]
    assert labels == ["free-standing structures", "hybrid structures"]
    assert [k for k, _ in _groups(df, {"stone-gateway": True})][1] == "hybrid frames"


def test_compare_prints_no_bare_nan(cabinet, capsys):
    """The analytic row's contact columns printed 'NaN' (a silent NaN to a reader)."""
    assert main(["compare", cabinet, "--phi0-alpha", "0.3", "--engine", "pymunk",
                 "--duration", "1", "-q"]) == 0
    out = capsys.readouterr().out
    assert "NaN" not in out and "n/a" in out and "n/a: not measured" in out


def test_compare_says_why_a_run_is_not_ok(cabinet, capsys):
    """A 7 g pulse makes the squat cabinet slide 0.8 m in pymunk: the table said 'diverged'
    and nothing else."""
    pytest.importorskip("pymunk")
    assert main(["compare", cabinet, "--pulse", "symmetric", "--amplitude", "11.45",
                 "--frequency", "4", "--engine", "pymunk", "-q"]) == 0
    out = capsys.readouterr().out
    assert "pymunk: diverged: sliding" in out and "max_sliding" in out


def test_info_speaks_of_a_block_as_a_block_and_explains_none(cabinet, gateway, capsys):
    """The cabinet's alpha was 'slenderness of the taller column'; a 'none' critical angle or
    fracture rotation was left unexplained."""
    assert main(["info", cabinet]) == 0
    assert "column" not in capsys.readouterr().out
    assert main(["info", gateway, "--set", "devices.fracture_strain=none"]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("phi_fracture_ccw"))
    assert "none: the tendons never fracture" in line
    line = next(x for x in out.splitlines() if x.startswith("phi_cr_ccw "))
    assert "none: no zero of dV/dphi" in line
