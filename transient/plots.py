"""Plot helpers: each takes an ``ax`` and returns the artists; callers make and save figures."""
from __future__ import annotations

import math

import numpy as np


def speed(ax, traj, label=None):
    """ω(t) [rpm]."""
    artists = ax.plot(traj["t"], traj["omega"] * 30.0 / math.pi, lw=1.0, label=label)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("ω [rpm]")
    ax.grid(True, alpha=0.3)
    return artists


def acceleration(ax, traj, label=None):
    """ε(t) [rad/s²]."""
    artists = ax.plot(traj["t"], traj["epsilon"], lw=0.6, label=label)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("ε [rad/s²]")
    ax.grid(True, alpha=0.3)
    return artists


def last_cycle(traj, cycle):
    """Boolean mask of the samples in the last whole cycle of crank angle."""
    phi = traj["phi"]
    return phi >= phi[-1] - cycle


def torques(ax, traj, cycle):
    """Moments over the last cycle against the crank angle in that cycle [deg]."""
    sel = last_cycle(traj, cycle)
    phi = np.degrees(traj["phi"][sel] - traj["phi"][sel][0])
    inertia = -0.5 * traj["dJ_dphi"][sel] * traj["omega"][sel] ** 2
    series = {"gas": traj["M_gas"][sel], "load": traj["M_load"][sel],
              "inertia −½J′ω²": inertia}
    if np.any(traj["M_starter"][sel]):
        series["starter"] = traj["M_starter"][sel]
    if "M_drive" in traj:
        series["drive (required)"] = traj["M_drive"][sel]
    artists = [ax.plot(phi, v, lw=1.0, label=k)[0] for k, v in series.items()]
    ax.set_xlabel("crank angle in the last cycle [deg]")
    ax.set_ylabel("M [N m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return artists


def indicator_phi(ax, table):
    """Indicator diagram p(φ) over the local cycle angle [deg], absolute pressure [MPa]."""
    x = np.linspace(0.0, table.period, 2881)
    artists = ax.plot(np.degrees(x), table(x) / 1e6, lw=1.0)
    for c in table.corners[1:-1]:
        ax.axvline(math.degrees(c), color="0.8", lw=0.5)
    ax.set_xlabel("local crank angle [deg]")
    ax.set_ylabel("p [MPa]")
    ax.grid(True, alpha=0.3)
    return artists


def indicator_pv(ax, table, volume, log=True):
    """Indicator diagram p(V), V [dm³], p [MPa]; log-log unless ``log`` is False."""
    x = np.linspace(0.0, table.period, 2881)
    plot = ax.loglog if log else ax.plot
    artists = plot(volume(x) * 1e3, table(x) / 1e6, lw=1.0)
    ax.set_xlabel("V [dm³]")
    ax.set_ylabel("p [MPa]")
    ax.grid(True, which="both", alpha=0.3)
    return artists
