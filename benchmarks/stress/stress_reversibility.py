#!/usr/bin/env python
"""Forward then backward: every method returns to its start.

- splitting (all schemes of kernels.splitting.SCHEMES): n steps of dt then n steps of -dt with
  explorer.drivers.split_step on the state (a symmetric composition satisfies
  Psi_{-dt} o Psi_dt = id exactly, so only round-off remains): T = 10 with dt = 0.01 and 0.001,
  10 orbits at each of mu = 0.002, 0.03, 0.5; threshold 1e4 machine epsilons relative to
  max(1, |y0|);
- taylor and dop853: forward T, then backward T by integrating the time-reversed system
  (docs/model.md R3 is carried into itself with time reversed by (p, M, g) -> (p, -M, -g),
  lam -> -lam, r -> -r; operation by operation the same arithmetic as negative steps), tol
  1e-10 and 1e-13, T = 10 on the chaotic orbits and 100 on the regular ones (mu = 0.002, the
  hyperbolic central point excluded); threshold 10 tol T (the adaptive methods control the error
  per unit time);
- taylor backward section map: drivers_tangent.return_map_taylor (negative Taylor steps), tol
  1e-15, mu = 0.3, 10 orbits: one return backward from each of 20 forward crossings lands on the
  previous one within 1e-10; chained, 5 returns forward then 5 backward land on the forward
  crossings within 1e-9 (the section map is chaotic here: a chain of 20 amplifies the round-off
  by ~10 per return, which is the dynamics, not the method).

    python benchmarks/stress/stress_reversibility.py            # ~1 min
    python benchmarks/stress/stress_reversibility.py --quick
"""
from __future__ import annotations

import argparse
import sys

import numpy as np
from _stress import Checks

EPS = np.finfo(float).eps


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    quick = args.quick
    ck = Checks("stress_reversibility", quick, argv)
    from explorer import model
    from explorer._jit import njit
    from explorer.analysis import sections
    from explorer.integrate import drivers
    from explorer.integrate.tangent import return_map_taylor
    from explorer.kernels import splitting
    from explorer.kernels.taylor import order_for_tolerance
    from explorer.model.equations import N_FLOWS

    @njit
    def steps(y, P, dt, ids, fr, n):
        for _ in range(n):
            drivers.split_step(y, P, dt, ids, fr)

    n_orb = 3 if quick else 10

    def seeds(prm, n):
        c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
        rng = np.random.default_rng(5)
        ang = rng.uniform(0, 2 * np.pi, n)
        rad = np.sqrt(rng.uniform(0.05, 0.8, n))
        return model.section_state(prm, c1 + r1 * rad * np.cos(ang), c2 + r2 * rad * np.sin(ang), 2.0)

    # ---- splitting
    for method in splitting.SCHEMES:
        ids, fr = splitting.flow_sequence(splitting.SCHEMES[method][0], N_FLOWS)
        ids, fr = np.ascontiguousarray(ids, np.int64), np.ascontiguousarray(fr, np.float64)
        worst, where = 0.0, None
        for mu in (0.002, 0.03, 0.5):
            prm = model.FIGURE4.with_(mu=mu)
            P = prm.as_array()
            for dt in ((0.01,) if quick else (0.01, 0.001)):
                n = int(round(10.0 / dt))
                for y0 in seeds(prm, n_orb):
                    y = y0.copy()
                    steps(y, P, dt, ids, fr, n)
                    steps(y, P, -dt, ids, fr, n)
                    e = np.abs(y - y0).max() / EPS / max(1.0, np.abs(y0).max())
                    if e > worst:
                        worst, where = e, dict(mu=mu, dt=dt, y0=y0.tolist())
        ck.check(f"{method}: T = 10 forward then backward (dt 0.01{'' if quick else ', 0.001'}), worst return error "
                 "in eps", worst <= 1e4, round(worst, 1), "<= 1e4", worst_case=where)

    # ---- adaptive: the time-reversed system
    def R(y):
        z = np.array(y, float, copy=True)
        z[..., 2:] *= -1
        return z

    for method in ("taylor", "dop853"):
        for mu, T in ((0.5, 10.0), (0.03, 10.0), (0.002, 100.0)):
            prm = model.FIGURE4.with_(mu=mu, chi=0.05, zeta=0.1, xi=0.1, eta=-0.2)
            prmR = prm.with_(lam=-prm.lam, xi=-prm.xi, eta=-prm.eta)
            y0 = seeds(prm, n_orb)
            for tol in (1e-10, 1e-13):
                a = sections.crossings(prm, states=y0, n_crossings=10**4, method=method, tol=tol, tmax=T)
                b = sections.crossings(prmR, states=R(a.final), n_crossings=10**4, method=method, tol=tol, tmax=T)
                assert np.all(a.info[:, 0] == T) and np.all(b.info[:, 0] == T)
                err = np.abs(R(b.final) - y0).max(axis=1)
                worst = float(err.max() / (tol * T))
                ck.check(f"{method} tol {tol:g}, mu = {mu}, T = {T:g}: forward then backward, worst error / (tol T)",
                         worst <= 10, round(worst, 3), "<= 10", errors=err.tolist())

    # ---- taylor backward section map
    prm = model.FIGURE4.with_(mu=0.3)
    P = prm.as_array()
    order = order_for_tolerance(1e-15)
    V0 = np.zeros((0, 5))

    def ret(y, sign):
        out = np.empty(5)
        st, t = return_map_taylor(y, V0, P, -1.0, 0.0, sign, 1e3, order, 10**8, np.zeros(1, np.int64), out,
                                  np.empty((0, 5)))
        assert st == 0 and t * sign > 0
        return out

    local, chained = 0.0, 0.0
    n_ret = 5 if quick else 20
    for y0 in seeds(prm, n_orb):
        path = [y0]
        for _ in range(n_ret):
            path.append(ret(path[-1], 1.0))
        for k in range(n_ret, 0, -1):                 # one step back from each forward crossing
            local = max(local, float(np.abs(ret(path[k], -1.0) - path[k - 1]).max()))
        y = path[5]
        for k in range(5, 0, -1):                     # a chain of 5 back
            y = ret(y, -1.0)
            chained = max(chained, float(np.abs(y - path[k - 1]).max()))
    ck.check(f"taylor return map (mu = 0.3, tol 1e-15): one return backward from each of {n_ret} forward crossings, "
             "worst distance to the previous crossing", local <= 1e-10, float(f"{local:.3g}"), "<= 1e-10")
    ck.check("taylor return map: 5 returns forward then 5 backward, worst distance to the forward crossings",
             chained <= 1e-9, float(f"{chained:.3g}"), "<= 1e-9")
    split_worst = max(c["value"] for c in ck.items if c["check"].startswith("split"))
    adapt = max(c["value"] for c in ck.items if c["check"].startswith(("taylor tol", "dop853 tol")))
    return ck.finish(f"splitting: worst return error {split_worst:g} eps (<= 1e4); taylor/dop853: worst "
                     f"error/(tol T) {adapt:g} (<= 10); taylor return map: see the last two checks")


if __name__ == "__main__":
    sys.exit(main())
