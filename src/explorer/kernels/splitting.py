"""Symmetric composition (splitting) methods of orders 2 to 8 (docs/methods.md): which exact
flow phi_k of ``H = H_0 + ... + H_{m-1}`` to apply for what fraction of the step.  Strang's
S(h) is phi_0(h/2) ... phi_{m-1}(h) ... phi_0(h/2); higher orders are S(g_s h) ... S(g_1 h) with
palindromic weights g (sum g = 1), float64, read-only, exact to double precision (Yoshida's 1990
solutions refined by Newton on the order conditions; tests/kernels/test_splitting.py).
``SCHEMES[name] = (weights, order, reference)``.
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
    h = np.asarray(half, dtype=np.float64)
    w = np.ascontiguousarray(np.concatenate([h, h[-2::-1]]))
    w.setflags(write=False)
    return w


def _closed_form(kind):
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


W_STRANG = _palindrome([1.0])

_tj_outer, _tj_centre = _closed_form("triple")
#: Yoshida (1990) / Forest-Ruth / Suzuki triple jump, 3 stages.
W_YOSHIDA4 = _palindrome([_tj_outer, _tj_centre])

_sz_outer, _sz_centre = _closed_form("suzuki")
#: Suzuki (1990) fractal, 5 stages: [p, p, 1 - 4p, p, p].
W_SUZUKI4 = _palindrome([_sz_outer, _sz_outer, _sz_centre])

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
    0.78451361047755726381949763,
    0.23557321335935813368479318,
    -1.17767998417887100694641568,
    1.31518632068391121888424973,     # w0 = 1 - 2 (w1 + w2 + w3)
])

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
    0.91484424622979156674879349,
    0.25369333656621135414614602,
    -1.44485223686060515769473066,
    -0.15824063536805017520406678,
    1.93813913762252598657918649,
    -1.96061023297531080760763338,
    0.10279984939179644069811513,
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
    """Flattened sub-flow applications of one step of ``Psi(h)``."""
    w, m = _check(weights, n_flows)
    if fsal and m < 2:
        raise ValueError("fsal=True needs n_flows >= 2")

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
