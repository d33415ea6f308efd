"""The README's example runs as written: its ```python blocks, in order, in one namespace."""

import re
import subprocess
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


ROOT_README = Path(__file__).resolve().parents[2] / "README.md"


def test_the_load_it_python_recipe_runs_and_matches_host_export(host_bin, tmp_path, monkeypatch):
    """The root README's "Load it" section as written: its `host` lines up to the PX4 export,
    then its ```python block; the file Python writes is the file `host export` wrote."""
    section = ROOT_README.read_text().split("## Load it", 1)[1].split("\n## ", 1)[0]
    lines = [l[len("host "):] for l in section.splitlines() if l.startswith("host ")]
    px4 = next(i for i, l in enumerate(lines) if "--format px4" in l)
    for line in lines[: px4 + 1]:
        p = subprocess.run([str(host_bin), *line.split()], cwd=tmp_path, capture_output=True, text=True)
        assert p.returncode == 0, f"host {line}: {p.stderr}"
    code = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    assert len(code) == 1, code
    monkeypatch.chdir(tmp_path)
    exec(compile(code[0], str(ROOT_README), "exec"), {})
    assert (tmp_path / "px4-from-python.params").read_text() == (tmp_path / "px4.params").read_text()
