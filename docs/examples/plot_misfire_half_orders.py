"""
A weak cylinder, a misfire and the half orders of the speed
===========================================================

A balanced four-cylinder 4-stroke fires every 180°: its speed holds the orders 2, 4, 6 … only.
In ``cases/diesel_4cyl_misfire.toml`` cylinder 2 gets 80 % of the fuel and cylinder 3 misfires
in every tenth of its cycles (``[[gas.cylinders]]``). Each cycle's order spectrum of ω then holds
the half orders ½, 1, 1½ …, larger in the cycles of a misfire. Linearised about the mean speed,
J̄·ω̄·dω/dφ = ΔM(φ), so a gas-torque component M_q of order q makes a speed component
ω_q = M_q/(J̄·ω̄·q): the dots are that estimate, from each cycle's gas torque.

A fuel factor or a misfire scales the combustion only: a misfiring cylinder still compresses and
expands, on the mixed cycle's motored curve (the compression polytrope both ways, peaking at
p_c = p_a·ε^n1 = 7.488 MPa), and the weak cylinder burns 80 % of the heat at every angle
(peaking at p_c + 0.8·(p_z − p_c)). The second figure shows both against the full-load and
motored curves. What the orders see is the missing combustion, not a missing compression.
"""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import MaxNLocator

import transient
from transient.analysis.orders import order_spectrum, to_angle_grid
from transient.analysis.thermo import own_cycles
from transient.plots import run_indicator_phi
from transient.scene.queries import gas_tables

CASES = Path(transient.__file__).resolve().parents[1] / "cases"
scene = transient.load_scene(CASES / "diesel_4cyl_misfire.toml")
print(scene.gas.cylinders)
result = transient.simulate(scene)
df = result.to_dataframe()
traj = {c: df[c].to_numpy() for c in ("t", "phi", "omega", "epsilon", "M_gas", "J")}

n, cycle = 720, scene.mechanism.cycle
_, grid = to_angle_grid(traj, ("omega", "M_gas", "J"), n, cycle, closed=True)
w = grid["omega"]
speed = order_spectrum(w[:-1], n, cycle, detrend="ramp", end=w[-1])
torque = order_spectrum(grid["M_gas"][:-1], n, cycle)
w_mean = w[:-1].reshape(-1, n).mean(axis=1)
J_mean = grid["J"].mean()

last = slice(-20, None)  # the last twenty cycles: the pattern repeats every ten
cycles = np.arange(speed.coef.shape[0])[last] + 1
fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
for index, colour in ((1, "C0"), (3, "C1")):
    q = speed.orders[index]
    amplitude = np.abs(speed.coef[last, index])
    estimate = np.abs(torque.coef[last, index]) / (J_mean * w_mean[last] * q)
    ax.plot(cycles, amplitude, "-", color=colour, label=f"order {q:g}: run")
    ax.plot(cycles, estimate, "o", color=colour, mfc="none",
            label=f"order {q:g}: M_q/(J̄ ω̄ q)")
    print(f"order {q:g}: largest relative difference "
          f"{np.max(np.abs(amplitude / estimate - 1)):.3f}")
print(f"order 2 (firing), last cycle: {abs(speed.coef[-1, 4]):.2f} rad/s")
ax.set_xlabel("engine cycle")
ax.xaxis.set_major_locator(MaxNLocator(integer=True))
ax.set_ylabel("amplitude of ω [rad/s]")
ax.grid(True, alpha=0.3)
ax.legend()
ax.set_title("Half orders of the speed\n"
             "cylinder 2 at 80 % fuel, cylinder 3 misfires every 10th cycle", fontsize=10)
plt.show()

# %%
# The last two whole cycles of cylinder 3 (its cycle 100 misfires) and the last of cylinder 2,
# against their own crank angle around the firing TDC (360°).
full, motored = gas_tables(scene)
fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
run_indicator_phi(ax, result, scene, cylinders=[3], cycles=(-2, -1), table=full,
                  motored=motored)
run_indicator_phi(ax, result, scene, cylinders=[2], cycles=(-1,))
ax.set_xlim(270, 480)
ax.set_title("A misfire on the motored curve,\n80 % fuel between it and full load", fontsize=10)
phi = df["phi"].to_numpy()
for k, c in ((3, -2), (3, -1), (2, -1)):
    a = own_cycles(scene, result.trajectory, k)[c]
    inside = (phi >= a) & (phi < a + cycle)
    print(f"cylinder {k}, its cycle from φ = {np.degrees(a):.0f}°: peak "
          f"{df[f'p_{k}'].to_numpy()[inside].max() / 1e6:.3f} MPa")
print(f"motored compression end p_c = {motored(2 * np.pi)[()] / 1e6:.3f} MPa")
plt.show()
