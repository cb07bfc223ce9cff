"""What a backend can do is an attribute of its class (``engines/base.py``), read through the
registry by sweeps and campaigns, which name no engine."""

from __future__ import annotations

import subprocess
import sys

import pytest

import rockbench as rb
from rockbench.engines import REGISTRY, get_backend
from rockbench.engines.base import Backend


def test_every_backend_declares_the_capabilities():
    for name in REGISTRY:
        B = get_backend(name)
        assert isinstance(B.batched, bool) and isinstance(B.fast, bool)
        assert B.relative_cost > 0
    assert Backend.batched is False and Backend.fast is False and Backend.relative_cost == 1.0
    assert get_backend("mujoco").batched and get_backend("mujoco").fast
    assert get_backend("pymunk").fast and not get_backend("pymunk").batched
    assert get_backend("pybullet").relative_cost > get_backend("mujoco").relative_cost


def test_a_backend_without_batched_runs_refuses_them():
    B = get_backend("pymunk")
    scene = rb.load_scene("housner-block")
    assert "no batched path" in B.batch_refusal(scene, B.Settings())
    with pytest.raises(rb.ParameterError, match="batched"):
        B.run_batch(scene, [])


def test_sweeps_and_campaigns_read_the_capabilities():
    from rockbench.campaign.run import _job_weight
    from rockbench.campaign.maps import is_fast
    from rockbench.sweep.runs import _batch_key

    base = {"scene": "housner-block", "overrides": {}, "settings": {}, "duration": 3.0,
            "phi0": 0.0, "motion": {"kind": "ricker", "A": 2.0, "W": 3.0}}
    assert _batch_key(dict(base, engine="mujoco")) is not None
    assert _batch_key(dict(base, engine="pymunk")) is None
    assert _batch_key(dict(base, engine="mujoco", phi0=0.1)) is None
    job = {"scene": "paper-asymmetric", "kind": "pulse", "duration": 4.0}   # longest first
    assert _job_weight(job) == pytest.approx(4.0)
    assert _job_weight(dict(job, scene="paper-asymmetric-hybrid")) == pytest.approx(10.0)
    assert [e for e in REGISTRY if is_fast(e)] == ["pymunk", "mujoco"]


def test_reading_a_capability_imports_no_engine():
    code = ("import sys; from rockbench.engines import REGISTRY, get_backend; "
            "[get_backend(n).batched for n in REGISTRY]; "
            "print(sorted(m for m in ('pymunk', 'mujoco', 'pybullet', 'openseespy', 'pydrake')"
            " if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


def test_opensees_without_its_library_says_why_and_what_installs_it(monkeypatch):
    """Without an importable openseespy (e.g. no libblas.so.3, openseespy's wheel re-raising
    the loader's error as "Failed to import openseespy on Linux") the probe reports the first
    cause, and the remedy names the system library."""
    import sys

    from rockbench.engines.opensees import OpenseesBackend

    monkeypatch.setitem(sys.modules, "openseespy.opensees", None)
    ok, why = OpenseesBackend._probe()
    assert not ok and why.startswith("openseespy does not import: ")
    blas = ("openseespy does not import: ImportError: libblas.so.3: cannot open shared "
            "object file: No such file or directory")
    assert "apt-get install libblas3" in OpenseesBackend.remedy(blas)
    assert OpenseesBackend.remedy("ImportError: No module named 'openseespy'") == \
        "pip install 'rockbench[opensees]'"


def test_the_cause_of_an_import_failure_is_the_first_one():
    from rockbench.engines.opensees import _import_cause

    try:
        try:
            raise ImportError("libblas.so.3: cannot open shared object file")
        except ImportError:
            raise RuntimeError("Failed to import openseespy on Linux.")
    except RuntimeError as e:
        assert _import_cause(e) == "ImportError: libblas.so.3: cannot open shared object file"
