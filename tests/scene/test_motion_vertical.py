"""Ground motions with a vertical component: the pulse's in-phase vertical part, a record's
vertical channel (one time base), their descriptions, labels, scaling, the a-priori limits and
the command line (``--vertical``, ``--record-vertical``). SI units."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from rockbench.cli.main import main
from rockbench.constants import G
from rockbench.errors import ParameterError
from rockbench.scene.motion import Record, RickerPulse, make_pulse, motion_from_spec
from rockbench.scene.records import load_record
from rockbench.scene.scene import load_scene

SHARED = Path(__file__).resolve().parents[2] / ".." / "shared" / "records"
BLOCK = load_scene("housner-block")


@pytest.mark.parametrize("shape", ["symmetric", "antisymmetric"])
@pytest.mark.parametrize("sign", [1, -1])
def test_pulse_vertical_part_is_in_phase(shape, sign):
    """a_v(t) = r u_g''(t) at every t (same shape, sign, period), peak r a_g, same window."""
    p = RickerPulse(3.0, 0.7, shape, sign, vertical_ratio=0.45)
    v = p.vertical
    t = np.linspace(p.t_start, p.t_end, 1001)
    np.testing.assert_allclose(v.acceleration(t), 0.45 * p.acceleration(t), rtol=1e-15,
                               atol=1e-15 * p.peak)
    assert v.peak == pytest.approx(0.45 * 3.0, rel=1e-15)
    assert (v.t_start, v.t_end) == (p.t_start, p.t_end) and v.vertical is None
    assert RickerPulse(3.0, 0.7, shape, sign).vertical is None
    assert RickerPulse(3.0, 0.7, shape, sign, vertical_ratio=0.0).vertical is None


@pytest.mark.parametrize("bad", [-0.1, 3.5, math.nan, math.inf, "x", True, None])
def test_vertical_ratio_is_validated(bad):
    with pytest.raises(ParameterError) as e:
        RickerPulse(3.0, 0.7, vertical_ratio=bad)
    assert e.value.name == "vertical_ratio"


def test_describe_round_trips_and_scaled_scales_both():
    st = BLOCK.structure
    for p in (RickerPulse(2.5, 0.4, "antisymmetric", -1, vertical_ratio=0.3),
              RickerPulse.dimensionless(3.0, 4.0, st, "symmetric", 1, vertical_ratio=0.7),
              make_pulse("symmetric", 1, amplitude=2.0, period=0.5, vertical_ratio=1.2)):
        d = p.describe()
        q = motion_from_spec(d, st)
        t = np.linspace(p.t_start, p.t_end, 101)
        np.testing.assert_array_equal(q.acceleration(t), p.acceleration(t))
        np.testing.assert_array_equal(q.vertical.acceleration(t), p.vertical.acceleration(t))
        assert json.loads(json.dumps(d)) == d
        s = p.scaled(-2.0)
        np.testing.assert_allclose(s.acceleration(t), -2 * p.acceleration(t), atol=1e-12)
        np.testing.assert_allclose(s.vertical.acceleration(t), -2 * p.vertical.acceleration(t),
                                   atol=1e-12)
        assert "V=" in p.label() and "vertical part" in p.label(long=True)
    # without a vertical part the description keeps today's keys
    assert "vertical_ratio" not in RickerPulse(2.0, 0.5).describe()


def test_record_vertical_channel_shares_the_time_base():
    t = np.arange(0.0, 2.0, 0.01)
    h = Record(t, np.sin(3 * t))
    same = h.with_vertical(Record(t, np.cos(5 * t), name="up"))
    np.testing.assert_array_equal(same.vertical.samples, np.cos(5 * t))
    assert same.describe()["vertical_resampled"] is False
    t2 = np.arange(0.003, 2.5, 0.02)                 # another clock: sampled at h's times
    other = h.with_vertical(Record(t2, np.cos(5 * t2)))
    np.testing.assert_array_equal(other.vertical.time, t)
    np.testing.assert_allclose(other.vertical.samples, np.interp(t, t2, np.cos(5 * t2),
                                                                 left=0.0, right=0.0))
    assert other.describe()["vertical_resampled"] is True
    s = same.scaled(-1.5)
    np.testing.assert_allclose(s.vertical.samples, -1.5 * np.cos(5 * t))
    assert h.vertical is None and h.with_vertical(None).vertical is None
    with pytest.raises(ParameterError, match="vertical"):
        h.with_vertical(np.zeros(3))
    assert "& up" in same.label()


def test_load_record_pairs_two_at2_files(tmp_path):
    """Two components of one station (same NPTS and DT) are paired sample for sample; the
    shared accelerograms (two stations, dt 0.005 and 0.01: there is no vertical channel in
    ../shared/records) are paired by sampling the second at the first's times."""
    def at2(name, values, dt):
        lines = ["TEST", f"{name}", "ACCELERATION TIME HISTORY IN UNITS OF G",
                 f"NPTS= {len(values)}, DT= {dt:.4f} SEC"]
        lines += [" ".join(f"{v:.7E}" for v in values[i:i + 5]) for i in range(0, len(values), 5)]
        p = tmp_path / f"{name}.AT2"
        p.write_text("\n".join(lines) + "\n")
        return p
    k = np.arange(400)
    hp = at2("STA-N", 0.2 * np.sin(k / 7), 0.01)
    vp = at2("STA-UP", -0.1 * np.cos(k / 5), 0.01)
    r = load_record(hp, vertical=vp, scale=2.0)
    np.testing.assert_allclose(r.vertical.samples, 2 * -0.1 * np.cos(k / 5) * 9.80665,
                               rtol=1e-7)
    assert r.describe()["vertical_resampled"] is False
    with pytest.raises(ParameterError) as e:
        load_record(hp, vertical=tmp_path / "missing.txt")
    assert e.value.name.startswith("record-vertical")
    if SHARED.is_dir():
        pair = load_record(SHARED / "IV1979_ElCentroArray4_230.AT2",
                           vertical=SHARED / "IV1940_ElCentro_180.AT2")
        assert pair.vertical.npts == pair.npts and pair.describe()["vertical_resampled"]
        spec = {"kind": "record", "path": str(SHARED / "IV1979_ElCentroArray4_230.AT2"),
                "vertical_path": str(SHARED / "IV1940_ElCentro_180.AT2"), "scale": -1.0}
        again = motion_from_spec(spec)
        np.testing.assert_array_equal(again.vertical.samples, -pair.vertical.samples)


def test_cli_vertical_pulse_and_record(tmp_path, capsys):
    assert main(["run", "housner-block", "--pulse", "symmetric", "--amplitude", "2",
                 "--frequency", "4", "--vertical", "0.5", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["motion"]["vertical_ratio"] == 0.5
    assert {"sliding_onset", "sliding_contact", "t_lift_off", "validity"} <= set(d)
    assert main(["run", "housner-block", "--pulse", "symmetric", "--amplitude", "2",
                 "--frequency", "4", "--vertical", "4"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--vertical" in err[0]
    assert main(["run", "housner-block", "--record", "IV1940_ElCentro_180", "--vertical",
                 "0.5"]) == 2
    assert "given only with --pulse" in capsys.readouterr().err
    assert main(["run", "housner-block", "--pulse", "symmetric", "--amplitude", "2",
                 "--frequency", "4", "--record-vertical", "x.AT2"]) == 2
    assert "given only with --record" in capsys.readouterr().err
    assert main(["run", "housner-block", "--record", "IV1940_ElCentro_180",
                 "--record-vertical", "IV1979_ElCentroArray4_230", "--duration", "5",
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["motion"]["vertical_name"] == "IV1979_ElCentroArray4_230"
    try:
        main(["run", "--help"])
    except SystemExit:
        pass
    text = " ".join(capsys.readouterr().out.split())
    assert "--vertical RATIO" in text and "positive up" in text and "m/s^2" in text
    assert "--record-vertical FILE" in text


# --- any horizontal motion with any vertical one (WithVertical) ---------------------------------
def test_with_vertical_pairs_any_two_motions():
    """The horizontal's acceleration, peak and sup after t; the vertical as given; the window
    spanning both; knots the union of both (a lift-off at a_v = -g is bracketed on them);
    scaled scales both; picklable; a component with its own vertical part refused."""
    import pickle

    from rockbench.scene.motion import WithVertical
    from rockbench.validity import lift_off_time

    still = Record([-1.0, 2.0], [0.0, 0.0], name="still")
    v = RickerPulse(1.5 * G, 0.3, sign=-1)
    m = WithVertical(still, v)
    assert m.vertical is v and m.horizontal is still
    assert (m.t_start, m.t_end) == (-1.0, 2.0)
    t = np.linspace(-1.0, 2.0, 301)
    np.testing.assert_array_equal(m.acceleration(t), still.acceleration(t))
    assert m.peak == 0.0 and m.max_abs_after(0.0) == 0.0
    k = m.knots(-0.5, 0.5)
    assert set(v.knots(-0.5, 0.5)) <= set(k) and k[0] == -0.5 and k[-1] == 0.5
    assert np.all(np.diff(k) > 0)
    # g + a_v <= 0 first where 1.5 w(tau) = 1 on the main (downward) lobe of the vertical pulse
    from scipy.optimize import brentq
    w = lambda tau: (1 - 2 * math.pi**2 * tau**2) * math.exp(-math.pi**2 * tau**2)
    tau = brentq(lambda x: 1.5 * w(x) - 1.0, -0.3, 0.0, xtol=1e-15)
    assert lift_off_time(m) == pytest.approx(tau * 0.3, abs=1e-12)
    s = m.scaled(-2.0)
    np.testing.assert_allclose(s.vertical.acceleration(t), -2.0 * v.acceleration(t), rtol=1e-15)
    back = pickle.loads(pickle.dumps(m))
    np.testing.assert_array_equal(back.vertical.acceleration(t), v.acceleration(t))
    d = m.describe()
    assert d["kind"] == "record" and d["vertical"]["kind"] == "ricker"
    json.dumps(d)
    assert m.label() == "still & vertical " + v.label()
    with pytest.raises(ParameterError, match="horizontal"):
        WithVertical(RickerPulse(1.0, 1.0, vertical_ratio=0.5), v)
    with pytest.raises(ParameterError, match="vertical"):
        WithVertical(still, RickerPulse(1.0, 1.0, vertical_ratio=0.5))
    with pytest.raises(ParameterError, match="vertical"):
        WithVertical(still, 3.0)


def test_with_vertical_of_an_in_phase_pulse_is_the_pulse_with_its_vertical_ratio():
    """WithVertical(pulse, r x pulse) is RickerPulse(..., vertical_ratio=r): the analytic model
    (solve_ivp path, uplift at |a_g| > lambda (g + a_v) bracketed on the union of the knots)
    gives the same history, and Newmark's block the same slip."""
    import rockbench as rb
    from rockbench.analytic.sliding import sliding_response

    scene = load_scene("paper-asymmetric")
    own = RickerPulse.dimensionless(3.0, 4.0, scene.structure, vertical_ratio=0.4)
    h = RickerPulse.dimensionless(3.0, 4.0, scene.structure)
    pair = rb.WithVertical(h, RickerPulse(0.4 * h.amplitude, h.period))
    a = rb.run(scene, own, duration=4.0, method="DOP853")
    b = rb.run(scene, pair, duration=4.0, method="DOP853")
    assert a.summary.n_impacts == b.summary.n_impacts >= 1
    assert b.summary.t_uplift == pytest.approx(a.summary.t_uplift, abs=1e-12)
    np.testing.assert_allclose(b.history["phi"], a.history["phi"], rtol=0, atol=1e-9 * scene.alpha)
    s1 = sliding_response(own, 0.1).summary
    s2 = sliding_response(pair, 0.1).summary
    assert s2.final_displacement == pytest.approx(s1.final_displacement, rel=1e-12)
