"""The README's example runs as written: its ```python blocks, in order, in one namespace."""

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def blocks():
    return re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)


def test_the_readme_example_runs(tmp_path, monkeypatch, capsys):
    found = blocks()
    assert len(found) >= 5
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    for code in found:
        exec(compile(code, str(README), "exec"), namespace)
    out = capsys.readouterr().out
    assert "CAL_ACC0_XOFF" in out
    assert (tmp_path / "calibration" / "calibration.toml").exists()
    # At rest the compensated specific force is 1 g (the simulated unit is about 1 % off uncalibrated).
    f = float(re.search(r"\|f\| at rest: ([0-9.]+) g", out).group(1))
    assert abs(f - 1.0) < 2e-3, f
