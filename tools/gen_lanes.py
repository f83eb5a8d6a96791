#!/usr/bin/env python
"""Write the engine's Taylor recurrences of Chaplygin's equations (docs/model.md R3), scalar and
SIMD, from :mod:`explorer.model.chaplygin` by :func:`explorer.integrate.codegen.recurrence`: the
generator of every System (docs/systems.md), so the engine's recurrence is derived, not written.

- ``src/explorer/integrate/_lanes_generated.py``: the orbit, ``chaplygin.system()`` (5 rows);
  ``taylor_coefficients_into``/``taylor_coefficients``/``taylor_coefficients_lanes``.
- ``src/explorer/integrate/_tangent_lanes_generated.py``: in the engine's 15-row array (the orbit,
  then two deviation vectors from rows DEV1 = 5 and DEV2 = 10), the orbit and one deviation vector
  (``tangent_coefficients*``: the orbit's decomposition extended by rows 5..9 of
  ``chaplygin.variational(1)``, so the orbit's rows are R3's bit for bit), and the second deviation
  vector alone (``deviation_coefficients*``: rows 10..14 of ``chaplygin.variational(2)``, from the
  orbit's coefficients).

Each lane of a ``*_lanes`` kernel computes bit for bit what its scalar twin computes (one generator
emits both: the same operations in the same order).  Regenerate after changing the generator or
``explorer.model.chaplygin`` (tests/integrate/test_lanes.py checks the files are up to date)::

    python tools/gen_lanes.py            # writes both files
    python tools/gen_lanes.py --check    # exit 1 if a file is stale
    python tools/gen_lanes.py -o FILE [--tangent-output FILE2]    # write elsewhere
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from explorer.integrate import codegen  # noqa: E402
from explorer.model import chaplygin  # noqa: E402

OUTPUT = ROOT / "src" / "explorer" / "integrate" / "_lanes_generated.py"
TANGENT_OUTPUT = ROOT / "src" / "explorer" / "integrate" / "_tangent_lanes_generated.py"
#: rows of the tangent lane array Z[k, row, lane]: the orbit, then up to two deviation vectors
TANGENT_ROWS = 15
DEV1 = 5
DEV2 = 10

#: the one template of a generated file
MODULE = '''\
# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from {source} by explorer.integrate.codegen
# (generator version {version}).
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""{doc}

Each lane of a ``*_lanes`` kernel computes bit for bit what its scalar twin computes (the same
IEEE operations in the same order; the vector operations of :mod:`explorer.integrate.simd`: no
fast-math, no FMA).
"""
import numpy as np

from explorer._jit import njit
from explorer.integrate.simd import LANES, vload, vsplat, vstore, vzero  # noqa: F401

{constants}


{recurrences}'''


def _doc(what, rows, work):
    return (f"{what}: X[i, k] = x_i^(k)(0)/k! for k = 1..order in rows {rows},\n"
            f"    with the parameters P (the packed vector) and the work array W[{work}, >= order].")


def _lanes_doc(name, rows, work):
    return (f"LANES orbits at once: rows {rows} of X[k, row, l] (C-contiguous, XS / LANES rows), k = 1..order,\n"
            f"    W of shape (order + 1, max({work}, 1), LANES).  Each lane equals {name}_into bit for bit.")


def _module(source, doc, constants, recurrences):
    text = "\n\n".join(part for r in recurrences for part in (r.scalar, r.lanes))
    return MODULE.format(source=source, version=codegen.GENERATOR_VERSION, doc=doc, constants=constants,
                         recurrences=text)


def generate():
    """``_lanes_generated.py``: the orbit's recurrence, scalar and on lanes."""
    system = chaplygin.system()
    what = "The Taylor coefficients of R3 from X[:, 0]"
    r = codegen.recurrence(system, "taylor_coefficients", doc=_doc(what, "0..4", "N_WORK"),
                           lanes_doc=_lanes_doc("taylor_coefficients", "0..4", "N_WORK"))
    constants = (f"#: state variables (p1, p2, M, g1, g2): the rows of X\nNVAR = {system.dimension}\n"
                 f"#: rows of the work array\nN_WORK = {r.n_work}\n"
                 "#: flat strides of one order in the lane arrays X[k, i, l] and W[k, r, l]\n"
                 "XS = NVAR * LANES\nWS = max(N_WORK, 1) * LANES")
    return _module("explorer.model.chaplygin.system()",
                   "The Taylor recurrence of Chaplygin's R3 (docs/model.md), generated: the scalar form for the\n"
                   "scalar drivers (:mod:`explorer.integrate.systems`), the lane form for\n"
                   ":mod:`explorer.integrate.lanes`.", constants, [r])


def generate_tangent():
    """``_tangent_lanes_generated.py``: the orbit and a deviation vector, and a second deviation
    vector alone, scalar and on lanes, in the 15-row array."""
    orbit = chaplygin.system()
    one = chaplygin.variational(vectors=1)
    two = chaplygin.variational(vectors=2)
    # the orbit's own decomposition, extended by the first vector's equations: the orbit's rows are
    # the same operations as in the orbit's recurrence, so R3's bit for bit
    d = codegen.decompose(orbit)
    codegen.decompose(one, one.rhs[DEV1:DEV1 + 5], into=d)
    tangent = codegen.recurrence(
        one, "tangent_coefficients", decomposition=d, n_work="N_WORK_TANGENT", ws="WS_TANGENT",
        doc=_doc("R3 and its variational equations from X[:, 0] (rows 0..4: the orbit's recurrence's\n"
                 "    operations, so its values)", "0..9", "N_WORK_TANGENT"),
        lanes_doc=_lanes_doc("tangent_coefficients", "0..9", "N_WORK_TANGENT"))
    rows = range(DEV2, DEV2 + 5)
    deviation = codegen.recurrence(
        two, "deviation_coefficients", [two.rhs[i] for i in rows], rows, n_work="N_WORK_TANGENT",
        ws="WS_TANGENT",
        doc=_doc("The second deviation vector alone (the orbit's coefficients given in rows 0..4)",
                 f"{DEV2}..{DEV2 + 4}", "N_WORK_TANGENT"),
        lanes_doc=_lanes_doc("deviation_coefficients", f"{DEV2}..{DEV2 + 4}", "N_WORK_TANGENT"))
    work = max(tangent.n_work, deviation.n_work, 1)
    constants = ("#: rows of the lane array: the orbit (5) and two deviation vectors (5 each)\n"
                 f"NROWS = {TANGENT_ROWS}\n#: first row of each deviation vector\nDEV1 = {DEV1}\nDEV2 = {DEV2}\n"
                 "#: rows of the work array W[k, r, l] of both recurrences (at least 1)\n"
                 f"N_WORK_TANGENT = {work}\n"
                 "#: flat strides of one order in the lane arrays X[k, i, l] and W[k, r, l]\n"
                 "XS = NROWS * LANES\nWS_TANGENT = N_WORK_TANGENT * LANES")
    return _module("explorer.model.chaplygin.system(), variational(1) and (2)",
                   "The Taylor recurrence of R3 with deviation vectors (its variational equations), generated:\n"
                   "the scalar form for :mod:`explorer.integrate.tangent`, the lane form for\n"
                   ":mod:`explorer.integrate.tangent_lanes`.", constants, [tangent, deviation])


def operation_counts(kernel, order, tangent=False):
    """The vector operations one call of the generated lane ``kernel`` executes at ``order``:
    {"vadd": n, "vsub": n, "vmul": n, "vneg": n, "vdiv": n}, each on one vector of LANES doubles (per
    lane: that many scalar operations; a scalar's operations are not counted).  Counted by running the
    generated text itself with one-lane stand-ins that count (benchmarks/bench_roofline.py divides the
    flops of a step by these)."""
    import re

    import numpy as np

    text = generate_tangent() if tangent else generate()
    text = re.sub(r"^from explorer\..*$", "", text, flags=re.M)
    counts = dict.fromkeys(("vadd", "vsub", "vmul", "vneg", "vdiv"), 0)

    class Vec:
        def __init__(self, x):
            self.x = float(x)

        def _op(name, fn, swap=False):  # a factory of methods
            def op(a, b):
                counts[name] += 1
                a, b = (b, a) if swap else (a, b)
                return Vec(fn(a.x if isinstance(a, Vec) else a, b.x if isinstance(b, Vec) else b))
            return op

        __add__, __radd__ = _op("vadd", float.__add__), _op("vadd", float.__add__, True)
        __sub__, __rsub__ = _op("vsub", float.__sub__), _op("vsub", float.__sub__, True)
        __mul__, __rmul__ = _op("vmul", float.__mul__), _op("vmul", float.__mul__, True)
        __truediv__, __rtruediv__ = _op("vdiv", float.__truediv__), _op("vdiv", float.__truediv__, True)

        def __neg__(self):
            counts["vneg"] += 1
            return Vec(-self.x)

    ns = {"np": np, "njit": lambda *a, **k: (a[0] if a and callable(a[0]) else (lambda f: f)), "LANES": 1,
          "vload": lambda a, i: Vec(a.reshape(-1)[i]), "vstore": lambda a, i, v: a.reshape(-1).__setitem__(i, v.x),
          "vzero": lambda: Vec(0.0), "vsplat": lambda x: Vec(x), "taylor_coefficients_into": None}
    exec(compile(text, "<generated>", "exec"), ns)
    rows = ns.get("NROWS", ns.get("NVAR"))
    X = np.zeros((order + 1, rows, 1))
    X[0] = 0.5
    ns[kernel](np.ones(9), X, order, np.zeros((order + 1, 1, 1)))
    return counts


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--output", type=Path, default=OUTPUT)
    ap.add_argument("--check", action="store_true", help="do not write; exit 1 if the output differs")
    ap.add_argument("--tangent-output", type=Path, default=None,
                    help=f"where the tangent recurrences go (default {TANGENT_OUTPUT.name} when -o is not given)")
    args = ap.parse_args(argv)
    outputs = [(args.output, generate())]
    tangent_out = args.tangent_output
    if tangent_out is None and args.output == OUTPUT:
        tangent_out = TANGENT_OUTPUT
    if tangent_out is not None:
        outputs.append((tangent_out, generate_tangent()))
    if args.check:
        stale = 0
        for path, text in outputs:
            old = path.read_text() if path.exists() else ""
            if old != text:
                print(f"{path} is out of date; run tools/gen_lanes.py", file=sys.stderr)
                stale = 1
        return stale
    for path, text in outputs:
        path.write_text(text)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
