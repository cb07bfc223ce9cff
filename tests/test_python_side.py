"""The Python side engineers expect: notebook views, summaries as frames, public plotting
helpers, typing marker, and assert_agree failures that point at the caller."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from importlib import resources
from pathlib import Path

import pandas as pd
import pytest
from matplotlib.figure import Figure

import rockbench as rb
from rockbench.errors import ParameterError
from rockbench.result import COST_FIELDS, SUMMARY_FIELDS, Summary


@pytest.fixture(scope="module")
def runs():
    scene = rb.load_scene("housner-block")
    pulse = rb.RickerPulse.dimensionless(A=3.0, W=3.0, structure=scene.structure)
    ref = rb.run(scene, pulse, duration=3.0)
    return scene, pulse, ref


def test_summary_fields_cover_the_dataclass():
    from dataclasses import fields
    assert [f.name for f in fields(Summary)] == list(SUMMARY_FIELDS)
    for text in (*SUMMARY_FIELDS.values(), *COST_FIELDS.values()):
        unit, meaning = text.split(", ", 1)
        assert unit and meaning


def test_summary_to_frame_keeps_values_and_units(runs):
    _, _, ref = runs
    f = ref.summary.to_frame()
    assert list(f.columns) == ["value", "unit", "meaning"]
    assert f.loc["n_impacts", "value"] == ref.summary.n_impacts
    assert f.loc["max_abs_phi", "unit"] == "rad"
    assert f.loc["max_abs_phi_over_alpha", "value"] == pytest.approx(
        ref.summary.max_abs_phi_over_alpha)
    c = ref.cost.to_frame()
    assert c.loc["steps", "value"] == ref.cost.steps and isinstance(c.loc["steps", "value"], int)


def test_result_repr_is_short_and_html_has_units(runs):
    _, _, ref = runs
    text = repr(ref)
    assert text.startswith("<Result analytic on 'housner-block'") and "\n" not in text
    assert "max|phi|/alpha" in text and len(text) < 200
    page = ref._repr_html_()
    assert "<table>" in page and ">rad<" in page and "housner-block" in page


def test_plot_helpers_return_figures(runs):
    scene, pulse, ref = runs
    fig = rb.plot_history(ref)
    assert isinstance(fig, Figure) and len(fig.axes) == 3
    fig = rb.plot_history({"reference": ref}, detail=False)
    assert isinstance(fig, Figure) and len(fig.axes) == 1
    cells = pd.DataFrame({"pulse": ["symmetric", "antisymmetric"] * 2, "sign": [1, 1, -1, -1],
                          "amplitude": [1.0, 2.0, 1.0, 2.0], "frequency": [3.0] * 4,
                          "overturned": [False, True, False, True],
                          "max_abs_phi_over_alpha": [0.5, 1.5, 0.4, 1.5], "status": ["ok"] * 4})
    assert isinstance(rb.plot_map(cells), Figure)
    assert isinstance(rb.plot_map(cells, compare=cells.assign(backend="pymunk")),
                      Figure)
    table = pd.DataFrame({"engine": ["pymunk", "pymunk"], "dt": [1e-3, 5e-4],
                          "cpu_per_sim_s": [0.01, 0.02], "worst_error": [0.03, 0.01]})
    assert isinstance(rb.plot_work_precision(table, tolerance=0.02), Figure)


def test_plot_helpers_refuse_what_they_cannot_draw(runs):
    with pytest.raises(ParameterError, match="results"):
        rb.plot_history(42)
    with pytest.raises(ParameterError, match="frame"):
        rb.plot_map(pd.DataFrame({"pulse": []}))
    with pytest.raises(ParameterError, match="tolerance"):
        rb.plot_work_precision(pd.DataFrame({"engine": [], "dt": [], "cpu_per_sim_s": [],
                                             "worst_error": []}), tolerance=2.0)


def test_package_is_typed():
    assert resources.files("rockbench").joinpath("py.typed").is_file()


def test_assert_agree_failure_points_at_the_callers_line(tmp_path: Path):
    test = tmp_path / "test_user.py"
    test.write_text(textwrap.dedent("""
        import rockbench as rb
        from rockbench.testing import assert_agree

        def test_user():
            scene = rb.load_scene("housner-block")
            pulse = rb.RickerPulse.dimensionless(A=3.0, W=3.0, structure=scene.structure)
            ref = rb.run(scene, pulse, duration=2.0)
            eng = rb.run(scene, pulse, engine="pymunk", duration=2.0)
            assert_agree(eng, ref, peak_rtol=1e-12, nrmse=1e-12)
    """))
    out = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                          "-p", "no:xdist", str(test)], capture_output=True, text=True,
                         cwd=tmp_path, timeout=300)
    text = out.stdout + out.stderr
    assert out.returncode == 1, text
    assert "agree.py" not in text, text   # no frame of rockbench.testing in the traceback
    assert "assert_agree(eng, ref" in text
