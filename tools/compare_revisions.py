"""Bit-identity of two revisions: run the same crossings (dop853, taylor, split4), chaos indicators
(dop853, taylor, split6), trajectory (R1) and fixed point in each, then compare every number.

    git worktree add /tmp/base <rev>
    NUMBA_CACHE_DIR=/tmp/nc-base python tools/compare_revisions.py /tmp/base /tmp/base.npz
    python tools/compare_revisions.py . /tmp/new.npz
    python tools/compare_revisions.py --compare /tmp/base.npz /tmp/new.npz

Used for refactors that must not change results (e.g. the DOP853 step written once in
explorer.integrate.systems). Each run must use its own NUMBA_CACHE_DIR.
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
    r = sections.section_crossings(prm, p1, p2, 2.0, 200, method=m, **kw)
    out[m] = np.concatenate([r.data.ravel(), r.final.ravel(), r.info.ravel()])
y0 = model.section_state(prm, p1[:6], p2[:6], 2.0)
for m, kw in (("dop853", dict(tol=1e-12)), ("taylor", dict(tol=1e-13)), ("split6", dict(dt=0.05))):
    r = lyapunov.indicators(prm, y0, 300.0, method=m, history=5, **kw)
    out["ly_" + m] = np.concatenate([r.mlce, r.megno, r.fli, r.final.ravel(), r.history.ravel()])
res = tr.trajectory(tr.full_params(), tr.initial_state(tr.full_params(), 0.5, 0.0, 2.0, 0.0), 200.0, 2001)
out["traj"] = np.concatenate([np.asarray(res[k], float).ravel() for k in sorted(res)
                              if isinstance(res[k], np.ndarray) and res[k].dtype.kind == "f"])
fp = fixedpoints.find_fixed_point(prm, 2.0, (-0.2, 0.0))
out["fp"] = np.concatenate([fp.point, fp.jacobian.ravel()])
np.savez(sys.argv[2], **out)
print("ok", sorted(out))
