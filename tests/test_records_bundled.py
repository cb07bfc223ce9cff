"""The records shipped inside the package (issue 14): present, unmodified, readable without
``shared/``, with their provenance beside them."""

from __future__ import annotations

import hashlib
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from rockbench.constants import G_STANDARD
from rockbench.errors import ParameterError
from rockbench.scene.motion import Record
from rockbench.scene.records import bundled_records, load_bundled

#: name: (sha256 of the shipped bytes, NPTS, DT [s], PGA [g], time of the PGA [s]) -
#: rockbench/records/PROVENANCE.md
SHIPPED = {
    "IV1940_ElCentro_180": ("edcd5353db8a9305227293142a3b8b8a7622b273f886c5e739dea451f0111063",
                            4000, 0.01, 0.31288, 2.15),
    "IV1979_ElCentroArray4_230": (
        "840ae0f05f36443a8d81203eb430a3f1858c0388c1ff57b8038aef3c2085593b",
        7818, 0.005, 0.37043, 5.27),
}
ROOT = Path(__file__).resolve().parents[1]


def test_bundled_list_is_the_shipped_set_and_unmodified():
    recs = bundled_records()
    assert [r["name"] for r in recs] == sorted(SHIPPED)
    for r in recs:
        digest = hashlib.sha256(Path(r["path"]).read_bytes()).hexdigest()
        assert digest == SHIPPED[r["name"]][0], r["name"]
        assert "/shared/" not in r["path"]          # inside the package


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_load_bundled_reproduces_the_header(name):
    _, npts, dt, pga_g, t_pga = SHIPPED[name]
    rec = load_bundled(name)
    assert isinstance(rec, Record)
    assert rec.npts == npts and rec.dt == dt
    i = int(np.argmax(np.abs(rec.samples)))
    assert rec.peak / G_STANDARD == pytest.approx(pga_g, abs=5e-6)
    assert rec.time[i] == pytest.approx(t_pga, abs=dt / 2)
    # case-insensitive, with or without the suffix
    assert load_bundled(name.lower() + ".AT2").npts == npts


def test_unknown_name_lists_the_bundled_ones():
    with pytest.raises(ParameterError, match="IV1940_ElCentro_180"):
        load_bundled("ChiChi1999_TCU052-N")       # surveyed, not shippable
    with pytest.raises(ParameterError):
        load_bundled(None)


def test_provenance_beside_every_shipped_file_and_excluded_ones_explained():
    text = (ROOT / "rockbench" / "records" / "PROVENANCE.md").read_text()
    for name, (digest, *_ ) in SHIPPED.items():
        assert name in text and digest in text
    assert "NOT shipped" in text and "ChiChi1999_TCU052-N" in text and "LA21" in text


def test_package_data_glob_ships_them():
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())
    globs = cfg["tool"]["setuptools"]["package-data"]["rockbench"]
    assert "records/*.AT2" in globs and "records/*.md" in globs


def test_bundled_records_need_no_shared_folder(tmp_path):
    """A fresh process that cannot see shared/ (cwd elsewhere) still loads them."""
    code = ("from rockbench.scene.records import bundled_records, load_bundled;"
            "print(sum(load_bundled(r['name']).npts for r in bundled_records()))")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, check=True)
    assert int(out.stdout) == 4000 + 7818
