"""The README's Python example runs as printed and says what the README claims."""

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_example_runs_as_printed(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)             # the example writes its figure where it runs
    text = README.read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "the README has no Python example"
    code = blocks[0]
    assert len(code.strip().splitlines()) <= 12
    exec(compile(code, str(README), "exec"), {})
    out = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in out] == ["analytic", "pymunk"]
    peaks = [float(re.search(r"max\|phi\|/alpha = ([0-9.]+)", line).group(1)) for line in out]
    assert abs(peaks[1] / peaks[0] - 1) < 0.03        # the engine within 3 % of the theory
    assert (tmp_path / "histories.png").stat().st_size > 10_000    # rb.plot_history drew it
