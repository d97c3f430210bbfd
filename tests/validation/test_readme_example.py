"""The README's Python example, and the Python of the documentation's *Getting started*, run as
printed: each ```python block is executed in a fresh folder holding only the scenes it reads."""
import re
import shutil
from pathlib import Path

import transient

ROOT = Path(__file__).resolve().parents[2]


def readme_example() -> str:
    blocks = re.findall(r"^```python\n(.*?)^```", (ROOT / "README.md").read_text(encoding="utf-8"),
                        flags=re.S | re.M)
    assert len(blocks) == 1, "the README has one Python example"
    return blocks[0]


def test_readme_python_example_runs(tmp_path, monkeypatch, capsys):
    code = readme_example()
    for path in sorted(set(re.findall(r'"(cases/[^"]+\.toml)"', code))):
        (tmp_path / path).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / path, tmp_path / path)
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {"__name__": "readme"})
    printed = capsys.readouterr().out
    assert "rad/s" in printed and "δ of the last cycle" in printed
    res = transient.open_result(tmp_path / "spinup.h5")
    assert res.complete
    assert res.trajectory["omega"][-1] > res.trajectory["omega"][0]


def test_getting_started_python_runs(tmp_path, monkeypatch, capsys):
    text = (ROOT / "docs" / "getting_started.md").read_text(encoding="utf-8")
    blocks = re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)
    assert blocks, "Getting started has Python"
    monkeypatch.chdir(tmp_path)
    for code in blocks:
        for path in sorted(set(re.findall(r'"(cases/[^"]+\.toml)"', code))):
            (tmp_path / path).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(ROOT / path, tmp_path / path)
        exec(compile(code, "getting_started.md", "exec"), {"__name__": "getting_started"})
    first, second = capsys.readouterr().out.splitlines()[:2]
    assert first.startswith("finished rad/s ") and float(second) > 0.0
