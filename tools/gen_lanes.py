#!/usr/bin/env python
"""Write the engine's Taylor recurrences of Chaplygin's equations (docs/model.md R3), scalar and
SIMD, from :mod:`explorer.model.chaplygin` by :func:`explorer.integrate.codegen.recurrence`: the
generator of every System (docs/systems.md), so the engine's recurrence is derived, not written.

- ``src/explorer/integrate/_lanes_generated.py``: the orbit, ``chaplygin.system()`` (5 rows);
  ``taylor_coefficients_into``/``taylor_coefficients``/``taylor_coefficients_lanes``.
- ``src/explorer/integrate/_tangent_lanes_generated.py``: the orbit and one deviation vector
  (``tangent_coefficients``: the orbit's decomposition extended by rows 5..9 of
  ``chaplygin.variational(1)``, so the orbit's rows are R3's bit for bit), scalar, for the DOP853,
  splitting and return-map tangent loops (the Taylor indicators load ``chaplygin.variational``'s
  own module, :func:`explorer.integrate.tangent.indicators_module`).
- ``src/explorer/integrate/_systems_generated.py``: each method's one step for each system of the
  scalar drivers (:data:`SYSTEMS`), rendered from one template per method (:data:`STEPS`), so a
  driver calls its system's step by name (numba cannot cache a function that takes another
  compiled function as an argument: the callee's type names the function object).

Each lane of a ``*_lanes`` kernel computes bit for bit what its scalar twin computes (one generator
emits both: the same operations in the same order).  Regenerate after changing the generator or
``explorer.model.chaplygin`` (tests/integrate/test_lanes.py checks the files are up to date)::

    python tools/gen_lanes.py            # writes the three files
    python tools/gen_lanes.py --check    # exit 1 if a file is stale
    python tools/gen_lanes.py -o FILE [--tangent-output FILE2] [--systems-output FILE3]    # write elsewhere
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
SYSTEMS_OUTPUT = ROOT / "src" / "explorer" / "integrate" / "_systems_generated.py"
#: first row of the deviation vector in the tangent array
DEV1 = 5

#: the one template of a generated file
MODULE = '''\
# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from {source} by explorer.integrate.codegen
# (generator version {version}).
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""{doc}"""
import numpy as np

from explorer._jit import njit

{constants}


{recurrences}'''


def _doc(what, rows, work):
    return (f"{what}: X[i, k] = x_i^(k)(0)/k! for k = 1..order in rows {rows},\n"
            f"    with the parameters P (the packed vector) and the work array W[{work}, >= order].")


def _module(source, doc, constants, recurrences):
    text = "\n\n".join(r.scalar for r in recurrences)
    return MODULE.format(source=source, version=codegen.GENERATOR_VERSION, doc=doc, constants=constants,
                         recurrences=text)


#: what follows the generated module of Chaplygin's System in ``_lanes_generated.py``
CHAPLYGIN_TAIL = """

# ---- the engine's names: its state's rows, and its H (explorer.model.equations.energy, docs/model.md R3)
# in the rows' H - H0, of which explorer.integrate.drivers.start_carry takes H0 for every method
from explorer.model.equations import energy  # noqa: E402, F811

#: state variables (p1, p2, M, g1, g2): the rows of X
NVAR = DIM
"""


def generate():
    """``_lanes_generated.py``: the generated module of ``chaplygin.system()``
    (:func:`explorer.integrate.codegen.source`: the recurrence, scalar and on lanes, and the crossing
    drivers of every System, :mod:`~explorer.integrate.codegen_crossings` and
    :mod:`~explorer.integrate.codegen_lanes`), the model's H in its rows."""
    from explorer.integrate import codegen_crossings, codegen_lanes

    system = chaplygin.system()
    text = codegen.source(system)
    for template in codegen.TEMPLATES:   # only the crossing drivers: the engine has its own indicators
        if template not in (codegen_crossings, codegen_lanes):
            part = template.render(system)
            assert text.count(part) == 1, template.__name__
            text = text.replace(part, "")
    head = ("# Written to this file by tools/gen_lanes.py from explorer.model.chaplygin.system().\n"
            "# Regenerate:  python tools/gen_lanes.py     (check: --check)\n"
            "# ruff: noqa  (the text of every System's module: its imports repeat, template by template)\n")
    return head + text + CHAPLYGIN_TAIL


def generate_tangent():
    """``_tangent_lanes_generated.py``: the orbit and a deviation vector, scalar, in 10 rows."""
    orbit = chaplygin.system()
    one = chaplygin.variational(vectors=1)
    # the orbit's own decomposition, extended by the vector's equations: the orbit's rows are the
    # same operations as in the orbit's recurrence, so R3's bit for bit
    tangent = codegen.recurrence(
        one, "tangent_coefficients", decomposition=codegen.decompose_extending(orbit, one),
        n_work="N_WORK_TANGENT",
        doc=_doc("R3 and its variational equations from X[:, 0] (rows 0..4: the orbit's recurrence's\n"
                 "    operations, so its values)", "0..9", "N_WORK_TANGENT"))
    constants = (f"#: first row of the deviation vector\nDEV1 = {DEV1}\n"
                 "#: rows of the work array W[k, r] of the recurrence (at least 1)\n"
                 f"N_WORK_TANGENT = {max(tangent.n_work, 1)}")
    return _module("explorer.model.chaplygin.system() and variational(1)",
                   "The Taylor recurrence of R3 with a deviation vector (its variational equations), generated,\n"
                   "for the tangent loops of :mod:`explorer.integrate.tangent` (docs/systems.md).", constants,
                   [tangent])


#: the systems of the scalar drivers: (suffix, what it is, its field dy = f(y) or None, its Taylor
#: coefficients of X[:, 0] or None, one exact sub-flow of the composition or None)
SYSTEMS = (
    ("reduced", "R3 (docs/model.md), 5 variables", "rhs(y, P, dy)", "taylor_coefficients(P, X, order)",
     "apply_flow(flow_ids[i], y, P, fracs[i] * dt)"),
    ("tangent", "R3 and one deviation vector (rows 5..9), 10 variables", "rhs_augmented(y, P, dy)", None,
     "apply_flow_tangent(flow_ids[i], y[:N_ORBIT], y[N_ORBIT:], P, fracs[i] * dt)"),
    ("full", "R1 (docs/model.md) with the position, FULL_DIM variables", "rhs_full(y, P, dy)", None, None),
    # y(t0 - s) has the coefficients (-1)^k X_k of y(t0 + s), exactly
    ("backward", "R3 in reversed time, y(t0 - s) of s", None,
     "taylor_coefficients(P, X, order)\n    reverse_time(X, order)", None),
)

SYSTEMS_MODULE = '''\
# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from its templates STEPS and its list SYSTEMS.
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""Each method's one step for each system of the scalar drivers (docs/architecture.md, "The system
seam"): the step written once, in a template, and rendered with each system's field, recurrence and
sub-flows, so a loop calls its system's step by name:

{systems}
"""
from explorer._jit import njit
from explorer.integrate._lanes_generated import taylor_coefficients
from explorer.integrate.systems import FIRST_STEP, N_ORBIT, STEP_OK, finite_column, reverse_time, rhs_augmented
from explorer.kernels import STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW
from explorer.kernels import dop853 as dp
from explorer.kernels import taylor as tk
from explorer.kernels.checks import all_finite
from explorer.kernels.clock import clip_step, resolves
from explorer.model.equations import apply_flow, apply_flow_tangent, rhs, rhs_full
'''

#: each method's step, rendered for every system with what it needs ({s}: the system's suffix)
STEPS = {
    "field": '''

@njit(inline="always")
def field_{s}(y, P, dy):
    """dy = f(y) of {what}."""
    {field}
''',
    "dop853": '''

@njit
def dop853_first_step_{s}(y, P, K, rtol, atol, span, tmp):
    """K[0] = f(y) and scipy's initial step for an integration over ``span``."""
    field_{s}(y, P, K[0])
    h0 = dp.initial_step_part1(y, K[0], rtol, atol, span, 1.0, tmp)
    field_{s}(tmp, P, K[1])
    return dp.initial_step_part2(y, K[0], K[1], h0, rtol, atol, span)


@njit(inline="always")
def dop853_step_{s}(y, P, K, t, tend, end_code, h_abs, steps, max_steps, rtol, atol, tmp, ynew, fsal):
    """One accepted DOP853 step (Hairer, Nørsett & Wanner) from ``y`` at time ``t`` towards ``tend``
    (K[0] = f(y) on entry), rejected attempts retried at the controller's smaller step; ``end_code``
    (h = 0) when ``t`` has reached ``tend``.  Returns (code, h, last, h_abs, steps)."""
    if not (t < tend):
        return end_code, 0.0, False, h_abs, steps
    if h_abs == FIRST_STEP:
        h_abs = dop853_first_step_{s}(y, P, K, rtol, atol, tend - t, tmp)
    rejected = False
    while True:
        if steps >= max_steps:
            return STATUS_MAX_STEPS, 0.0, False, h_abs, steps
        if dp.step_too_small(t, h_abs):
            return STATUS_STEP_UNDERFLOW, 0.0, False, h_abs, steps
        h, last = clip_step(t, h_abs, tend)
        for s in range(1, 12):
            dp.stage_input(y, K, s, h, tmp)
            field_{s}(tmp, P, K[s])
        dp.step_solution(y, K, h, ynew)
        err = dp.error_norm(y, ynew, K, h, rtol, atol)
        steps += 1
        if not (err == err) or not all_finite(ynew):
            return STATUS_NONFINITE, h, last, h_abs, steps
        if err < 1.0:
            if fsal:
                field_{s}(ynew, P, K[12])
            return STEP_OK, h, last, h_abs * dp.accepted_factor(err, rejected), steps
        h_abs *= dp.step_factor(err)
        rejected = True


@njit
def dop853_dense_stages_{s}(y, P, K, h, tmp):
    """The three extra stages K[13..15] of the 7th-order continuous extension."""
    for s in range(13, 16):
        dp.stage_input(y, K, s, h, tmp)
        field_{s}(tmp, P, K[s])
''',
    "taylor": '''

@njit(inline="always")
def taylor_coefficients_{s}(P, X, order):
    """X[i, k] = y_i^(k)/k!, k = 0..order, from X[:, 0]: {what}."""
    {coefficients}


@njit(inline="always")
def taylor_step_{s}(X, P, t, tend, end_code, order, factor, steps, max_steps, ynew):
    """One step of the adaptive Taylor method of ``order`` (Jorba & Zou 2005) from X[:, 0] at time ``t``
    towards ``tend``, its size from the orbit's rows; ``end_code`` (h = 0) when ``t`` has reached ``tend``.
    Returns (code, h, last, steps)."""
    if not (t < tend):
        return end_code, 0.0, False, steps
    if steps >= max_steps:
        return STATUS_MAX_STEPS, 0.0, False, steps
    taylor_coefficients_{s}(P, X, order)
    if not (finite_column(X, order, N_ORBIT) and finite_column(X, order - 1, N_ORBIT)):
        return STATUS_NONFINITE, 0.0, False, steps
    h = tk.step_size(X[:N_ORBIT], order, factor)
    h, last = clip_step(t, h, tend)
    if not resolves(t, h):
        return STATUS_STEP_UNDERFLOW, 0.0, False, steps
    tk.evaluate(X, order, h, ynew)
    steps += 1
    if not all_finite(ynew):
        return STATUS_NONFINITE, h, last, steps
    return STEP_OK, h, last, steps
''',
    "split": '''

@njit(inline="always")
def compose_{s}(y, P, dt, flow_ids, fracs):
    """One step ``dt`` of the composition (flow_ids, fracs) of the exact sub-flows of R4 (docs/model.md),
    in place, for {what}."""
    for i in range(flow_ids.shape[0]):
        {compose}


@njit(inline="always")
def split_step_{s}(y, P, dt, flow_ids, fracs, steps, max_steps, ynew):
    """One step of a splitting method from ``y`` into ``ynew`` (the loop decides when its span ends:
    t_n = n dt is never summed).  Returns (code, steps)."""
    if steps >= max_steps:
        return STATUS_MAX_STEPS, steps
    for i in range(y.shape[0]):
        ynew[i] = y[i]
    compose_{s}(ynew, P, dt, flow_ids, fracs)
    steps += 1
    if not all_finite(ynew):
        return STATUS_NONFINITE, steps
    return STEP_OK, steps
''',
}


def generate_systems():
    """``_systems_generated.py``: :data:`STEPS` rendered for each of :data:`SYSTEMS` that has what
    the method needs (DOP853 a field, Taylor a recurrence, splitting sub-flows)."""
    parts = []
    for s, what, field, coefficients, compose in SYSTEMS:
        for method, needs in (("field", field), ("dop853", field), ("taylor", coefficients), ("split", compose)):
            if needs is not None:
                parts.append(STEPS[method].format(s=s, what=what, field=field, coefficients=coefficients,
                                                  compose=compose))
    names = "\n".join(f"- ``*_{s}``: {what}" for s, what, *_ in SYSTEMS)
    return SYSTEMS_MODULE.format(systems=names) + "".join(parts)


def operation_counts(order, nvec=0):
    """The vector operations one call of the generated lane recurrence ``taylor_coefficients_lanes``
    executes at ``order``, of the orbit (``nvec = 0``, ``chaplygin.system()``) or of the indicators'
    module with ``nvec`` deviation vectors (``chaplygin.variational(nvec)``, the orbit's decomposition
    extended): {"vadd": n, "vsub": n, "vmul": n, "vneg": n, "vdiv": n}, each on one vector of LANES
    doubles (per lane: that many scalar operations; a scalar's operations are not counted).  Counted by
    running the generated text itself with one-lane stand-ins that count (benchmarks/bench_roofline.py
    divides the flops of a step by these)."""
    import math
    import re

    import numpy as np

    orbit = chaplygin.system()
    system = chaplygin.variational(vectors=nvec) if nvec else orbit
    r = codegen.recurrence(system, decomposition=codegen.decompose_extending(orbit, system))
    text = re.sub(r"^from explorer\..*$", "", r.lanes, flags=re.M)
    counts = dict.fromkeys(("vadd", "vsub", "vmul", "vneg", "vdiv"), 0)

    def counted(name, fn):
        def op(*args):
            counts[name] += 1
            return fn(*args)
        return op

    ns = {"np": np, "njit": lambda *a, **k: (a[0] if a and callable(a[0]) else (lambda f: f)), "LANES": 1,
          "vget": lambda a, k, r: float(a[k, r, 0]), "vset": lambda a, k, r, v: a.__setitem__((k, r, 0), v),
          "vzero": lambda: 0.0, "vsplat": float, "vsqrt": math.sqrt, "taylor_coefficients_into": None,
          "vadd": counted("vadd", float.__add__), "vsub": counted("vsub", float.__sub__),
          "vmul": counted("vmul", float.__mul__), "vdiv": counted("vdiv", float.__truediv__),
          "vneg": counted("vneg", float.__neg__)}
    exec(compile(text, "<generated>", "exec"), ns)
    X = np.zeros((order + 1, system.dimension, 1))
    X[0] = 0.5
    ns["taylor_coefficients_lanes"](np.ones(9), X, order, np.zeros((order + 1, max(r.n_work, 1), 1)))
    return counts


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--output", type=Path, default=OUTPUT)
    ap.add_argument("--check", action="store_true", help="do not write; exit 1 if the output differs")
    ap.add_argument("--tangent-output", type=Path, default=None,
                    help=f"where the tangent recurrences go (default {TANGENT_OUTPUT.name} when -o is not given)")
    ap.add_argument("--systems-output", type=Path, default=None,
                    help=f"where the systems' steps go (default {SYSTEMS_OUTPUT.name} when -o is not given)")
    args = ap.parse_args(argv)
    outputs = [(args.output, generate())]
    tangent_out, systems_out = args.tangent_output, args.systems_output
    if args.output == OUTPUT:
        tangent_out = tangent_out or TANGENT_OUTPUT
        systems_out = systems_out or SYSTEMS_OUTPUT
    if tangent_out is not None:
        outputs.append((tangent_out, generate_tangent()))
    if systems_out is not None:
        outputs.append((systems_out, generate_systems()))
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
