"""Scene and table files are read defensively: a folder, a FIFO or a device given as a scene or
a pressure table is a one-line error saying what it is (a FIFO would be read forever), and TOML
nested too deeply to read is one line, not a RecursionError."""
from __future__ import annotations

import os

import pytest
from scene_texts import SMALL

from transient.cli import main
from transient.errors import SceneError
from transient.scene import load_scene


def one_line_error(capsys, *argv) -> str:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.mark.parametrize("kind", ["a folder", "a FIFO", "a character device"])
def test_a_scene_that_is_not_a_regular_file(tmp_path, capsys, kind):
    path = tmp_path / "scene.toml"
    if kind == "a folder":
        path.mkdir()
    elif kind == "a FIFO":
        os.mkfifo(path)
    else:
        path = "/dev/zero"
    err = one_line_error(capsys, "check", path)
    assert f"is {kind}, not a scene file" in err and str(path) in err


def test_a_pressure_table_that_is_a_fifo(tmp_path, capsys):
    os.mkfifo(tmp_path / "p.csv")
    scene = tmp_path / "s.toml"
    scene.write_text(SMALL + '\n[gas]\nmodel = "table"\nfile = "p.csv"\n', encoding="utf-8")
    err = one_line_error(capsys, "check", scene)
    assert "gas.file" in err and "is a FIFO, not a CSV file" in err


def test_toml_nested_too_deeply(tmp_path):
    path = tmp_path / "deep.toml"
    path.write_text("a = " + "[" * 100_000 + "]" * 100_000 + "\n", encoding="utf-8")
    with pytest.raises(SceneError, match="nested too deeply"):
        load_scene(path)
