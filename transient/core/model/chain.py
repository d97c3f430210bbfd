r"""The serial chain of rigid sub-chains joined by non-ideal pairs (Antonyuk §3, (18), (22)–(29)).

A one-DOF machine is cut at its n non-ideal pairs into sub-chains k = 0 … n; pair k joins
sub-chain k (shaft side, k = 0 holds the shaft) and k + 1. Everything is reduced to the shaft
angle φ (ω = φ̇): sub-chain k has the reduced inertia J_k(φ) ≥ 0, J′_k = dJ_k/dφ and the
generalized force M_k of its applied moments and forces (19)–(21).

Sign conventions
----------------
Pair k takes the generalized moment S_k out of side k (side k feels −S_k) and delivers
S′_k = η*_k S_k to side k + 1, both per unit φ̇, so S_k ω is the power side k sends into the
pair and S′_k ω the power side k + 1 receives. η*_k is (25)'s η*: η_fwd,k when side k drives
(forward mode), 1/η_bwd,k when side k + 1 drives (backward mode); 0 < η ≤ 1.

In the paper's coordinates of one pair (a = side 0, b = side 1, u = u_ba = φ̇_b/φ̇_a), the reaction
on a is M_ba = −S_0 and the reaction on b, as a moment in b's own coordinate, is
M_ab = S′_0/u = η* S_0/u; hence M_ab u = −η* M_ba, the power relation (23)–(24).

Derivation (virtual power per sub-chain)
----------------------------------------
With R_k = M_k − ½ J′_k ω² and a = φ̈, the sub-chains obey (S_{−1} = S_n = 0)

    J_k a = R_k + η*_{k−1} S_{k−1} − S_k,        k = 0 … n.

Solving the first n equations forward, S_k = R_k − J_k a + η*_{k−1} S_{k−1}, i.e.

    S_k = (1/c_k) Σ_{j≤k} c_j (R_j − J_j a),     c_j = Π_{i<j} 1/η*_i   (c_0 = 1),

because Π_{i=j}^{k−1} η*_i = c_j/c_k. The last equation is "S_n = 0", which gives the
acceleration explicitly:

    φ̈ = Σ_j c_j (M_j − ½ J′_j ω²) / Σ_j c_j J_j.

All η* = 1 is (18) with J = Σ J_k, M = Σ M_k; one pair (c_1 = 1/η*) is (22) multiplied out; two
pairs are (27)–(28) with I_np = Σ c_j J_j, M_np = Σ c_j M_j and A = Σ c_j ½J′_j, which carries
the inertia factors the printed A lacks (a misprint in (28): the printed A lacks (I_b + I_c) on
its first term and I_d on its second, so it is not an inertia). Summing the sub-chain equations
times ω,

    Σ_k (J_k φ̈ + ½ J′_k ω²) ω = Σ_k M_k ω − Σ_k (1 − η*_k) S_k ω,

so the loss in pair k is (1 − η*_k) S_k ω, ≥ 0 whenever the mode agrees with the sign of S_k ω.
The reactions (29) follow from the same S_k: M_ba = −S_0 = (I_a/I_np)(M_np − A ω²) − M_a (the
printed + A ω² in (29) is a sign misprint, found by re-deriving from a's own equation and (27)).

Mode selection
--------------
``paper`` (:func:`modes_paper`): criterion (25), M_a φ̇_a ≥ 0 → forward, generalized to a chain
by taking for M_a the moment of everything on the shaft side of pair k reduced ideally to φ,
Σ_{j≤k} M_j. It looks at the applied moments only, not at the power actually transmitted, so
when inertia dominates it can pick a mode whose loss is negative (a gap in (25) as printed: it
uses the sign of the external moment's power on a, not of the power flowing through the pair).

``power-flow`` (:func:`modes_power_flow`): the mode of pair k must agree with the power it
transmits — forward requires S_k ω ≥ 0, backward S_k ω < 0. Equivalently S′_k = g_k(S_k) with

    g_k(S) = η_fwd,k S  if S ω ≥ 0,    S/η_bwd,k  if S ω < 0,

a continuous, strictly increasing function (both slopes positive). *Claim: for ω ≠ 0 a serial
chain has exactly one power-flow-consistent solution; self-braking (none) and ambiguity (several)
cannot occur.* Proof: for a trial a, the forward recursion S_0 = R_0 − J_0 a,
S_k = R_k − J_k a + g_{k−1}(S_{k−1}) makes every S_k a continuous, piecewise-linear,
non-increasing function of a, and the residual of the last sub-chain
F(a) = R_n − J_n a + g_{n−1}(S_{n−1}(a)) has slope −Σ_j J_j Π_{i=j}^{n−1} g′_i ≤
−min_j(Π g′) Σ_j J_j < 0. So F has exactly one root; a, then every S_k, then (where S_k ≠ 0) every
mode is unique, and a pair with S_k = 0 transmits nothing, so either of its modes gives the same a
and S (φ̈ is continuous across a power-flow switch: no chattering). For one pair this is explicit:

    S_0 = D / (η* J_0 + J_1),    D = J_1 R_0 − J_0 R_1,

D independent of the mode and η* J_0 + J_1 > 0, so sign S_0 = sign D for both candidates.

The kernel still enumerates the 2ⁿ candidate mode vectors (n ≤ :data:`MAX_PAIRS`) and counts the
consistent ones, because in floating point a tie S_k ≈ 0 can give 0 or 2 consistent candidates.
Rule: several consistent → the one with the lowest bit mask (bit k set = pair k backward, so
forward is preferred, matching the ≥ of the criterion); none → the one with the smallest total
violation Σ_k max(0, ∓S_k ω). By the continuity above, both choices change φ̈ only by rounding.

At rest (ω = 0) the power is zero and the criterion is applied to the incipient motion instead:
with σ = ±1 the trial direction, solve the chain with g_k built from σ in place of ω, obtaining
a_σ. Since η ≤ 1 makes g_k for σ = +1 never larger than for σ = −1, a_+ ≤ a_−: if a_+ > 0 the chain
starts forward, if a_− < 0 backward, and if a_+ ≤ 0 ≤ a_− the friction of the pairs holds the
applied moments — the chain is *locked* (:data:`LOCKED`), φ̈ = 0. This is the locking case "losses
exceed the applied torque": for one pair, locking means the static reaction ratio
S′_0/S_0 = −M_1/M_0 lies in [η_fwd, 1/η_bwd]. Since the sub-chains share the single coordinate φ,
locking is global. When locked, S_out[0] = M_0 (statics of sub-chain 0); for n = 1 also
S′_0 = −M_1; for n ≥ 2 the interior reactions are statically indeterminate and S_out[1:] is NaN.
A self-locking pair (η_bwd ≤ 0, the paper's ξ_ba regime) is outside this model.

All kernels take plain float64 arrays; shapes: J, dJ, M: (n + 1,); ``eta_*``, S_out: (n,).
"""
from __future__ import annotations

import numpy as np

from ..jit import compiled, kernel

#: Largest number of pairs :func:`modes_power_flow` enumerates (2ⁿ candidates).
MAX_PAIRS = 6

#: Status codes of :func:`modes_power_flow`.
UNIQUE, AMBIGUOUS, NONE_CONSISTENT, LOCKED = 0, 1, 2, 3


@kernel(inline=True)
def eta_star(eta_fwd, eta_bwd, forward):
    """η* of (25): η_fwd when the shaft side drives (``forward``), else 1/η_bwd."""
    if forward:
        return eta_fwd
    return 1.0 / eta_bwd


@kernel(inline=True)
def chain_solve(J, dJ, M, eta_s, w, S_out):
    """φ̈ of the serial chain for given modes; fills the pair moments S_k.

    Parameters
    ----------
    J, dJ, M : float64[n + 1]
        Reduced inertia, its φ-derivative and generalized force of each sub-chain; Σ J_k > 0.
    eta_s : float64[n]
        η*_k of each pair (see :func:`eta_star`).
    w : float
        Shaft speed φ̇.
    S_out : float64[n]
        Filled with S_k, the moment pair k takes out of side k (side k + 1 receives η*_k S_k).

    Returns
    -------
    float
        φ̈ = Σ c_j (M_j − ½J′_j ω²) / Σ c_j J_j, c_j = Π_{i<j} 1/η*_i (module docstring).
    """
    n = eta_s.shape[0]
    half_w2 = 0.5 * w * w
    c = 1.0
    num = M[0] - dJ[0] * half_w2
    den = J[0]
    for j in range(1, n + 1):
        c /= eta_s[j - 1]
        num += c * (M[j] - dJ[j] * half_w2)
        den += c * J[j]
    a = num / den
    # The forward recursion is the sub-chain equations themselves, so S_k satisfies them to rounding.
    prev = 0.0
    for k in range(n):
        s = M[k] - dJ[k] * half_w2 - J[k] * a + prev
        S_out[k] = s
        prev = eta_s[k] * s
    if n > 0 and J[n] == 0.0 and dJ[n] == 0.0:
        # A last sub-chain without inertia (the cylinders, loaded by the gas alone) is in
        # balance with the pair before it: that pair carries its moment exactly, zero where the
        # gas force is, rather than the rounding left of the recursion's long sum.
        S_out[n - 1] = -M[n] / eta_s[n - 1]
    return a


@kernel
def pair_losses(eta_s, S, w, out):
    """Power lost in each pair, (1 − η*_k) S_k ω [W]; fills ``out`` (float64[n])."""
    for k in range(eta_s.shape[0]):
        out[k] = (1.0 - eta_s[k]) * S[k] * w


@kernel
def modes_paper(M, eta_fwd, eta_bwd, w, eta_out):
    """η* of every pair by criterion (25) generalized to a chain (module docstring).

    Pair k is forward when (Σ_{j≤k} M_j) ω ≥ 0, i.e. the moments on its shaft side deliver power.
    Fills ``eta_out`` (float64[n]).
    """
    upstream = 0.0
    for k in range(eta_out.shape[0]):
        upstream += M[k]
        eta_out[k] = eta_star(eta_fwd[k], eta_bwd[k], upstream * w >= 0.0)


@kernel(inline=True)
def _copy(dst, src):
    """dst[:] = src, as a loop (an array assignment needs reference counting, ``core.jit``)."""
    for i in range(src.shape[0]):
        dst[i] = src[i]


@kernel
def _best_candidate(J, dJ, M, eta_fwd, eta_bwd, w, sigma, eta_out, S_out, eta_try, S_try):
    """Enumerate the 2ⁿ modes against direction ``sigma``; keep the chosen one in eta_out/S_out.

    Returns ``(phi_ddot, n_consistent)``; the choice follows the rule of the module docstring.
    """
    n = eta_fwd.shape[0]
    n_ok = 0
    best_viol = np.inf
    a_best = np.nan
    for mask in range(1 << n):
        for k in range(n):
            eta_try[k] = eta_star(eta_fwd[k], eta_bwd[k], ((mask >> k) & 1) == 0)
        a = chain_solve(J, dJ, M, eta_try, w, S_try)
        viol = 0.0
        ok = True
        for k in range(n):
            p = S_try[k] * sigma
            if (mask >> k) & 1:
                viol += max(0.0, p)  # backward needs S_k σ < 0
                ok = ok and p < 0.0
            else:
                viol += max(0.0, -p)  # forward needs S_k σ ≥ 0
                ok = ok and p >= 0.0
        if ok:
            n_ok += 1
            if n_ok == 1:
                best_viol = -1.0  # a consistent candidate beats every inconsistent one
                a_best = a
                _copy(eta_out, eta_try)
                _copy(S_out, S_try)
        elif n_ok == 0 and viol < best_viol:
            best_viol = viol
            a_best = a
            _copy(eta_out, eta_try)
            _copy(S_out, S_try)
    return a_best, n_ok


@compiled
def modes_power_flow(J, dJ, M, eta_fwd, eta_bwd, w, eta_out, S_out):
    """:func:`modes_power_flow_into` with scratch space of its own (for callers outside the
    compiled loop)."""
    return modes_power_flow_into(J, dJ, M, eta_fwd, eta_bwd, w, eta_out, S_out,
                                 np.empty((4, eta_fwd.shape[0])))


@kernel
def modes_power_flow_into(J, dJ, M, eta_fwd, eta_bwd, w, eta_out, S_out, scratch):
    """φ̈ with every pair in the mode consistent with the power it transmits.

    Parameters
    ----------
    J, dJ, M : float64[n + 1]
        As in :func:`chain_solve`.
    eta_fwd, eta_bwd : float64[n]
        Efficiencies with side k resp. side k + 1 driving, in (0, 1].
    w : float
        Shaft speed φ̇.
    eta_out, S_out : float64[n]
        Filled with the chosen η*_k and S_k (S_out[1:] NaN when locked with n ≥ 2).
    scratch : float64[4, n]
        Work space (a kernel allocates nothing, ``transient.core.jit``).

    Returns
    -------
    phi_ddot : float
    status : int
        :data:`UNIQUE`, :data:`AMBIGUOUS` (several consistent — a rounding tie at S_k ≈ 0),
        :data:`NONE_CONSISTENT` (none — a rounding tie; exact arithmetic never gives it for
        ω ≠ 0), or :data:`LOCKED` (ω = 0 and the pairs hold the applied moments: φ̈ = 0).
    n_consistent : int
        Number of consistent candidates (for ω = 0, in the direction that moves; 0 if locked).
    """
    n = eta_fwd.shape[0]
    eta_try, S_try, eta_b, S_b = scratch[0], scratch[1], scratch[2], scratch[3]
    if w != 0.0:
        sigma = 1.0 if w > 0.0 else -1.0
        a, n_ok = _best_candidate(J, dJ, M, eta_fwd, eta_bwd, w, sigma, eta_out, S_out,
                                  eta_try, S_try)
    else:
        a, n_ok = _best_candidate(J, dJ, M, eta_fwd, eta_bwd, w, 1.0, eta_out, S_out,
                                  eta_try, S_try)
        if not a > 0.0:
            a, n_ok = _best_candidate(J, dJ, M, eta_fwd, eta_bwd, w, -1.0, eta_b, S_b,
                                      eta_try, S_try)
            if a < 0.0:
                _copy(eta_out, eta_b)
                _copy(S_out, S_b)
            else:
                # Neither direction of incipient motion is consistent: static friction holds.
                for k in range(n):
                    eta_out[k] = np.nan
                    S_out[k] = np.nan
                if n >= 1:
                    S_out[0] = M[0]
                return 0.0, LOCKED, 0
    if n_ok == 1:
        return a, UNIQUE, n_ok
    if n_ok > 1:
        return a, AMBIGUOUS, n_ok
    return a, NONE_CONSISTENT, n_ok


@kernel
def one_pair_reactions(I_a, u_ba, eta_s, S0):
    """(M_ba, M_ab) of (26) in the paper's coordinates from S_0 (sign conventions above).

    M_ba = −S_0 acts on a; M_ab = η* S_0 / u_ba acts on b, in b's own coordinate.
    ``I_a`` is unused; kept so the call mirrors (26)'s parameter list.
    """
    return -S0, eta_s * S0 / u_ba


@kernel
def two_pair_reactions(u_ba, u_dc, eta_ba, eta_dc, S0, S1):
    """(M_ba, M_ab, M_dc, M_cd) of (29) re-derived, from S_0 and S_1.

    M_ba = −S_0 on a; M_ab = η*_ba S_0/u_ba on the rigid b + c (b's coordinate);
    M_dc = −S_1/u_ba on b + c (c's coordinate, c moving with b); M_cd = η*_dc S_1/(u_ba u_dc)
    on d (d's coordinate).
    """
    return -S0, eta_ba * S0 / u_ba, -S1 / u_ba, eta_dc * S1 / (u_ba * u_dc)
