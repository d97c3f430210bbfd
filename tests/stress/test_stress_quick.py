"""``transient stress --quick`` end to end (the CI run of the stress suite, issue 9): every case
passes or is a written-up known failure, and the report lists every case with its numbers."""
from __future__ import annotations

from transient.cli import main
from transient.stress import catalogue


def test_stress_quick(tmp_path, capsys):
    code = main(["stress", "--quick", "-o", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0, out
    report = (tmp_path / "stress.md").read_text(encoding="utf-8")
    quick = [c for c in catalogue() if c.quick]
    rows = [line for line in report.splitlines() if line.startswith("| ") and
            not line.startswith("| case")]
    assert [r.split(" | ")[0][2:] for r in rows] == [c.name for c in quick]
    for case, row in zip(quick, rows):
        cells = row.split(" | ")
        assert cells[2] == "pass" or (case.known and cells[2] == "**known failure**"), row
    assert "**FAIL**" not in report
