"""Explicit Runge–Kutta pairs for the compiled stepper, as data (docs/theory.md, Steppers).

A :class:`Tableau` holds what :mod:`transient.core.integrator.rk` needs of an embedded pair with
dense output, so that one compiled loop serves every method:

* ``A`` (n_ext × n_ext): the stage coefficients, the main stages ``0 … n_stages − 1``, the FSAL
  stage ``n_stages`` (the derivative at the new state) and any extra stages of the dense output;
* ``B`` (n_stages): the propagated solution's weights;
* ``E5``, ``E3`` (n_stages + 1): error estimators. The norm is Hairer's DOP853 blend
  ``err5²/√(err5² + 0.01·err3²)``; with ``E3 = 0`` it is the ordinary RMS norm of ``E5``;
* ``D`` (rows × n_ext): the dense output's higher rows. The interpolant of a step from y with
  Δy = y_new − y is ``y + θ(F0 + (1−θ)(F1 + θ(F2 + (1−θ)(F3 + θ(F4 + …)))))`` with
  ``F0 = Δy``, ``F1 = h f0 − Δy``, ``F2 = 2Δy − h(f0 + f1)`` and ``F(3+r) = h Σ_s D[r, s] K_s``:
  the form of Hairer's DOP853 and DOPRI5 codes (``CONTD8``, ``CONTD5``);
* ``exponent``: 1/(q + 1) for an error estimator of order q (the step-size control);
* ``stiff_bound``: the bound on the estimate hλ of Hairer's stiffness test (*Solving ODEs II*,
  §IV.2). ``dop853.f`` tests 6.1 and ``dopri5.f`` 3.25, the edges of the stability regions on
  the negative real axis; but the error estimators already hold the step below them: on a PI
  governor with a 2 µs actuator lag (λ ≈ −1/(τ_A ω) ≈ −1190 /rad) DOP853 settles at hλ = 5.17
  (measured with ``rk.stiffness``, which then equals h/(τ_A ω) to 4 digits), and 6.1 never fires.
  Hence 4.0 and, in the same ratio, 2.5 for DOPRI5 (on the same scene at rtol 1e-8 DOPRI5's
  step was still limited by accuracy, at hλ = 0.875). No scene in ``cases/`` trips the test
  with either pair (scanned with every case at its own tolerance).

DOP853: Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.10 (coefficients in
:mod:`.dop853_coefficients`). DOPRI5: Dormand & Prince (1980), *J. Comput. Appl. Math.* 6, 19–26,
with Shampine's 4th-order dense output as in Hairer's ``dopri5.f`` (the ``D`` row) and SciPy's
``RK45`` (``A``, ``B``, ``E``).
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np

from . import dop853_coefficients as dc
from .rosenbrock import WTableau, ros34pw2

Tableau = namedtuple("Tableau", ["A", "B", "E5", "E3", "D", "n_stages", "n_ext", "exponent",
                                 "order", "stiff_bound"])


def _dop853() -> Tableau:
    return Tableau(A=dc.A.copy(), B=dc.B.copy(), E5=dc.E5.copy(), E3=dc.E3.copy(), D=dc.D.copy(),
                   n_stages=dc.N_STAGES, n_ext=dc.N_STAGES_EXTENDED, exponent=1.0 / 8.0, order=8,
                   stiff_bound=4.0)


def _dopri5() -> Tableau:
    n_stages, n_ext = 6, 7
    A = np.zeros((n_ext, n_ext))
    A[1, :1] = [1 / 5]
    A[2, :2] = [3 / 40, 9 / 40]
    A[3, :3] = [44 / 45, -56 / 15, 32 / 9]
    A[4, :4] = [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729]
    A[5, :5] = [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656]
    B = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84])
    A[6, :6] = B  # the FSAL stage: f at the new state
    # 5th- minus 4th-order solution (Hairer's E1 … E7, sign irrelevant to the norm)
    E5 = np.array([71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40])
    D = np.array([[-12715105075 / 11282082432, 0.0, 87487479700 / 32700410799,
                   -10690763975 / 1880347072, 701980252875 / 199316789632,
                   -1453857185 / 822651844, 69997945 / 29380423]])
    return Tableau(A=A, B=B, E5=E5, E3=np.zeros(n_stages + 1), D=D, n_stages=n_stages,
                   n_ext=n_ext, exponent=1.0 / 5.0, order=5, stiff_bound=2.5)


#: The compiled methods by name (``solver.method`` in a scene): the explicit pairs, and the
#: Rosenbrock–W method for stiff shaft lines (:mod:`.rosenbrock`).
TABLEAUS: dict[str, Tableau | WTableau] = {"dop853": _dop853(), "dopri5": _dopri5(),
                                           "ros34pw2": ros34pw2()}
