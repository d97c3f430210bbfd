"""Every piston's travel and its derivatives in the shaft angle, for any mechanism: what the
cylinder volumes (:mod:`.thermo`) and the piston accelerations W = ω²s″ + εs′
(:mod:`transient.analysis.orders`, Semenov §4) are made of.

s_k(φ) is the travel of cylinder k's piston from its top (for a swash plate: inner) dead centre
toward the crank axis [m], s′_k = ds_k/dφ [m/rad], s″_k [m/rad²], from each mechanism's exact
kinematics: the crank-slider by Gots (1) vectorised
(:func:`~transient.analysis.loads.crank_slider.slider_arrays`), the articulated rows and the
swash plate by their kinematics tables (the compiled kernel's transfer functions, so that the
travel is the one the run's forces act along).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..mechanisms import PluginTable, needed


@dataclass(frozen=True)
class Pistons:
    """Piston kinematics of every cylinder at the angles asked for.

    Attributes
    ----------
    s, ds, dds : (n, m) arrays
        Travel [m] from the cylinder's own dead centre toward the crank axis, and its first and
        second derivatives in the shaft angle [m/rad, m/rad²].
    area : (n,) array
        Area the cylinder's pressure acts on [m²]: F_p, or 2F_p for the opposed pistons of a
        two-half swash plate (both bound the one volume).
    stroke : (n,) array
        Exact stroke of each piston [m].
    """

    s: NDArray[np.float64]
    ds: NDArray[np.float64]
    dds: NDArray[np.float64]
    area: NDArray[np.float64]
    stroke: NDArray[np.float64]


def _crank_slider(mech, phi):
    from .loads.crank_slider import slider_arrays

    rows = [slider_arrays(phi - phase, mech.crank_radius, mech.rod_length, mech.offset)[:3]
            for phase in mech.firing_angles]
    s, ds, dds = (np.array([r[i] for r in rows]) for i in range(3))
    n = mech.n_cylinders
    return s, ds, dds, np.full(n, mech.piston_area), np.full(n, mech.stroke())


def _articulated(mech, phi):
    from ..mechanisms.articulated import piston_strokes

    tab = mech.kinematics_table(phi)
    n = mech.n_cylinders
    s, ds, dds = (np.array([tab[f"{c}_{k + 1}"] for k in range(n)]) for c in ("s", "u", "du"))
    return s, ds, dds, np.full(n, mech.piston_area), np.tile(piston_strokes(mech), mech.rows)


def _swash_plate(mech, phi):
    from ..mechanisms.swash_plate import dead_centres, kinematics_table, stroke

    tab = kinematics_table(mech, phi)
    inner = kinematics_table(mech, np.asarray(dead_centres(mech)[0], dtype=float))
    n = mech.n_cylinders
    # x of cylinder k's piston joint from its value at the cylinder's inner dead centre
    s = np.array([tab[f"x_{k + 1}"] - inner[f"x_{k + 1}"][k] for k in range(n)])
    ds, dds = (np.array([tab[f"{c}_{k + 1}"] for k in range(n)]) for c in ("u", "du"))
    return s, ds, dds, np.full(n, mech.halves * mech.piston_area), stroke(mech)


#: Per mechanism name (capability ``"pistons"``): (mechanism, φ (m,)) → s, s′, s″ (n, m), area (n,), stroke (n,).
#: A mechanism's own module of :mod:`transient.analysis.loads` may hold it as
#: ``piston_travel``.
KINEMATICS = PluginTable({"crank-slider": _crank_slider, "articulated": _articulated,
                          "swash-plate": _swash_plate},
                         "transient.analysis.loads.{}", "piston_travel")


def piston_kinematics(mech, phi: ArrayLike) -> Pistons:
    """:class:`Pistons` of ``mech`` at the shaft angles ``phi`` [rad] (capability
    ``"pistons"``, which every mechanism has: :class:`~transient.mechanisms.MissingCapability`
    for one without it)."""
    law = needed(mech, "pistons", KINEMATICS)
    phi = np.atleast_1d(np.asarray(phi, dtype=float))
    return Pistons(*law(mech, phi))


def cylinder_torques(scene, traj) -> NDArray[np.float64]:
    """Each cylinder's gas torque on the shaft at the samples of ``traj`` (``phi`` and
    ``p_<k>``), (n, samples) [N m]: (p_k − p0)·A_k·s′_k for a pressure, the force times s′_k
    (both pistons of a two-half swash plate) for a force model; their sum is ``M_gas``."""
    from ..scene.queries import gas_is_force

    mech = scene.mechanism
    pk = piston_kinematics(mech, np.asarray(traj["phi"], dtype=float))
    p = np.array([np.asarray(traj[f"p_{k + 1}"], dtype=float) for k in range(mech.n_cylinders)])
    if gas_is_force(scene):
        return p * pk.ds * (pk.area / mech.piston_area)[:, None]
    return (p - scene.gas.p0) * pk.ds * pk.area[:, None]
