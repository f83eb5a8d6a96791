"""The Melnikov figure (docs/model.md R8; ur24 against its correction): the numbers come from
:mod:`explorer.analysis.melnikov`, this module only draws them."""
from __future__ import annotations

import math

import numpy as np

from explorer import model
from explorer.analysis.melnikov import (
    DEFAULT_MUS,
    _params,
    check_params,
    closed_form,
    measured_splitting,
    melnikov_integral,
    melnikov_table,
    ur24,
)
from explorer.app.figures import _matplotlib
from explorer.model import ParameterError


def melnikov_figure(params=None, h=None, *, mus=DEFAULT_MUS, g0=0.5 * math.pi, n_measured=12,
                    mu_curve=None, dpi=150):
    """Three panels: (a) J(g0) of both branches (quadrature), ur24 as printed and the corrected
    closed form, with the splitting measured on the section at mu_curve (default: the smallest
    mu) divided by mu at n_measured phases; (b) |measured| and mu |J| against mu at g0;
    (c) |ratio - 1| against mu (O(mu))."""
    _matplotlib()
    from matplotlib.figure import Figure

    prm = model.FIGURE4 if params is None else _params(params)
    h = model.FIGURE4_H if h is None else h
    c = check_params(prm, h)
    prm0 = prm.with_(mu=0.0)
    mu_curve = min(mus) if mu_curve is None else mu_curve
    gg = np.linspace(0.0, 2.0 * math.pi, 361)
    u = ur24(prm0, c)
    cf = closed_form(prm0, c)
    fig = Figure(figsize=(13.0, 3.9), dpi=dpi, layout="constrained")
    ax = fig.subplots(1, 3)
    colours = {1: "C0", -1: "C3"}
    for s in (1, -1):
        ax[0].plot(gg, melnikov_integral(prm0, c, gg, s), color=colours[s], lw=1.6,
                   label=f"quadrature, sign {s:+d}")
        ax[0].plot(gg[::24], (cf["sin_plus"] if s == 1 else cf["sin_minus"]) * np.sin(gg[::24])
                   + cf["cos"] * np.cos(gg[::24]), "o", mfc="none", color=colours[s], ms=5,
                   label=f"closed form (residues), sign {s:+d}")
        gm = (np.arange(n_measured) + 0.5) * 2.0 * math.pi / n_measured
        meas = []
        for g in gm:
            try:
                meas.append(measured_splitting(prm0, h, mu_curve, g, s)["measured"] / mu_curve)
            except ParameterError:
                meas.append(np.nan)
        ax[0].plot(gm, meas, "x" if s == 1 else "+", color=colours[s], ms=7, mew=1.5,
                   label=fr"measured $\Delta F_0/\mu$ ($\mu$ = {mu_curve:g}), sign {s:+d}")
    ax[0].plot(gg, u["sin"] * np.sin(gg) + u["cos"] * np.cos(gg), "k--", lw=1.2, label="ur24 as printed")
    ax[0].axhline(0.0, color="0.6", lw=0.6)
    ax[0].set_xlabel(r"$g_0$ ($\varphi$ at the centre of the homoclinic orbit)")
    ax[0].set_ylabel(r"$J(g_0)$")
    ax[0].set_xlim(0, 2 * math.pi)
    ax[0].set_xticks(np.arange(5) * 0.5 * math.pi, ["0", r"$\pi/2$", r"$\pi$", r"$3\pi/2$", r"$2\pi$"])
    top = 1.25 * max(abs(cf["sin_plus"]), abs(cf["sin_minus"])) + abs(cf["cos"])
    ax[0].set_ylim(-top, 1.55 * top)
    ax[0].legend(fontsize=6, loc="upper center", ncol=2)
    ax[0].set_title(fr"(a) Melnikov function, $c = {c:.4g}$, $h = {h:g}$", fontsize=10)
    rows = melnikov_table(prm, h, mus, (g0,), (1, -1))
    mus_a = np.array(mus, float)
    for s in (1, -1):
        r = [row for row in rows if row["sign"] == s]
        meas = np.array([row["measured"] for row in r])
        pred = np.array([row["predicted"] for row in r])
        ax[1].loglog(mus_a, np.abs(meas), "o" if s == 1 else "s", color=colours[s], mfc="none" if s == -1 else None,
                     ms=6 if s == 1 else 9, label=f"measured, sign {s:+d}")
        ax[1].loglog(mus_a, np.abs(pred), "-" if s == 1 else "--", color=colours[s], lw=1,
                     label=fr"$\mu |J|$, sign {s:+d}")
        ax[2].loglog(mus_a, np.abs(meas / pred - 1.0), "o-", color=colours[s], label=f"sign {s:+d}")
    ax[2].loglog(mus_a, mus_a, "k:", lw=1, label=r"$\propto \mu$")
    ax[1].set_xlabel(r"$\mu$")
    ax[1].set_ylabel(r"$|F_0(W^u) - F_0(W^s)|$ on $\varphi = \pi$")
    ax[1].set_title(fr"(b) splitting at $g_0 = {g0 / math.pi:.3g}\pi$", fontsize=10)
    ax[1].legend(fontsize=7)
    ax[2].set_xlabel(r"$\mu$")
    ax[2].set_ylabel(r"|measured / ($\mu J$) $- 1$|")
    ax[2].set_title("(c) first-order error", fontsize=10)
    ax[2].legend(fontsize=7)
    return fig
