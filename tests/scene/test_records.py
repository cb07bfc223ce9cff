"""Record loaders, checked on the real records of ``shared/records`` (PROVENANCE.md) and on
small synthetic files for every failure mode."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rockbench.constants import G_STANDARD
from rockbench.errors import ParameterError, RecordError
from rockbench.scene.records import find_records, load_at2, load_columns, load_record

RECORDS = Path(__file__).resolve().parents[2].parent / "shared" / "records"
SAC_LA = RECORDS / "sac-la-2in50"
#: Small record fixtures shipped with the tests (tests/data/records/README.md): never skipped.
FIXTURES = Path(__file__).resolve().parents[1] / "data" / "records"
FIX_AT2 = FIXTURES / "IV1940_ElCentro_180_5s.AT2"
FIX_COLUMNS = FIXTURES / "LA21_6s.dat"

#: PROVENANCE.md, section 2: (file, NPTS, DT [s], PGA [g], PGA [cm/s^2], time of PGA [s]).
AT2_FILES = [
    ("IV1979_ElCentroArray4_230.AT2", 7818, 0.005, 0.37043, 363.27, 5.27),
    ("IV1940_ElCentro_180.AT2", 4000, 0.01, 0.31288, 306.83, 2.15),
    ("ChiChi1999_TCU052-N.AT2", 18000, 0.005, 0.41903, 410.93, 34.0),
]
#: PROVENANCE.md, section 3: PGAs [cm/s^2] equal to the published SAC table.
SAC_PGA = {"LA21": 1258.00, "LA22": 902.75, "LA25": 851.62, "LA26": 925.29,
           "LA27": 908.70, "LA28": 1304.10}


def need(path: Path) -> Path:
    if not path.exists():
        pytest.skip(f"shared record data not found at {path}")
    return path


def sac_table() -> dict[str, dict[str, str]]:
    with open(need(SAC_LA / "records.csv"), newline="") as fh:
        return {row["record"]: row for row in csv.DictReader(fh)}


# --- the real records -----------------------------------------------------------------------------
@pytest.mark.parametrize("fname, npts, dt, pga_g, pga_cm, t_pga", AT2_FILES)
def test_at2_records_match_provenance(fname, npts, dt, pga_g, pga_cm, t_pga):
    r = load_at2(need(RECORDS / fname))
    assert r.npts == npts
    assert r.dt == dt
    assert r.t_start == 0.0
    assert r.t_end == pytest.approx((npts - 1) * dt, abs=1e-9)
    assert r.peak / G_STANDARD == pytest.approx(pga_g, abs=5e-6)
    assert r.peak * 100 == pytest.approx(pga_cm, abs=0.005)
    # PROVENANCE rounds the time (ChiChi: 34.005 s is written 34.0 s)
    assert r.time[np.argmax(np.abs(r.samples))] == pytest.approx(t_pga, abs=1.01 * dt)
    assert r.name == Path(fname).stem and r.units_in == "g"
    assert "NPTS" in r.source and "DT" in r.source
    assert load_record(RECORDS / fname).describe() == r.describe()


def test_el_centro_array4_peak_equals_its_header():
    r = load_at2(need(RECORDS / "IV1979_ElCentroArray4_230.AT2"))
    assert "PGA=   .37043 G" in r.source
    assert round(r.peak / G_STANDARD, 5) == 0.37043  # the header's PGA, to its 5 decimals


def test_sac_la_records_match_their_table():
    table = sac_table()
    assert len(table) == 20
    for rec, row in table.items():
        r = load_columns(need(SAC_LA / f"{rec}.dat"), dt=float(row["dt_s"]), units="cm/s2")
        assert r.name == rec
        assert r.npts == int(row["npts"])
        assert r.dt == float(row["dt_s"])
        assert r.peak * 100 == pytest.approx(float(row["pga_cm_s2"]), abs=0.005)
        if rec in SAC_PGA:
            assert r.peak * 100 == pytest.approx(SAC_PGA[rec], abs=0.01)


def test_sac_la_through_load_record_with_scale():
    row = sac_table()["LA21"]
    r = load_record(SAC_LA / "LA21.dat", dt=float(row["dt_s"]), units="cm/s2", scale=0.5)
    assert r.peak * 100 == pytest.approx(0.5 * 1258.00, abs=0.005)
    assert r.name == "LA21 x0.5"
    assert r.describe()["scale"] == 0.5


# --- the shipped fixtures (tests/data/records): run on a fresh clone, never skipped ------------------
def test_fixture_at2_loads_with_its_header():
    r = load_record(FIX_AT2)
    assert r.npts == 500 and r.dt == 0.01 and r.t_start == 0.0
    assert r.t_end == pytest.approx(4.99, abs=1e-12)
    assert r.units_in == "g" and r.name == "IV1940_ElCentro_180_5s"
    # the first 5 s hold the record's PGA (PROVENANCE.md: 0.31288 g at 2.15 s)
    assert r.peak / G_STANDARD == pytest.approx(0.31288, abs=5e-6)
    assert r.time[np.argmax(np.abs(r.samples))] == pytest.approx(2.15, abs=1e-9)
    assert r.samples[0] / G_STANDARD == pytest.approx(-0.6403182e-02, rel=1e-12)
    assert load_at2(FIX_AT2).describe() == r.describe()


def test_fixture_headerless_takes_dt_and_units_from_records_csv():
    r = load_record(FIX_COLUMNS)                        # dt and units from records.csv
    assert r.npts == 300 and r.dt == 0.02 and r.units_in == "cm/s2"
    assert r.peak * 100 == pytest.approx(74.112, abs=5e-4)
    assert r.time[np.argmax(np.abs(r.samples))] == pytest.approx(5.44, abs=1e-9)
    assert r.samples[0] * 100 == pytest.approx(0.45156e-01, rel=1e-12)
    given = load_record(FIX_COLUMNS, dt=0.02, units="cm/s2")
    np.testing.assert_array_equal(given.samples, r.samples)
    # an explicit option wins over the listing
    assert load_record(FIX_COLUMNS, units="m/s2").peak == pytest.approx(74.112, abs=5e-6)


def test_fixture_folder_is_found_whole():
    records, notes = find_records(FIXTURES)
    assert notes == []
    by_name = {r["name"]: r for r in records}
    assert set(by_name) == {"IV1940_ElCentro_180_5s", "LA21_6s"}
    assert by_name["IV1940_ElCentro_180_5s"]["dt"] is None          # the header gives it
    assert (by_name["LA21_6s"]["dt"], by_name["LA21_6s"]["units"]) == (0.02, "cm/s2")
    with open(FIXTURES / "records.csv", newline="") as fh:
        row = next(csv.DictReader(fh))
    r = load_record(by_name["LA21_6s"]["path"], dt=by_name["LA21_6s"]["dt"],
                    units=by_name["LA21_6s"]["units"])
    assert r.npts == int(row["npts"]) and r.peak * 100 == pytest.approx(
        float(row["pga_cm_s2"]), abs=5e-4)


def test_fixtures_are_the_first_samples_of_the_shared_records():
    """Where ../shared/records is present: the fixtures are exact cuts of the records."""
    full = load_at2(need(RECORDS / "IV1940_ElCentro_180.AT2"))
    np.testing.assert_array_equal(load_at2(FIX_AT2).samples, full.samples[:500])
    la21 = load_columns(need(SAC_LA / "LA21.dat"), dt=0.02, units="cm/s2")
    np.testing.assert_array_equal(load_record(FIX_COLUMNS).samples, la21.samples[:300])


# --- synthetic AT2 files --------------------------------------------------------------------------
OLD_HEADER = ("PEER STRONG MOTION DATABASE RECORD. PROCESSING BY PACIFIC ENGINEERING.\n"
              "SOMEWHERE 1/1/01, STATION, 000\n"
              "ACCELERATION TIME HISTORY IN UNITS OF G. FILTER POINTS: HP=0.1 Hz LP=25.0 Hz\n")


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize("header_line", [
    "NPTS=      7, DT=   .0050 SEC,   0 POLE @    40.00000 HZ, ACAUSAL",
    "NPTS=  7, DT= .00500 SEC",
    "DT= 5.0E-03 SEC, NPTS= 7",
    "       7    0.0050    NPTS, DT",
])
def test_at2_header_variants(tmp_path, header_line):
    values = "  .1000000E+00  -.2000000E+00   .3E-01   0.4 -5e-1\n  .6  -.7000000E+00\n"
    path = write(tmp_path, "x.at2", OLD_HEADER + header_line + "\n" + values)
    r = load_record(path)  # lower-case suffix is still AT2
    assert r.npts == 7 and r.dt == 0.005
    np.testing.assert_allclose(r.samples / G_STANDARD, [0.1, -0.2, 0.03, 0.4, -0.5, 0.6, -0.7],
                               rtol=1e-15)
    np.testing.assert_allclose(r.time, 0.005 * np.arange(7), rtol=1e-15)


def at2(tmp_path: Path, npts: int, values: str, header_line: str | None = None) -> Path:
    line = header_line or f"NPTS= {npts}, DT= .0100 SEC"
    return write(tmp_path, "bad.AT2", OLD_HEADER + line + "\n" + values)


@pytest.mark.parametrize("npts, values, header_line, message", [
    (4, ".1 .2 .3\n", None, "NPTS=4 but 3 values"),
    (2, ".1 .2 .3\n", None, "NPTS=2 but 3 values"),
    (3, ".1 .2\n.3 abc\n", None, "line 6"),
    (3, ".1 nan .3\n", None, "not finite"),
    (3, ".1 .2 inf\n", None, "not finite"),
    (3, ".1 .2 .3\n", "NPTS= 3, DT= .0000 SEC", "DT"),
    (3, ".1 .2 .3\n", "NPTS= 3 SEC", "NPTS and DT"),
    (1, ".1\n", None, "at least 2"),
])
def test_at2_errors_name_the_file(tmp_path, npts, values, header_line, message):
    path = at2(tmp_path, npts, values, header_line)
    with pytest.raises(RecordError, match=message) as info:
        load_at2(path)
    assert str(path) in str(info.value)


#: (units as a header writes them, m/s^2 per unit): PEER's "UNITS OF G", the issue's
#: "UNITS: CM/S^2" (was read as g: 294 g), and other agencies' spellings.
HEADER_UNITS = [
    ("ACCELERATION TIME HISTORY IN UNITS OF G. FILTER POINTS: HP=0.1 Hz", G_STANDARD),
    ("ACCELERATION TIME SERIES IN UNITS OF G", G_STANDARD),
    ("ACCELERATION TIME HISTORY IN UNITS OF G,  PGA=   .37043 G, PGV=   80.3737 CM/SEC",
     G_STANDARD),
    ("UNITS: CM/S^2", 0.01),
    ("ACCELERATION TIME HISTORY IN UNITS OF CM/SEC/SEC.", 0.01),
    ("Units: cm/s/s", 0.01),
    ("UNITS = gal", 0.01),
    ("ACCELERATION IN CM/SEC2, PGA= 306.8", 0.01),
    ("acceleration (cm/s**2)", 0.01),
    ("UNITS OF m/s^2", 1.0),
    ("units: mm/s^2", 0.001),
    ("UNITS: IN/S^2", 0.0254),
    ("UNITS: cm s^-2", 0.01),
]


@pytest.mark.parametrize("line, factor", HEADER_UNITS)
def test_at2_header_units_are_read_and_converted(tmp_path, line, factor):
    """The header's units are recognised in the spellings PEER and other agencies use, and the
    samples converted to m/s^2 (issue 22: "UNITS: CM/S^2" was read as g and a block under a
    0.3 g record overturned under 294 g)."""
    text = ("SOME AGENCY\nSTATION X\n" + line + "\nNPTS= 3, DT= .0100 SEC\n1.5 -2.0 0.25\n")
    r = load_record(write(tmp_path, "u.AT2", text))
    np.testing.assert_allclose(r.samples, np.array([1.5, -2.0, 0.25]) * factor, rtol=1e-15)


def test_at2_in_cm_s2_gives_the_pga_written_in_cm_s2(tmp_path):
    """The issue's case: El Centro 1940 rewritten in cm/s^2 under 'UNITS: CM/S^2' loads to
    the same record (PGA 3.068 m/s^2), not 100 x 9.81 times it."""
    src = need(RECORDS / "IV1940_ElCentro_180.AT2")
    g = load_at2(src)
    body = "\n".join(" ".join(f"{v * 100:.6f}" for v in g.samples[i:i + 5])
                     for i in range(0, g.npts, 5))
    path = write(tmp_path, "cm.AT2", "PEER STRONG MOTION DATABASE RECORD\nIMPERIAL VALLEY\n"
                 f"UNITS: CM/S^2\nNPTS=  {g.npts}, DT= .01000 SEC\n{body}\n")
    cm = load_record(path)
    assert cm.units_in == "cm/s2"
    assert cm.peak == pytest.approx(g.peak, rel=1e-6)
    assert cm.peak == pytest.approx(3.068, abs=1e-3)


@pytest.mark.parametrize("line, shown", [
    ("ACCELERATION TIME HISTORY IN UNITS OF CM/SEC. FILTER", "CM/SEC"),
    ("UNITS: KG", "KG"),
    ("UNITS OF FURLONGS/FORTNIGHT^2", "FURLONGS/FORTNIGHT^2"),
    ("UNITS: mgal", "mgal"),
])
def test_at2_in_an_unknown_unit_is_refused_naming_it(tmp_path, line, shown):
    path = write(tmp_path, "x.AT2", f"A\nB\n{line}\nNPTS= 2, DT= .01\n1 2\n")
    with pytest.raises(RecordError) as info:
        load_at2(path)
    msg = str(info.value)
    assert repr(shown) in msg and str(path) in msg
    assert "cm/s^2" in msg and "gal" in msg and "CM/S/S" in msg     # the accepted spellings


def test_at2_without_units_needs_them_given(tmp_path):
    path = write(tmp_path, "x.AT2", "A\nB\nC\nNPTS= 2, DT= .01\n1 2\n")
    with pytest.raises(RecordError, match="states no units"):
        load_record(path)
    assert load_record(path, units="gal").samples[1] == pytest.approx(0.02, rel=1e-15)
    assert load_record(path, units="g").samples[1] == pytest.approx(2 * G_STANDARD, rel=1e-15)


def test_at2_units_given_must_agree_with_the_header(tmp_path):
    path = at2(tmp_path, 2, "1 2\n")                     # UNITS OF G
    assert load_record(path, units="G").units_in == "g"
    with pytest.raises(ParameterError, match="record-units"):
        load_record(path, units="cm/s^2")
    with pytest.raises(ParameterError, match="record-units"):
        load_record(path, units="parsecs")


def test_two_disagreeing_unit_statements_are_refused(tmp_path):
    path = write(tmp_path, "x.AT2", "UNITS OF G\nUNITS: CM/S/S\nNPTS= 2, DT= .01\n1 2\n")
    with pytest.raises(RecordError, match="two units"):
        load_at2(path)


_LENGTH_WORDS = {"cm": 0.01, "centimeters": 0.01, "m": 1.0, "metres": 1.0, "mm": 0.001,
                 "in": 0.0254, "inches": 0.0254, "ft": 0.3048}
_SECONDS = ["s", "sec", "second"]
_SQUARES = ["/{s}^2", "/{s}**2", "/{s}2", "/{s}/{s}", " {s}^-2", ".{s}-2", "/({s}^2)"]


@st.composite
def unit_spellings(draw):
    """(spelling, m/s^2 per unit or None for an unknown unit) in random case."""
    kind = draw(st.sampled_from(["length", "g", "gal", "unknown"]))
    if kind == "length":
        word = draw(st.sampled_from(sorted(_LENGTH_WORDS)))
        sec = draw(st.sampled_from(_SECONDS))
        text, factor = word + draw(st.sampled_from(_SQUARES)).format(s=sec), _LENGTH_WORDS[word]
    elif kind == "g":
        text, factor = draw(st.sampled_from(["g", "(g)", "[G]"])), G_STANDARD
    elif kind == "gal":
        text, factor = draw(st.sampled_from(["gal", "gals"])), 0.01
    else:
        text = draw(st.sampled_from(["cm/s", "m", "kg", "km/h^2", "cm/s^3", "furlong/s^2",
                                     "mgal", "ug", "N", "cm2/s", "g/s", "percent"]))
        factor = None
    case = draw(st.sampled_from([str.lower, str.upper, str.title, lambda x: x]))
    return case(text), factor


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(unit=unit_spellings(), style=st.sampled_from(["UNITS OF {u}", "UNITS: {u}",
                                                     "Acceleration in {u}", "units = {u}"]))
def test_fuzz_header_units(tmp_path, unit, style):
    """Random spellings of known and unknown units in random header styles: a known unit
    converts exactly, an unknown one is a RecordError naming it; nothing else happens."""
    text, factor = unit
    line = style.format(u=text)
    path = write(tmp_path, "f.AT2", f"FUZZ\n{line}\nNPTS= 2, DT= .01\n1.0 -3.0\n")
    if factor is None:
        with pytest.raises(RecordError) as info:
            load_at2(path)
        # named with the accepted spellings, or (a word after "in" that is no unit) no units
        assert "accepted" in str(info.value) and repr(text) in str(info.value) or (
            style.startswith("Acc") and "/" not in text and "states no units" in str(info.value))
    else:
        r = load_at2(path)
        np.testing.assert_allclose(r.samples, [factor, -3.0 * factor], rtol=1e-15)


@pytest.mark.parametrize("loader", [load_at2, lambda p: load_columns(p, dt=0.01, units="g")])
def test_missing_and_empty_files(tmp_path, loader):
    missing = tmp_path / "nope.AT2"
    with pytest.raises(RecordError, match="nope.AT2"):
        loader(missing)
    empty = write(tmp_path, "empty.dat", "  \n\n")
    with pytest.raises(RecordError, match="empty.dat.*empty"):
        loader(empty)
    binary = tmp_path / "bin.dat"
    binary.write_bytes(b"\x00\xff\xfe 1 2 3")
    with pytest.raises(RecordError, match="bin.dat"):
        loader(binary)


# --- headerless columns ---------------------------------------------------------------------------
def test_columns_row_major_units_and_t0(tmp_path):
    path = write(tmp_path, "LAxx.dat", "  1.0  2.0  3.0\n\n 4.0\n# note\n5.0 6.0\n")
    r = load_columns(path, dt=0.02, units="cm/s2", t0=1.0)
    np.testing.assert_allclose(r.samples, [0.01, 0.02, 0.03, 0.04, 0.05, 0.06], rtol=1e-15)
    np.testing.assert_allclose(r.time, 1.0 + 0.02 * np.arange(6), rtol=1e-15)
    assert r.name == "LAxx" and r.units_in == "cm/s2"
    assert load_columns(path, dt=0.02, units="m/s2", name="q").samples[-1] == 6.0
    assert load_columns(path, dt=0.02, units="g").samples[-1] == 6.0 * G_STANDARD


def test_columns_bad_token_names_line(tmp_path):
    path = write(tmp_path, "x.dat", "1 2\n3 4\n5 six\n")
    with pytest.raises(RecordError, match=r"x\.dat, line 3: 'six'"):
        load_columns(path, dt=0.01, units="g")


@pytest.mark.parametrize("kwargs, name", [
    ({"dt": 0.0, "units": "g"}, "dt"),
    ({"dt": -1.0, "units": "g"}, "dt"),
    ({"dt": math.nan, "units": "g"}, "dt"),
    ({"dt": 0.01, "units": "furlong/s2"}, "units"),
    ({"dt": 0.01, "units": "cm/s"}, "units"),
    ({"dt": 0.01, "units": None}, "units"),
    ({"dt": 0.01, "units": "g", "t0": math.nan}, "t0"),
])
def test_columns_bad_arguments(tmp_path, kwargs, name):
    path = write(tmp_path, "x.dat", "1 2 3\n")
    with pytest.raises(ParameterError, match=name):
        load_columns(path, **kwargs)


finite = st.floats(-1e6, 1e6, allow_nan=False)


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.lists(finite, min_size=1, max_size=8), min_size=1, max_size=30),
       dt=st.floats(1e-4, 1.0), t0=st.floats(-10.0, 10.0))
def test_columns_round_trip(tmp_path, rows, dt, t0):
    values = [v for row in rows for v in row]
    path = write(tmp_path, "rt.dat", "\n".join(" ".join(repr(v) for v in row) for row in rows))
    if len(values) < 2:
        with pytest.raises(RecordError, match="at least 2"):
            load_columns(path, dt=dt, units="m/s2")
        return
    r = load_columns(path, dt=dt, units="m/s2", t0=t0)
    np.testing.assert_array_equal(r.samples, values)
    assert r.npts == len(values) and r.dt == dt and r.t_start == t0


# --- dispatch -------------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, name", [
    ({"units": "g"}, "record-dt"),
    ({"dt": 0.01}, "record-units"),
    ({"dt": 0.0, "units": "g"}, "record-dt"),
    ({"dt": 0.01, "units": "km/h"}, "record-units"),
    ({"dt": 0.01, "units": 3}, "record-units"),
    ({"dt": 0.01, "units": "g", "scale": 0.0}, "record-scale"),
    ({"dt": 0.01, "units": "g", "scale": math.nan}, "record-scale"),
])
def test_load_record_names_the_option(tmp_path, kwargs, name):
    path = write(tmp_path, "x.dat", "1 2 3\n")
    with pytest.raises(ParameterError, match=name):
        load_record(path, **kwargs)


def test_load_record_at2_options_must_agree_with_file(tmp_path):
    path = at2(tmp_path, 3, ".1 .2 .3\n")
    assert load_record(path, dt=0.01, units="g", scale=-2.0).samples[0] == \
        pytest.approx(-0.2 * G_STANDARD, rel=1e-15)
    with pytest.raises(ParameterError, match="record-dt"):
        load_record(path, dt=0.02)
    with pytest.raises(ParameterError, match="record-units"):
        load_record(path, units="cm/s2")


def test_records_csv_units_are_parsed_and_bounded(tmp_path, monkeypatch):
    """records.csv units: 'gal' was read as g (it starts with "g") and 'mm/s^2' as cm/s^2 (the
    fallback); now every spelling is parsed, an unknown one names the file and the record, and
    the listing is size-limited like a record file."""
    from rockbench.scene.records import listed_metadata

    (tmp_path / "a.dat").write_text("1 2 3\n")
    listing = tmp_path / "records.csv"
    for cell, units in (("gal", "cm/s2"), ("mm/s^2 (scaled)", "mm/s2"), ("G", "g"), ("", "cm/s2")):
        listing.write_text(f"record,dt_s,units\na,0.01,{cell}\n")
        assert listed_metadata(tmp_path / "a.dat")["units"] == units
    listing.write_text("record,dt_s,units\na,0.01,furlongs\n")
    with pytest.raises(RecordError, match="records.csv.*'a'.*furlongs"):
        listed_metadata(tmp_path / "a.dat")
    monkeypatch.setenv("ROCKBENCH_RECORD_BYTES", "10")
    with pytest.raises(RecordError, match="records.csv has .* bytes"):
        listed_metadata(tmp_path / "a.dat")


def test_records_csv_names_vertical_channels(tmp_path):
    """A ``vertical`` column: an AT2 pair listed without dt (the headers give it), a headerless
    pair whose channel takes its record's dt and units; the channels are not records; each
    record loads with its channel; a missing channel, one naming the record itself, and a
    headerless file without a dt are errors naming the listing."""
    import shutil

    from rockbench.scene.records import bundled_dir, listed_metadata

    for name in ("IV1940_ElCentro_180", "IV1979_ElCentroArray4_230"):
        shutil.copy(bundled_dir() / f"{name}.AT2", tmp_path / f"{name}.AT2")
    (tmp_path / "H.dat").write_text("1 2 3 4\n5 6 7 8\n")
    (tmp_path / "V.dat").write_text("-1 -1 -2 -2\n0 0 1 1\n")
    listing = tmp_path / "records.csv"
    listing.write_text("record,dt_s,units,vertical\n"
                       "IV1940_ElCentro_180,,,IV1979_ElCentroArray4_230.AT2\n"
                       "H,0.01,cm/s^2,V\n")
    recs, notes = find_records(tmp_path)
    assert [r["name"] for r in recs] == ["H", "IV1940_ElCentro_180"] and not notes
    h, at = recs
    assert h["vertical"] == str((tmp_path / "V.dat").resolve())
    assert (h["vertical_dt"], h["vertical_units"]) == (0.01, "cm/s2")
    assert at["vertical"].endswith("IV1979_ElCentroArray4_230.AT2")
    assert at["vertical_dt"] is None and at["dt"] is None
    assert listed_metadata(tmp_path / "H.dat")["vertical"] == h["vertical"]
    rec = load_record(h["path"], dt=h["dt"], units=h["units"], vertical=h["vertical"],
                      vertical_dt=h["vertical_dt"], vertical_units=h["vertical_units"])
    np.testing.assert_allclose(rec.vertical.samples, 0.01 * np.array([-1, -1, -2, -2, 0, 0,
                                                                       1, 1]), rtol=1e-15)
    both = load_record(at["path"], vertical=at["vertical"])
    assert both.vertical is not None and both.describe()["vertical_resampled"]
    listing.write_text("record,dt_s,units,vertical\nH,0.01,cm/s^2,GONE\n")
    with pytest.raises(RecordError, match="records.csv.*'H'.*'GONE'.*no file"):
        find_records(tmp_path)
    listing.write_text("record,dt_s,units,vertical\nH,0.01,cm/s^2,H.dat\n")
    with pytest.raises(RecordError, match="names itself"):
        find_records(tmp_path)
    listing.write_text("record,dt_s,units,vertical\nH,,cm/s^2,V\n")
    with pytest.raises(RecordError, match="headerless"):
        find_records(tmp_path)
    listing.write_text("record,units\nH,cm/s^2\n")                 # no dt, no vertical column
    with pytest.raises(RecordError, match="no dt column"):
        find_records(tmp_path)
