"""``transient stress --quick`` end to end (the CI run of the stress suite): every case
passes or is a written-up known failure, and the report lists every case with its numbers."""
from __future__ import annotations

import pytest

from transient.cli import main
from transient.verify.stress import catalogue


@pytest.mark.slow
@pytest.mark.stress
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


def test_the_ladder_rule_catches_a_rise_and_ignores_the_floor():
    """``tolerance-ladder``'s monotonicity rule: a rise fails it, unless it is above the rtol
    the rule starts from or below the reference's noise floor."""
    from transient.verify.stress import LADDER_FLOOR, _falls

    rtols = [1e-3, 1e-4, 1e-5, 1e-6]
    assert _falls(rtols, [1e-3, 1e-4, 1e-5, 1e-6])
    assert not _falls(rtols, [1e-3, 2e-3, 1e-5, 1e-6])
    assert _falls(rtols, [1e-3, 2e-3, 1e-5, 1e-6], below=1e-4)
    assert not _falls(rtols, [1e-3, 2e-3, 1e-5, 2e-5], below=1e-4)
    assert _falls(rtols, [1e-3, 1e-4, LADDER_FLOOR / 2, LADDER_FLOOR])
