"""Bit-identity of two revisions: run the same crossings (dop853, taylor, split4), chaos indicators
(dop853, taylor, split6), trajectory (R1), fixed point, section map (forward and backward, with
and without its Jacobian, and a return cut by its time budget: the compiled return
``integrate.tangent.return_map_taylor``) and the manifold branches of a saddle
(``manifolds.grow_branch``) in each, then compare every number.

    git worktree add /tmp/base <rev>
    NUMBA_CACHE_DIR=/tmp/nc-base python tools/compare_revisions.py /tmp/base /tmp/base.npz
    python tools/compare_revisions.py $PWD /tmp/new.npz
    python tools/compare_revisions.py --compare /tmp/base.npz /tmp/new.npz

Used for refactors that must not change results (e.g. each method's step rendered per system
by tools/gen_lanes.py). Each run must use its own NUMBA_CACHE_DIR.
"""
import sys

import numpy as np

if sys.argv[1] == "--compare":
    a, b = np.load(sys.argv[2]), np.load(sys.argv[3])
    bad = [k for k in a.files if not (a[k].shape == b[k].shape and np.array_equal(a[k], b[k], equal_nan=True))]
    print("identical" if not bad else f"differ: {bad}")
    sys.exit(1 if bad else 0)
sys.path.insert(0, sys.argv[1] + "/src")
import explorer

assert explorer.__file__.startswith(sys.argv[1]), explorer.__file__
from explorer import model
from explorer.analysis import fixedpoints, lyapunov, sections
from explorer.analysis import trajectory as tr

prm = model.FIGURE4.with_(mu=0.5)
p1 = np.linspace(-0.5, 0.5, 12)
p2 = np.zeros(12) + 0.1
out = {}
for m, kw in (("dop853", dict(tol=1e-12)), ("taylor", dict(tol=1e-13)), ("split4", dict(dt=0.05))):
    r = sections.crossings(prm, 2.0, np.column_stack([p1, p2]), n_crossings=200, method=m, **kw)
    out[m] = np.concatenate([r.data.ravel(), r.final.ravel(), r.info.ravel()])
y0 = model.section_state(prm, p1[:6], p2[:6], 2.0)
for m, kw in (("dop853", dict(tol=1e-12)), ("taylor", dict(tol=1e-13)), ("split6", dict(dt=0.05))):
    r = lyapunov.indicators(prm, states=y0, tmax=300.0, method=m, history=5, **kw)
    out["ly_" + m] = np.concatenate([r.mlce, r.megno, r.fli, r.final.ravel(), r.history.ravel()])
res = tr.trajectory(tr.full_params(), tr.initial_state(tr.full_params(), 0.5, 0.0, 2.0, 0.0), 200.0, 2001)
out["traj"] = np.concatenate([np.asarray(res[k], float).ravel() for k in sorted(res)
                              if isinstance(res[k], np.ndarray) and res[k].dtype.kind == "f"])
fp = fixedpoints.find_fixed_point(prm, 2.0, (-0.2, 0.0))
out["fp"] = np.concatenate([fp.point, fp.jacobian.ravel()])
from explorer.analysis import manifolds as mf  # noqa: E402
from explorer.analysis.section_map import SectionMap  # noqa: E402

smap = SectionMap(prm, 2.0)
rows = []
for x in ((-0.2, 0.0), (0.1, 0.2), (0.3, -0.1)):
    for backward in (False, True):
        for jac in (False, True):
            r = smap(x, backward=backward, jacobian=jac)
            rows += [r.point, r.state, [r.time], r.jacobian.ravel() if jac else []]
out["map"] = np.concatenate(rows)
from explorer.integrate.tangent import return_map_taylor  # noqa: E402

y0 = smap.state((0.1, 0.2))
cut = []
for tmax in (0.37, 1.0):
    yout, Vout = np.empty(5), np.empty((2, 5))
    st, t = return_map_taylor(y0, smap.lift(y0), smap.P, smap.cphi, smap.sphi, 1.0, tmax, smap.order, 10**8,
                              np.zeros(1, np.int64), yout, Vout)
    cut += [float(st), t]
out["map_cut"] = np.array(cut)
sad = SectionMap(model.FIGURE4.with_(mu=0.03), 2.0)
fp0 = fixedpoints.find_fixed_point(sad, (0.0, 0.0))
if not fp0.stable:
    sd = mf.saddle(sad, fp0)
    for stable in (False, True):
        b = mf.grow_branch(sd, stable=stable, arclength=1.0)
        out["branch_" + ("s" if stable else "u")] = np.concatenate([b.points.ravel(), b.sigma[1:]])
np.savez(sys.argv[2], **out)
print("ok", sorted(out))
