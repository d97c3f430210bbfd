"""What each scene key means, in a line: the key reference (:mod:`.keyref`) shows it beside what
the reader asks of the key (its unit, default and bounds are the reader's, not restated here).
Table → key → meaning, in reST inline markup; the keys of the ``[mechanism]`` tables are the
mechanisms' own (``key_meanings`` of each), which read them. The records' docstrings
(:mod:`.records`) hold the equations behind them."""
from __future__ import annotations

MEANINGS: dict[str, dict[str, str]] = {
    "": {
        "scene": "Its name and description.",
        "mechanism": "The mechanism: its type, geometry and masses.",
        "inertia": "Constant inertias on the shaft.",
        "gas": "The gas forces: the cylinder pressure model, per-cylinder variation, injection.",
        "load": "The load on the shaft: torques, a generator, a map, a schedule, a clutched "
                "inertia.",
        "starter": "A starter motor that turns the shaft until it reaches its cut-out speed.",
        "governor": "A speed governor setting the fuel command.",
        "initial": "The shaft's angle and speed at the start.",
        "run": "What is run and when it ends, and the budgets that bound it.",
        "solver": "How the equation of motion is integrated.",
        "output": "How densely the trajectory is sampled.",
        "friction": "Non-ideal kinematic pairs and how their modes are chosen.",
        "analysis": "Results derived after the run, stored only when asked for.",
        "shaft": "The elastic shaft line: stations, sections, dampers and the coupling to a "
                 "driven inertia (absent: a rigid shaft).",
    },
    "shaft": {
        "stations": "The stations of the line, in order from the front end "
                    "(``[[shaft.stations]]``).",
        "sections": "The shaft sections between consecutive stations, one fewer than the "
                    "stations (``[[shaft.sections]]``).",
        "dampers": "Torsional vibration dampers, each a ring on a station's hub "
                   "(``[[shaft.dampers]]``).",
        "coupling": "An elastic coupling, a gear and the driven inertia beyond the last station "
                    "(``[shaft.coupling]``).",
        "reference": "The station whose angle is the run's crank angle.",
        "load_at": "Where the load acts: a station's name, or ``driven`` (the driven inertia).",
        "speed_range": "Lowest and highest speed whose critical speeds ``transient modes`` "
                       "lists.",
    },
    "shaft.stations[]": {
        "name": "Names the station (unique): the modes table and the dampers refer to it.",
        "inertia": "The station's own constant inertia (pulley, hub, webs and counterweights, "
                   "flywheel); its cylinders' reduced inertia comes on top.",
        "damping": "Absolute damping of the station, on its motion relative to the line's "
                   "rigid-body motion (never a drag on the whole rotation).",
        "cylinders": "The cylinders (1-based) whose crankpin the station carries; empty for a "
                     "pulley or flywheel.",
    },
    "shaft.sections[]": {
        "stiffness": "Torsional stiffness of the section.",
        "length": "Length of a round shaft section (without ``stiffness``).",
        "diameter": "Outer diameter of a round shaft section.",
        "bore": "Inner diameter of a hollow section; k = Gπ(d⁴ − d_i⁴)/(32 L).",
        "shear_modulus": "Shear modulus G of the section's material.",
        "damping": "Relative (section) damping coefficient between its two stations.",
        "loss_factor": "Loss factor η: viscous c = η·k/ω₁ at the line's first natural "
                       "frequency.",
        "damping_ratio": "Damping ratio ζ: viscous c = 2ζ·k/ω₁ at the line's first natural "
                         "frequency.",
    },
    "shaft.dampers[]": {
        "station": "The station whose hub carries the damper.",
        "model": "``viscous`` (a ring in silicone: inertia and damping) or ``tuned`` (a "
                 "rubber-sprung ring: also a stiffness).",
        "inertia": "Moment of inertia of the damper's ring.",
        "damping": "Damping coefficient between ring and hub.",
        "stiffness": "Stiffness between ring and hub (``tuned``).",
    },
    "shaft.coupling": {
        "stiffness": "Torsional stiffness of the elastic coupling, at shaft speed.",
        "damping": "Damping coefficient of the coupling.",
        "gear_ratio": "Gear ratio i = n_driven / n_shaft beyond the coupling; the driven "
                      "inertia is i²·J_d at the shaft.",
        "driven_inertia": "Moment of inertia J_d of the driven machine, at its own speed.",
    },
    "scene": {
        "name": "Names the result: labels its file, figures and terminal lines.",
        "description": "Free text, kept with the result.",
    },
    "mechanism": {
        "type": "The mechanism; it selects which keys this table takes (below, one table per "
                "type).",
    },
    "inertia": {
        "shaft": "Moment of inertia of the shaft with what turns rigidly with it.",
        "flywheel": "Moment of inertia of the flywheel.",
        "load": "Moment of inertia of the driven machine, coupled rigidly.",
    },
    "gas": {
        "model": "The cylinder pressure model: none, an indicator diagram (``table``), the mixed "
                 "cycle, a force pulse (``trapezoid``), Wiebe combustion or a compressor.",
        "p0": "Crankcase pressure p₀: the piston force is (p − p₀)·piston area.",
        "n": "Polytropic exponent of the compression.",
        "p_suction": "Suction pressure p_s.",
        "p_discharge": "Discharge pressure p_d.",
        "n_reexpansion": "Polytropic exponent of the re-expansion of the clearance gas.",
        "clearance_ratio": "Clearance volume over swept volume, V_c/V_s; small enough that the "
                           "clearance gas re-expands to p_suction before the bottom dead centre "
                           "(else the compressor delivers nothing).",
        "cylinders": "Per-cylinder departures (``[[gas.cylinders]]``): fuel and pressure "
                     "factors, cut-out, misfires, combustion offset.",
        "p_intake": "Constant pressure of the intake stroke (four-strokes only; a two-stroke "
                    "refuses it).",
        "p_exhaust": "Constant pressure of the exhaust stroke (four-strokes only; a two-stroke "
                     "refuses it).",
        "compression_ratio": "Compression ratio ε = (V_s + V_c)/V_c.",
        "p_a": "Pressure at the start of compression (mixed cycle) or at intake closing "
               "(Wiebe).",
        "n1": "Polytropic exponent of the compression.",
        "p_z": "Peak pressure of the cycle.",
        "rho": "Pre-expansion ratio ρ: volume at the end of combustion over the clearance "
               "volume.",
        "n2": "Polytropic exponent of the expansion.",
        "injection": "Start of injection, a local angle as the tables': each cylinder takes the "
                     "governor's command there and burns it until its next one.",
        "wiebe": "The Wiebe combustion (``[gas.wiebe]``).",
        "woschni": "Wall heat transfer by Woschni's correlation (``[gas.woschni]``); the "
                   "crank-slider only.",
        "amplitude": "Peak force of the pulse on each piston.",
        "ramp": "Rise (and fall) of the pulse.",
        "duration": "Length of the pulse, ramps included.",
        "phi": "Local angles of the table over one cycle (four-stroke: 0 at the gas-exchange "
               "TDC; two-stroke: 0 at the firing TDC).",
        "force": "Force on each piston at each angle, applied as it is (no piston area, no "
                 "p₀); instead of ``p``.",
        "p": "Absolute cylinder pressure at each angle.",
        "motored_p": "Motored pressure at each angle (no combustion): needed for a fuel below "
                     "1 (governor, fuel factors, misfires).",
        "corners": "Angles where the curve may jump or kink, between samples too; each is a "
                   "breakpoint of the integration.",
        "interpolation": "How the table is interpolated between its angles.",
        "file": "CSV file (relative to the scene) with an angle column (``phi``, ``phi_deg``) "
                "and a pressure (``p``, ``p_bar``, ``p_MPa``, ``p_Pa``) or force column "
                "(``force``, ``force_N``, ``force_kN``), optionally ``motored_p…``.",
    },
    "gas.cylinders[]": {
        "cylinder": "The cylinder this entry is for.",
        "fuel": "Fuel factor φ_k, multiplying the governor's command for this cylinder.",
        "pressure": "Pressure factor β_k on its pressure above p₀ (a leaking cylinder, an "
                    "indicator's calibration).",
        "cut_out": "No fuel in any cycle: it follows the motored curve (not with ``fuel``).",
        "misfire_cycles": "Cycles that misfire (1: the one in progress at the start).",
        "combustion_offset": "Shift δ_k of its combustion: later if positive, earlier if "
                             "negative; the compression stays with the piston.",
        "misfire_every": "Cycles n, 2n, 3n, … misfire (0: none).",
        "misfire_rate": "Probability that a cycle misfires, drawn from ``misfire_seed``.",
        "misfire_seed": "Seed of the misfire draws: the same misfires for the same seed, "
                        "cylinder and cycle on every run and machine.",
    },
    "gas.wiebe": {
        "start": "Start of combustion, a local angle (four-stroke: 360° is the firing TDC).",
        "duration": "Duration of combustion.",
        "fuel_mass": "Fuel burned per cycle and cylinder at full load (fuel 1); 0 runs the "
                     "engine motored.",
        "a": "Wiebe efficiency parameter (6.908 burns 99.9 %).",
        "m": "Wiebe shape exponent.",
        "lhv": "Lower heating value of the fuel.",
        "efficiency": "Combustion efficiency η_c: the share of m_f·LHV released.",
        "gamma": "Ratio of specific heats γ at ``gamma_t_ref``.",
        "gamma_slope": "dγ/dT (0: a constant γ, for which part load is exact).",
        "gamma_t_ref": "Temperature at which γ = ``gamma``.",
        "t_a": "Gas temperature at intake closing.",
        "intake_closing": "Intake closing: start of the closed part of the cycle.",
        "exhaust_opening": "Exhaust opening: end of the closed part of the cycle.",
        "step": "Largest knot spacing of the pressure tables.",
        "tolerance": "Target relative error of the pressure tables.",
    },
    "gas.woschni": {
        "c1": "Woschni's C₁, multiplying the mean piston speed.",
        "c2": "Woschni's C₂, multiplying the pressure rise combustion causes (direct "
              "injection by default).",
        "wall_temperature": "Mean temperature of head, piston crown and liner.",
    },
    "load": {
        "torque": "Constant load torque: > 0 resists the rotation, < 0 drives it.",
        "linear": "Load torque per shaft speed, ``linear``·ω (resisting).",
        "fan": "Fan-law load torque, ``fan``·ω\\|ω\\| (resisting).",
        "generator_power": "Electrical power P drawn by a generator: torque P/ω (resisting).",
        "generator_min_speed": "Below this speed the generator's torque is held at "
                               "P/ω_min (finite at rest).",
        "schedule_time": "Times of the load schedule's points (not with "
                         "``schedule_revolutions``).",
        "schedule_revolutions": "Shaft revolutions from the start of the load schedule's "
                                "points (not with ``schedule_time``).",
        "schedule_scale": "Scale of every load at each schedule point; piecewise linear, two "
                          "equal abscissae are a step.",
        "inertia": "Inertia of a load at rest that a clutch couples to the shaft at "
                   "``inertia_time``.",
        "inertia_time": "When the clutch couples ``inertia`` (angular momentum is conserved).",
        "table": "A load torque from data (``[load.table]``).",
    },
    "load.table": {
        "interpolation": "How the torque is interpolated between the points.",
        "speed": "Shaft speeds of the points (a generator's, propeller's or fan's map).",
        "phi": "Shaft angles of the points within one engine cycle (a valve train's torque; "
               "periodic).",
        "time": "Times of the points (a measured trace).",
        "torque": "Load torque at each point, signed as ``[load] torque``.",
        "file": "CSV file (relative to the scene) with one abscissa column (``speed``, "
                "``speed_rpm``, ``phi``, ``phi_deg``, ``time``) and ``torque``.",
    },
    "starter": {
        "torque": "Stall torque of the starter: its torque is ``torque``·(1 − ω/"
                  "``noload_speed``).",
        "noload_speed": "Speed at which the starter's torque falls to 0.",
        "cutout_speed": "Speed at which the starter disengages, for the rest of the run.",
    },
    "governor": {
        "model": "The governor: none, a static droop characteristic, an isochronous PI(D) or "
                 "a centrifugal flyweight governor.",
        "speed_full": "Full fuel up to this speed, then falling linearly.",
        "speed_zero": "No fuel from this speed on.",
        "fuel_min": "Smallest fuel command (the rack's stop).",
        "fuel_max": "Largest fuel command (the rack's stop).",
        "gain_p": "Proportional gain K_p per unit relative speed error.",
        "gain_i": "Integral gain K_i per unit relative speed error.",
        "speed": "Speed ω_ref the governor holds.",
        "gain_d": "Derivative gain K_d (0: none).",
        "derivative_time": "Filter time constant τ_D of the derivative term.",
        "actuator_time": "Lag τ_A with which the rack follows the demand.",
        "rate_limit": "Largest rate of the rack (0: none).",
        "anti_windup": "Back-calculation anti-windup of the integrator.",
        "tracking_time": "Tracking time T_t of the anti-windup (0: K_p/K_i).",
        "fuel_initial": "Rack and integrator at the start.",
        "weights": "Number of flyweights n_w.",
        "weight_mass": "Mass m_w of each flyweight.",
        "radius": "Radius ρ₀ of the flyweights with the sleeve on its low stop.",
        "arm_ratio": "Bell-crank ratio a/b.",
        "gear_ratio": "Governor speed over shaft speed, i_g.",
        "sleeve_mass": "Mass of the sleeve and what moves with it.",
        "spring_rate": "Stiffness k of the governor spring.",
        "spring_preload": "Preload F₀ of the spring on the low stop.",
        "damping": "Viscous damping c of the sleeve.",
        "travel": "Sleeve travel z_max from the low stop (full fuel) to the high stop (no "
                  "fuel).",
    },
    "initial": {
        "phi": "Shaft angle at the start.",
        "omega": "Shaft speed at the start.",
    },
    "run": {
        "mode": "``dynamic``: integrate the equation of motion; ``prescribed-speed``: the "
                "shaft follows a given speed (inverse dynamics).",
        "t_end": "End time of the run (with ``revolutions``: whichever comes first).",
        "revolutions": "Revolutions of the shaft after which the run ends.",
        "max_output_bytes": "Most bytes the trajectory and the analyses may write (8 a value "
                            "before compression); a larger run is refused before it starts.",
        "max_steps": "Most step attempts the run may take; a run whose limits imply more is "
                     "refused before it starts.",
        "speed": "Constant speed of a prescribed-speed run.",
        "time": "Times of the prescribed speed table.",
        "speed_table": "Speeds at ``time``.",
        "interpolation": "How the speed table is interpolated: ``linear`` follows its corners "
                         "exactly, ``pchip`` is C¹ and never overshoots.",
    },
    "solver": {
        "method": "Integration method: compiled (``dop853``, ``dopri5``) or the reference "
                  "path (``scipy-*``).",
        "rtol": "Relative error tolerance, as scipy's; a dynamic run needs ≥ 100 ε = "
                "2.2 × 10⁻¹⁴, what double precision can deliver.",
        "atol": "Absolute error tolerance, as scipy's, in the units of each state.",
        "switch_speed": "Below this speed time is the independent variable, above it the "
                        "crank angle.",
        "max_step": "Largest step in crank angle.",
        "domain": "``auto``: crank angle above ``switch_speed``; ``time``: time throughout.",
        "fixed_step": "Fixed crank-angle step of the compiled methods, without error control "
                      "(0: adaptive).",
        "kinematics": "``exact``: the mechanism at every evaluation; ``tabulated``: periodic "
                      "splines of J(φ) and the transfer functions.",
        "table_tolerance": "Relative error the tabulated kinematics keep (0: 0.01·``rtol``).",
        "multirevolution": "``transient run`` follows the run on its cycle map's envelope, "
                           "macro steps over many cycles (a whole number of cycles).",
        "envelope_rtol": "Relative tolerance of the multirevolution envelope.",
    },
    "output": {
        "samples_per_rev": "Trajectory samples per revolution (in crank angle).",
        "dt": "Time between samples while the run steps in time (0: the angle spacing at "
              "1.5 × ``switch_speed``).",
    },
    "friction": {
        "policy": "How each pair's mode (which side drives) is chosen: by the power it "
                  "transmits, or by the paper's criterion (25).",
        "pairs": "The non-ideal pairs (``[[friction.pairs]]``).",
    },
    "friction.pairs[]": {
        "model": "``constant-eta``: constant efficiencies; ``reaction``: friction on the "
                 "joint's reaction; ``table``: efficiency maps.",
        "between": "The two links the pair joins, the shaft side first (the mechanism's links "
                   "or, for reaction pairs, its joints).",
        "name": "Labels the pair's result columns and reports.",
        "eta_forward": "Efficiency η_ba while the shaft side drives (a ``table`` pair: one row "
                       "per speed of one value per torque).",
        "eta_backward": "Efficiency η_ab while the far side drives (a ``table`` pair: one row "
                        "per speed of one value per torque).",
        "file": "CSV file of the maps (relative to the scene), one row per grid point: "
                "``speed_rpm`` or ``speed``, ``torque``, ``eta_forward``, ``eta_backward``.",
        "mu": "Friction coefficient μ (journal: friction circle μ·r·\\|R\\|; piston: μ·\\|N\\| "
              "on the side force).",
        "radius": "Radius r of the journal, pin or bearing.",
        "viscous": "Viscous friction: of a journal on its relative angular speed [N m s/rad], "
                   "of the piston on its speed [N s/m].",
        "ring_force": "Friction force of the piston rings' tension (the piston pair).",
        "ring_pressure": "Ring friction from the gas pressure behind the rings, as a share of "
                         "the gas force (the piston pair), c_p = 4 μ_ring h/D.",
        "speed": "Speed axis \\|ω\\| of the maps, increasing.",
        "torque": "Moment axis \\|S\\| of the maps, increasing.",
    },
    "analysis": {
        "loads": "Forces, pin and journal loads and torques over the last cycle.",
        "orders": "Signals whose order spectrum is stored per cycle: trajectory columns "
                  "(``omega``, ``M_gas``, ``p_1`` …) or ``W_<k>``, the piston acceleration of "
                  "cylinder k.",
        "irregularity": "The cyclic irregularity δ and mean speed of every cycle.",
        "thermodynamics": "Per cylinder and cycle: indicated work, IMEP, BMEP, FMEP, powers, "
                          "peak pressures; heat release for Wiebe combustion.",
        "max_order": "Orders stored up to this one.",
        "samples_per_cycle": "Crank-angle grid of the analyses per engine cycle.",
        "detrend": "What is done to ω before each cycle's spectrum: ``auto`` (the ramp of a "
                   "spin-up, else none), ``ramp`` or ``none``.",
    },
}
