"""``transient run`` never loses what a run computed and never writes through a planted link:
a partial result left by a killed run is refused without ``--force``; the temporary and probe
names are created exclusively; a result name that is a folder is a one-line error."""
from __future__ import annotations

import os

import h5py
from scene_texts import SMALL

from transient.cli import main


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def scene(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text(SMALL, encoding="utf-8")
    return path


def test_a_kept_partial_result_is_refused_without_force(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    part = out / ".small.h5.part"
    part.write_bytes(b"what a killed run computed")
    code, stdout, err = run(capsys, "run", scene(tmp_path), "-o", out, "-q")
    assert code == 2 and stdout == "" and err.count("\n") == 1
    assert str(part) in err and "--force" in err and "interrupted" in err
    assert part.read_bytes() == b"what a killed run computed"
    assert not (out / "small.h5").exists()
    code, _, err = run(capsys, "run", scene(tmp_path), "-o", out, "-q", "--force")
    assert code == 0, err
    assert not part.exists()
    with h5py.File(out / "small.h5", "r") as f:
        assert bool(f.attrs["complete"]) is True


def test_links_planted_at_the_temporary_names_are_not_followed(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    victims = {}
    for name in (".small.h5.part", ".small.h5.probe"):
        victim = tmp_path / f"victim{name}"
        victim.write_bytes(b"not yours")
        os.symlink(victim, out / name)
        victims[name] = victim
    # A link at the partial name is a partial result: refused without --force, even dangling.
    code, _, err = run(capsys, "run", scene(tmp_path), "-o", out, "-q")
    assert code == 2 and ".small.h5.part" in err
    code, _, err = run(capsys, "run", scene(tmp_path), "-o", out, "-q", "--force")
    assert code == 0, err
    for victim in victims.values():
        assert victim.read_bytes() == b"not yours"
    assert not os.path.lexists(out / ".small.h5.part")
    assert not os.path.lexists(out / ".small.h5.probe")
    assert (out / "small.h5").is_file() and not (out / "small.h5").is_symlink()


def test_a_dangling_link_at_the_partial_name_counts_as_a_partial_result(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    os.symlink(tmp_path / "nowhere", out / ".small.h5.part")
    code, _, err = run(capsys, "run", scene(tmp_path), "-o", out, "-q")
    assert code == 2 and ".small.h5.part" in err and "--force" in err
    assert not (tmp_path / "nowhere").exists()


def test_a_result_name_that_is_a_folder_is_refused_before_any_work(tmp_path, capsys):
    out = tmp_path / "out"
    (out / "small.h5").mkdir(parents=True)
    for extra in ((), ("--force",)):
        code, stdout, err = run(capsys, "run", scene(tmp_path), "-o", out, "-q", *extra)
        assert code == 2 and stdout == "" and err.count("\n") == 1, err
        assert "small.h5" in err and "is a folder" in err and "Traceback" not in err
    assert not os.path.lexists(out / ".small.h5.part")


def test_every_file_writing_command_refuses_to_replace_without_force(tmp_path, capsys):
    """plot, kinematics: a second run into the same names is one line, exit 2, the first files
    untouched; with --force they are written again."""
    out = tmp_path / "out"
    assert run(capsys, "run", scene(tmp_path), "-o", out, "-q")[0] == 0
    result = out / "small.h5"
    commands = {
        "plot": (["plot", result, "-o", out], out / "small_speed.png"),
        "kinematics": (["kinematics", scene(tmp_path), "-o", out / "k.csv", "--plot",
                        out / "k.png"], out / "k.csv"),
    }
    for name, (argv, first_file) in commands.items():
        assert run(capsys, *argv)[0] == 0, name
        stamp = first_file.read_bytes()
        code, stdout, err = run(capsys, *argv)
        assert code == 2 and err.count("\n") == 1 and "--force" in err, (name, err)
        assert first_file.read_bytes() == stamp
        assert run(capsys, *argv, "--force")[0] == 0, name


def test_a_link_planted_at_an_output_name_is_not_followed(tmp_path, capsys):
    victim = tmp_path / "victim.csv"
    victim.write_text("not yours")
    os.symlink(victim, tmp_path / "k.csv")
    code, _, err = run(capsys, "kinematics", scene(tmp_path), "-o", tmp_path / "k.csv")
    assert code == 2 and "--force" in err
    assert run(capsys, "kinematics", scene(tmp_path), "-o", tmp_path / "k.csv", "--force")[0] == 0
    assert victim.read_text() == "not yours"
    assert not (tmp_path / "k.csv").is_symlink()


def test_option_values_that_would_do_nothing_or_run_forever_are_refused(tmp_path, capsys):
    for argv, key in ((["kinematics", scene(tmp_path), "--points", "-5"], "--points"),
                      (["efficiency", scene(tmp_path), "--rpm", "inf"], "--rpm"),
                      (["efficiency", scene(tmp_path), "--rpm", "nan"], "--rpm")):
        code, stdout, err = run(capsys, *argv)
        assert code == 2 and stdout == "" and err.count("\n") == 1 and key in err, (argv, err)


def test_bench_and_stress_refuse_to_replace_a_record_before_any_work(tmp_path, capsys):
    """A benchmark or stress run into a folder that holds a record refuses at once (one line,
    exit 2) unless --force: a long run never ends by replacing a record unasked."""
    for argv, name in ((["bench", "--quick"], "work_precision.csv"),
                       (["bench", "--quick"], "targets.md"),
                       (["stress", "--quick"], "stress.md")):
        out = tmp_path / name
        out.mkdir()
        (out / name).write_text("the record")
        code, stdout, err = run(capsys, *argv, "-o", out)
        assert code == 2 and stdout == "" and err.count("\n") == 1, (argv, err)
        assert name in err and "--force" in err
        assert (out / name).read_text() == "the record"
        assert sorted(p.name for p in out.iterdir()) == [name]  # nothing else written
