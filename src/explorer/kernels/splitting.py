"""Symmetric composition (splitting) methods of orders 2, 4, 6 and 8.

Model-agnostic tables.  The physics splits ``H = H_0 + ... + H_{m-1}`` into
``m`` exactly solvable flows ``phi_k(t)``; this module only says *which* flow
to apply for *what fraction of the step* ``h``.

Basic method (Strang, order 2, symmetric)::

    S(h) = phi_0(h/2) phi_1(h/2) ... phi_{m-2}(h/2) phi_{m-1}(h)
           phi_{m-2}(h/2) ... phi_1(h/2) phi_0(h/2)

Higher orders are symmetric compositions ``Psi(h) = S(g_s h) ... S(g_1 h)``
with palindromic weights ``g`` (``g_i = g_{s+1-i}``, ``sum g = 1``).  Because
every sequence here is a palindrome, reading it left-to-right (operator
order) or right-to-left (application order) gives the same list; the arrays
returned by :func:`flow_sequence` are in application order.

Weights
-------
Every weight array below is float64, palindromic *exactly* (built by
mirroring one half), read-only, and exact to double precision:

* closed forms (triple jump, Suzuki fractal) are evaluated at import time in
  50-digit ``decimal`` arithmetic and rounded once to float64 (plain float64
  ``1/(2 - 2**(1/3))`` is one ulp off);
* Kahan & Li tables are the 26-digit values (as tabulated in SeLaLib
  ``src/time_integration/splitting_methods/sll_m_time_composition.F90``
  and choreo ``choreo/segm/precomputed_tables.py``; s9odr6a and s15odr8 agree
  with the independently typed 20-digit copies in REBOUND
  ``src/integrator_janus.c``);
* Yoshida's 1990 tables have only 15 digits and those digits do not satisfy
  the order conditions better than ~5e-14 (solution A) and ~3e-12 (solution
  D).  The values below are the same solutions refined by Newton's method on
  the order conditions (truncated BCH expansion in 80-digit decimal
  arithmetic; residual < 1e-70) and stored to 26 digits.  They differ from
  Yoshida's printed digits by <= 3e-15 (A) and <= 2.4e-13 (D), i.e. his last
  one to three digits were not converged.  The solution-A values agree with
  the 26-digit ones in SeLaLib ``sll_m_time_composition.F90`` (whose centre
  weight has a sign typo there) and the 34-digit ones in BeamTracking.jl
  (whose centre weight is 5e-17 off).  Solution D has large weights and is
  ill-conditioned: even its correctly rounded doubles leave order-condition
  residuals of ~6e-14 (harmless: they multiply h^3..h^7).

Verification: ``tests/kernels/test_splitting.py`` checks the order
conditions algebraically (truncated BCH in 50-digit decimal arithmetic on
the exact stored doubles: every residual is within what rounding the exact
weights to float64 can cause) and measures the observed order on a
three-way split of the free rigid body.

Dispatch
--------
``SCHEMES[name] = (weights, order, reference)``; the defaults per order are
``split2``, ``split4`` (Yoshida triple jump), ``split6`` (Kahan-Li s9odr6a),
``split8`` (Kahan-Li s15odr8).

This is a set-up time module (plain Python/numpy, called once per run); the
returned arrays are C-contiguous int64/float64 and can be passed straight to
njit kernels.
"""
from __future__ import annotations

from decimal import Decimal, localcontext

import numpy as np

__all__ = [
    "W_STRANG", "W_YOSHIDA4", "W_SUZUKI4", "W_KAHANLI6_S9", "W_YOSHIDA6A",
    "W_KAHANLI8_S15", "W_KAHANLI8_S17", "W_YOSHIDA8D", "SCHEMES",
    "DEFAULT_BY_ORDER", "flow_sequence", "fsal_lead_fraction",
]


def _palindrome(half):
    """Mirror ``half = [g_1, ..., g_c]`` (outermost ... centre) into the full
    palindrome ``[g_1, ..., g_c, ..., g_1]`` (odd length, exact mirror)."""
    h = np.asarray(half, dtype=np.float64)
    w = np.ascontiguousarray(np.concatenate([h, h[-2::-1]]))
    w.setflags(write=False)
    return w


def _closed_form(kind):
    """Float64 values (outer, centre) of the closed-form 4th-order weights,
    computed in 50-digit decimal arithmetic and rounded once."""
    with localcontext() as ctx:
        ctx.prec = 50
        if kind == "triple":        # g1 = 1/(2 - 2^(1/3)), g0 = 1 - 2 g1
            root = Decimal(2) ** (Decimal(1) / Decimal(3))
            outer = 1 / (2 - root)
            centre = 1 - 2 * outer
        elif kind == "suzuki":      # p = 1/(4 - 4^(1/3)), centre = 1 - 4 p
            root = Decimal(4) ** (Decimal(1) / Decimal(3))
            outer = 1 / (4 - root)
            centre = 1 - 4 * outer
        else:  # pragma: no cover
            raise ValueError(kind)
        return float(outer), float(centre)


# --- order 2 ---------------------------------------------------------------
W_STRANG = _palindrome([1.0])

# --- order 4 ---------------------------------------------------------------
_tj_outer, _tj_centre = _closed_form("triple")
#: Yoshida (1990) / Forest-Ruth / Suzuki triple jump, 3 stages.
W_YOSHIDA4 = _palindrome([_tj_outer, _tj_centre])

_sz_outer, _sz_centre = _closed_form("suzuki")
#: Suzuki (1990) fractal, 5 stages: [p, p, 1 - 4p, p, p].
W_SUZUKI4 = _palindrome([_sz_outer, _sz_outer, _sz_centre])

# --- order 6 ---------------------------------------------------------------
#: Kahan & Li (1997) s9odr6a, 9 stages (outermost ... centre).
W_KAHANLI6_S9 = _palindrome([
    0.39216144400731413927925056,
    0.33259913678935943859974864,
    -0.70624617255763935980996482,
    0.08221359629355080023149045,
    0.79854399093482996339895035,
])

#: Yoshida (1990) Table 1 solution A, 7 stages, Newton-refined (see above).
#: Published: w3 = 0.784513610477560, w2 = 0.235573213359357,
#: w1 = -1.17767998417887.
W_YOSHIDA6A = _palindrome([
    0.78451361047755726381949763,     # w3
    0.23557321335935813368479318,     # w2
    -1.17767998417887100694641568,    # w1
    1.31518632068391121888424973,     # w0 = 1 - 2 (w1 + w2 + w3)
])

# --- order 8 ---------------------------------------------------------------
#: Kahan & Li (1997) s15odr8, 15 stages (choreo labels the same digits
#: McLachlan 1995).
W_KAHANLI8_S15 = _palindrome([
    0.74167036435061295344822780,
    -0.40910082580003159399730010,
    0.19075471029623837995387626,
    -0.57386247111608226665638773,
    0.29906418130365592384446354,
    0.33462491824529818378495798,
    0.31529309239676659663205666,
    -0.79688793935291635401978884,
])

#: Kahan & Li (1997) s17odr8a, 17 stages (also listed in Hairer-Lubich-
#: Wanner 2006, Sec. V.3.2, p. 157); leading error coefficient ~10x smaller
#: than s15odr8.
W_KAHANLI8_S17 = _palindrome([
    0.13020248308889008087881763,
    0.56116298177510838456196441,
    -0.38947496264484728640807860,
    0.15884190655515560089621075,
    -0.39590389413323757733623154,
    0.18453964097831570709183254,
    0.25837438768632204729397911,
    0.29501172360931029887096624,
    -0.60550853383003451169892108,
])

#: Yoshida (1990) Table 2 solution D, 15 stages, Newton-refined (see above).
#: Published (w7 ... w1): 0.914844246229740, 0.253693336566229,
#: -1.44485223686048, -0.158240635368243, 1.93813913762276,
#: -1.96061023297549, 0.102799849391985.
W_YOSHIDA8D = _palindrome([
    0.91484424622979156674879349,     # w7
    0.25369333656621135414614602,     # w6
    -1.44485223686060515769473066,    # w5
    -0.15824063536805017520406678,    # w4
    1.93813913762252598657918649,     # w3
    -1.96061023297531080760763338,    # w2
    0.10279984939179644069811513,     # w1
    1.70845307078728158466837936,     # w0 = 1 - 2 (w1 + ... + w7)
])

_KL = "W. Kahan & R.-C. Li, Math. Comp. 66 (1997) 1089-1099, scheme "
_KL_DIGITS = ("26-digit values as tabulated in SeLaLib "
              "sll_m_time_composition.F90 and choreo segm/precomputed_tables"
              ".py (also Hairer-Lubich-Wanner, Geometric Numerical "
              "Integration, 2nd ed. 2006, Sec. V.3.2)")
_REBOUND = "agrees with the 20-digit REBOUND src/integrator_janus.c"
_YOSHIDA = "H. Yoshida, Phys. Lett. A 150 (1990) 262-268, "

SCHEMES = {
    "split2": (W_STRANG, 2,
               "G. Strang, SIAM J. Numer. Anal. 5 (1968) 506-517; symmetric "
               "(Strang) splitting, 1 stage"),
    "split4": (W_YOSHIDA4, 4,
               _YOSHIDA + "Sec. 4 triple jump g1 = 1/(2 - 2^(1/3)), "
               "g0 = 1 - 2 g1 (closed form), 3 stages"),
    "split4_suzuki": (W_SUZUKI4, 4,
                      "M. Suzuki, Phys. Lett. A 146 (1990) 319-323, fractal "
                      "p = 1/(4 - 4^(1/3)), centre 1 - 4p (closed form), "
                      "5 stages"),
    "split6": (W_KAHANLI6_S9, 6,
               _KL + "s9odr6a, 9 stages; " + _KL_DIGITS + "; " + _REBOUND),
    "split6_yoshida": (W_YOSHIDA6A, 6,
                       _YOSHIDA + "Table 1 solution A, 7 stages; "
                       "Newton-refined on the order conditions"),
    "split8": (W_KAHANLI8_S15, 8,
               _KL + "s15odr8, 15 stages (choreo attributes the same digits "
               "to R. I. McLachlan, SIAM J. Sci. Comput. 16 (1995) 151-168); "
               + _KL_DIGITS
               + "; " + _REBOUND),
    "split8_s17": (W_KAHANLI8_S17, 8,
                   _KL + "s17odr8a, 17 stages; " + _KL_DIGITS),
    "split8_yoshida": (W_YOSHIDA8D, 8,
                       _YOSHIDA + "Table 2 solution D, 15 stages; "
                       "Newton-refined on the order conditions"),
}

#: Default scheme name for each order.
DEFAULT_BY_ORDER = {2: "split2", 4: "split4", 6: "split6", 8: "split8"}


def _check(weights, n_flows):
    w = np.asarray(weights, dtype=np.float64)
    if w.ndim != 1 or w.size == 0 or not np.all(np.isfinite(w)):
        raise ValueError("weights must be a non-empty 1-D array of finite "
                         "floats")
    n = int(n_flows)
    if n != n_flows or n < 1:
        raise ValueError("n_flows must be a positive integer")
    return w, n


def flow_sequence(weights, n_flows, fsal=False):
    """Flattened sub-flow applications of one step of ``Psi(h)``.

    Parameters
    ----------
    weights : 1-D float array ``g`` (e.g. ``SCHEMES["split6"][0]``); the
        composition is ``S(g_s h) ... S(g_1 h)`` with ``S`` the Strang step
        over ``n_flows`` flows (flow 0 outermost with half steps, flow
        ``n_flows - 1`` in the middle with a full step).
    n_flows : number ``m >= 1`` of exactly solvable flows.
    fsal : see below.

    Returns
    -------
    (flow_ids, fractions) : C-contiguous ``int64`` and ``float64`` arrays of
    equal length, in application order.  Entry ``j`` means "apply
    ``phi_{flow_ids[j]}`` for time ``fractions[j] * h``".

    Contract (``fsal=False``)
    -------------------------
    * Stage ``i`` contributes ``phi_0(g_i/2) phi_1(g_i/2) ...
      phi_{m-2}(g_i/2) phi_{m-1}(g_i) phi_{m-2}(g_i/2) ... phi_0(g_i/2)``;
      stages are concatenated for ``i = 1 .. s``.
    * Adjacent applications of the same flow are merged into one whose
      fraction is the float64 sum, e.g. the trailing ``phi_0(g_i/2)`` and
      the leading ``phi_0(g_{i+1}/2)`` become ``phi_0((g_i + g_{i+1})/2)``.
      After merging no two consecutive entries have the same flow id.
      (Flows are exact, so ``phi_k(a) phi_k(b) = phi_k(a + b)``.)
      Nothing else is dropped or reordered; a merged fraction that happens
      to be 0.0 is kept.
    * For every flow ``k`` the fractions with ``flow_ids == k`` sum to
      ``sum(g) = 1`` up to rounding.  For ``m >= 2`` the sequence starts and
      ends with flow 0 (fraction ``g_1/2`` and ``g_s/2``) and has length
      ``s (2m - 2) + 1``; for ``m == 1`` it is the single entry
      ``(0, sum(g))``.
    * A palindromic ``g`` gives a palindromic sequence, so one step with
      ``h`` followed by one with ``-h`` is the identity (up to rounding).

    Contract (``fsal=True``, requires ``n_flows >= 2``)
    ---------------------------------------------------
    First-same-as-last: the leading ``phi_0(g_1 h/2)`` of each step is
    carried by the previous step.  The returned sequence is the
    ``fsal=False`` one with its first entry removed and its last entry
    ``phi_0(g_s/2)`` replaced by ``phi_0((g_s + g_1)/2)`` (``= g_1`` for a
    palindrome).  This saves one flow evaluation per step.  The caller must:

    1. at the start of a run (and after every re-synchronisation, and
       whenever ``h`` changes) apply ``phi_0(lead * h)`` once, with
       ``lead = fsal_lead_fraction(weights) = g_1/2``;
    2. per step, apply the returned sequence with the same ``h``;
    3. to read a synchronised state (end of run, output, event check, or
       before changing ``h``) apply ``phi_0(-lead * h)``, or equivalently
       replace the last fraction of the final step by ``g_s/2``; then
       resume with step 1.

    Between steps 2 and 3 the stored state is ``phi_0(lead h)`` applied to
    the true numerical solution, NOT the solution itself.
    """
    w, m = _check(weights, n_flows)
    if fsal and m < 2:
        raise ValueError("fsal=True needs n_flows >= 2")

    # Raw (unmerged) list of one step.
    ids = []
    fr = []
    for g in w:
        half = 0.5 * g
        for k in range(m - 1):
            ids.append(k)
            fr.append(half)
        ids.append(m - 1)
        fr.append(float(g))
        for k in range(m - 2, -1, -1):
            ids.append(k)
            fr.append(half)

    # Merge adjacent applications of the same flow.
    out_ids = [ids[0]]
    out_fr = [fr[0]]
    for k, f in zip(ids[1:], fr[1:]):
        if k == out_ids[-1]:
            out_fr[-1] = out_fr[-1] + f
        else:
            out_ids.append(k)
            out_fr.append(f)

    if fsal:
        # out = [phi_0(g_1/2), body..., phi_0(g_s/2)]
        lead = out_fr[0]
        out_ids = out_ids[1:]
        out_fr = out_fr[1:]
        out_fr[-1] = out_fr[-1] + lead

    return (np.ascontiguousarray(out_ids, dtype=np.int64),
            np.ascontiguousarray(out_fr, dtype=np.float64))


def fsal_lead_fraction(weights):
    """Fraction ``g_1/2`` of ``h`` of the leading ``phi_0`` that the caller
    applies once before the first step of an ``fsal=True`` run (and removes
    with ``phi_0(-lead h)`` to synchronise); see :func:`flow_sequence`."""
    w, _ = _check(weights, 1)
    return 0.5 * float(w[0])
