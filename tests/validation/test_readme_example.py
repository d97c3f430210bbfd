"""The Python of the documentation runs as printed: the README's example, *Getting started* and
every page of the user guide (``docs/guide/*.md``). Each page's ```python blocks are executed in
order, in one namespace, in a fresh folder holding only the scenes they read (``cases/…``); a
result file they read (``results/<stem>.h5``) is made first from the scene of the same stem, as
``transient run cases/<stem>.toml -o results`` makes it."""
import re
import shutil
from pathlib import Path

import pytest

import transient

ROOT = Path(__file__).resolve().parents[2]
GUIDE = ROOT / "docs" / "guide"


def python_blocks(page: Path) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", page.read_text(encoding="utf-8"),
                      flags=re.S | re.M)


def run_blocks(page: Path, folder: Path, monkeypatch) -> dict:
    """Execute ``page``'s Python blocks in ``folder`` as described above; their namespace."""
    monkeypatch.chdir(folder)
    namespace = {"__name__": "__main__"}  # (as a script runs them: the sweep's guard holds)
    for code in python_blocks(page):
        for path in sorted(set(re.findall(r'"(cases/[^"]+\.toml)"', code))):
            (folder / path).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(ROOT / path, folder / path)
        for path in sorted(set(re.findall(r'"(results/[^"/]+\.h5)"', code))):
            if not (folder / path).exists():
                scene = transient.load_scene(ROOT / "cases" / f"{Path(path).stem}.toml")
                (folder / "results").mkdir(exist_ok=True)
                transient.simulate(scene, folder / path)
        exec(compile(code, str(page.relative_to(ROOT)), "exec"), namespace)
    return namespace


def test_readme_python_example_runs(tmp_path, monkeypatch, capsys):
    assert len(python_blocks(ROOT / "README.md")) == 1, "the README has one Python example"
    run_blocks(ROOT / "README.md", tmp_path, monkeypatch)
    printed = capsys.readouterr().out
    assert "rad/s" in printed and "δ of the last cycle" in printed
    res = transient.open_result(tmp_path / "spinup.h5")
    assert res.complete
    assert res.trajectory["omega"][-1] > res.trajectory["omega"][0]


def test_getting_started_python_runs(tmp_path, monkeypatch, capsys):
    page = ROOT / "docs" / "getting_started.md"
    assert python_blocks(page), "Getting started has Python"
    run_blocks(page, tmp_path, monkeypatch)
    first, second = capsys.readouterr().out.splitlines()[:2]
    assert first.startswith("finished rad/s ") and float(second) > 0.0


#: The user guide's pages that hold Python (found, not listed: a page that gains a block is run).
GUIDE_PAGES = sorted(p.name for p in GUIDE.glob("*.md") if python_blocks(p))


def test_the_guide_pages_with_python_are_found():
    assert {"mechanisms.md", "results.md", "sweeps.md"} <= set(GUIDE_PAGES)


@pytest.mark.parametrize("name", GUIDE_PAGES)
def test_user_guide_python_runs(name, tmp_path, monkeypatch, capsys):
    """Each page's blocks run without error; what they compute is what the page says."""
    ns = run_blocks(GUIDE / name, tmp_path, monkeypatch)
    printed = capsys.readouterr().out
    if name == "mechanisms.md":
        scene = transient.load_scene(ROOT / "cases" / "radial_5cyl.toml")
        assert ns["geometry"] == scene.geometry()
        stated = re.search(r"# ([0-9.]+)… rad", (GUIDE / name).read_text(encoding="utf-8"))
        assert f"{ns['value']:.9f}".startswith(stated.group(1))  # the page's comment holds
        assert printed.startswith(f"slave 3: TDC {ns['value']:.4f} rad after its bank")
    elif name == "results.md":
        assert ns["res"].complete and ns["df"].shape[0] == ns["res"].trajectory["t"].size
    elif name == "sweeps.md":
        assert list(ns["df"]["status"]) == ["finished"] * 3
        assert ns["first"].status == "finished"
