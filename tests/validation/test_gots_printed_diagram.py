"""Mean indicated torque from the book's printed indicator diagram П2.1 (Gots App. 2, §2.9).

The printed pressure column is not one consistent curve (data README), yet its loop carries about
p_e-level work: rebuilt with intake 0.165 MPa (0–180°), the printed points 180–540° (linear between
them) and exhaust 0.182 MPa (540–720°), three cylinders at 4400 rpm give a mean torque of about
151.7 N m (an independent 0.25° rebuild, not in the book), against 205.77 N m from the ideal
polytropes of the same cycle (cases/gots_diesel_4400.toml). That is why the book compares its
"dynamic" 149.1 N m with M_e = 153.05 N m and not with M_i = 193.8 N m. The mean of −M_drive over a
cycle (inverse dynamics, inertia included) must equal 3·∮p dV/(4π) of the same table: inertia does
no net work per cycle. The comparisons are ``tests/references/gots.py``'s
:func:`printed_diagram_torque`.
"""
from __future__ import annotations

from references import check_all, gots


def test_mean_torque_of_the_printed_diagram():
    check_all(gots.printed_diagram_torque())
