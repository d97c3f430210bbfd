"""The swash-plate example through the whole stepper.

* Coasting conserves ½J(φ)ω² over 1000 revolutions at rtol 1e-10 (≤ 1e-8 relative), with the
  paper's masses: J(φ) of the example varies by about ±30 % (cross 13, link 9), so a wrong J′ in
  the work–energy form would show at once.
* The time to coast equals 1000·∫₀^{2π} √(J(φ)/(2K)) dφ (a quadrature of the kernel's J): the phase
  is integrated, not just the energy.
* Four cylinders run at least three times smoother than one in governed steady state
  (δ = (ω_max − ω_min)/ω_mean over the last turn), as the paper reports.

The comparisons are cases of ``tests/references`` (``closed_forms.py``, ``antonyuk.py``), which
the Validation page renders.
"""
from __future__ import annotations

from references import antonyuk, check_all, closed_forms


def test_coasting_conserves_kinetic_energy_and_phase():
    check_all(closed_forms.coasting_swash_plate())


def test_four_cylinders_are_at_least_three_times_smoother():
    check_all(antonyuk.four_cylinders_smoother())
