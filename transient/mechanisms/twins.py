"""Plain-Python twins of the mechanisms' compiled kernels, for the reference path
(:mod:`transient.reference`), which must not share the compiled code it checks: each gives
J(φ), dJ/dφ and the piston transfer functions u_k(φ) and their derivatives at one shaft angle.
"""
from __future__ import annotations

import numpy as np

from ..core.model import crank_slider as cs


class CrankSliderNumpy:
    """J(φ), dJ/dφ and the piston transfer functions of a crank-slider, in plain numpy, written
    out again from the Gots relations (exact piston velocity v = rω sin(φ + β)/cos β,
    Gots §1.2) rather than taken from the kernel."""

    def __init__(self, mech) -> None:
        self.mech = mech
        mp = mech.pack()
        self.r, self.l, self.e = mech.crank_radius, mech.rod_length, mech.offset
        self.m_slide = mp[cs.M_PISTON] + mp[cs.M_PIN]
        self.m_rot = mp[cs.M_CRANKPIN] + mp[cs.M_CRANK]
        self.m_rod, self.f_cg, self.I_rod = mp[cs.M_ROD], mp[cs.ROD_CG] / self.l, mp[cs.I_ROD]
        self.phases = np.asarray(mech.firing_angles)

    def terms(self, phi: float):
        """(J, dJ, u[k], u′[k]) at shaft angle φ, all cylinders."""
        J, dJ, u, du = self._per_cylinder(phi)
        return np.sum(J), np.sum(dJ), u, du

    def cylinder_terms(self, phi: float):
        """(J_k, dJ_k/dφ) of each cylinder k at shaft angle φ: its share of J(φ)."""
        J, dJ, _, _ = self._per_cylinder(phi)
        return J, dJ

    def _per_cylinder(self, phi: float):
        a = phi - self.phases
        r, l = self.r, self.l
        beta = np.arcsin((r * np.sin(a) - self.e) / l)
        cb = np.cos(beta)
        # Gots §1.2: piston velocity over ω, and its derivative (quotient rule).
        db = r * np.cos(a) / (l * cb)
        u = r * np.sin(a + beta) / cb
        du = r * (np.cos(a + beta) * (1 + db) * cb + np.sin(a + beta) * np.sin(beta) * db) / cb**2
        ddb = (l * np.sin(beta) * db**2 - r * np.sin(a)) / (l * cb)
        # Rod centre of mass: G = B + f (A − B); A on the crank circle, B on the cylinder axis.
        f = self.f_cg
        g1 = np.array([f * r * np.cos(a), -(1 - f) * u - f * r * np.sin(a)])
        g2 = np.array([-f * r * np.sin(a), -(1 - f) * du - f * r * np.cos(a)])
        J = (self.m_slide * u**2 + self.m_rot * r**2 + self.m_rod * np.sum(g1**2, axis=0)
             + self.I_rod * db**2)
        dJ = 2 * (self.m_slide * u * du + self.m_rod * np.sum(g1 * g2, axis=0)
                  + self.I_rod * db * ddb)
        return J, dJ, u, du


class KernelTwin:
    """A mechanism without a numpy twin runs its kernel's pure-Python code (``.py_func``): the
    same arithmetic as the compiled kernel, but not numba's compilation of it."""

    def __init__(self, mech, terms) -> None:
        self.mp = mech.pack()
        self.fn = terms.py_func
        self.u = np.empty(mech.n_cylinders)
        self.du = np.empty(mech.n_cylinders)

    def terms(self, phi):
        """(J, dJ, u[k], u′[k]) at shaft angle φ, all cylinders."""
        J, dJ = self.fn(self.mp, phi, self.u, self.du)
        return J, dJ, self.u.copy(), self.du.copy()
