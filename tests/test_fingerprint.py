"""The code fingerprint of stored results hashes the physics code only: editing the command
line, the report or a plan keeps every stored result; editing the model does not."""

from __future__ import annotations

import rockbench.sweep.store as S


def test_fingerprint_hashes_the_physics_and_nothing_else():
    files = S.fingerprint_files()
    tops = {f.split("/")[0] for f in files}
    assert {"analytic", "engines", "scene", "measure.py"} <= tops
    assert not any(f.startswith(("cli", "report/", "testing/", "campaign")) for f in files)
    assert not any(f.startswith("studies/") and f != "studies/sensitivity.py" for f in files)
    assert "studies/sensitivity.py" in files         # the analytic band is physics
    assert {"verdict.py", "run_length.py"} <= set(files)   # a run's verdict and its length
    assert "plotting.py" not in files
    assert "scenarios/paper-plan.toml" not in files and "scenarios/cases.toml" not in files
    assert "scenarios/paper-asymmetric.toml" in files


def test_fingerprint_follows_a_physics_file(monkeypatch, tmp_path):
    """A changed physics file changes the fingerprint; a changed CLI file does not."""
    import shutil

    import rockbench

    root = tmp_path / "rockbench"
    shutil.copytree(__import__("pathlib").Path(rockbench.__file__).parent, root,
                    ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(rockbench, "__file__", str(root / "__init__.py"))

    def fp():
        S.code_fingerprint.cache_clear()
        return S.code_fingerprint()

    try:
        base = fp()
        for rel in ("cli/main.py", "studies/advise.py", "campaign/run.py"):
            (root / rel).write_text((root / rel).read_text() + "\n# help text edited\n")
            assert fp() == base, rel
        (root / "measure.py").write_text((root / "measure.py").read_text() + "\n# physics\n")
        assert fp() != base
    finally:
        S.code_fingerprint.cache_clear()
