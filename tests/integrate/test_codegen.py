"""explorer.integrate.codegen: the Taylor recurrence derived from a System's SymPy equations
(docs/systems.md).  Each automatic-differentiation rule against high-precision derivatives, the
generated Chaplygin recurrence against the hand-written one (docs/model.md R3), a Hénon–Heiles
Taylor integration against DOP853, and the on-disk cache of the generated module.

The rule systems are one System (one module to compile): the states t (dt/dt = 1) and e
(de/dt = e), so t(s) = T0 + s and e(s) = E0 exp(s), and one state x_r per rule with
dx_r/dt = g_r(t, e): its coefficients are x_{r,k+1} = g_k / (k + 1) with g_k the Taylor
coefficients of g_r(T0 + s, E0 exp(s)) at s = 0, computed by ``mpmath.taylor`` (SymPy's
arbitrary-precision library) at 60 digits, for the rules with a closed-form reference also by
``sympy.series``.  A second group of states feeds a rule its own output (dy/dt = sin y, ...),
checked against the series of the exact solution.
"""
import math
import re

import mpmath
import numpy as np
import pytest
import sympy as sp
from systems import henon_heiles, oscillator

from explorer.integrate import codegen
from explorer.model import chaplygin
from explorer.model import parameters as mp_
from explorer.model.system import System
from explorer.model.validation import ParameterError

ORDER = 14              # coefficients up to x_14 (g_13)
T0, E0, LAM = 0.25, 1.5, 0.75   # exact in binary: the references use the same numbers
t, e, lam, s = sp.symbols("t e lam s")

#: rule -> g(t, e, lam)
RULES = {
    "add": e + t,
    "sub": t - e,
    "neg": -e,
    "add a parameter": e + lam,
    "parameter minus series": lam - e,
    "mul": t * e,
    "mul by a parameter": lam * e * e,
    "div": (t + 2) / (e + t),
    "parameter over series": lam / (e + t),
    "series over parameter": e / lam,
    "square": (e - t) ** 2,
    "integer power 5": (e - t) ** 5,
    "integer power -3": (e - t) ** -3,
    "real power 2.5": (e + t) ** 2.5,
    "rational power -1/3": (e + t) ** sp.Rational(-1, 3),
    "parameter power": (e + t) ** lam,
    "sqrt": sp.sqrt(e + t),
    "exp": sp.exp(e - t),
    "log": sp.log(e + t),
    "sin": sp.sin(e - t),
    "cos": sp.cos(e * t),
    "tan": sp.tan(e - t),
    "series power": e ** t,
    "shared subexpressions": sp.sin(e * t) * sp.exp(e * t) + sp.cos(e * t) / (1 + (e * t) ** 2),
    "functions of parameters only": e * sp.exp(lam) + t * sp.sqrt(lam) * sp.pi + sp.cos(lam) * sp.log(lam + 2) * t * e,
}
#: state y -> (dy/dt, y(0), exact solution y(tau) as a SymPy expression of tau)
tau = sp.Symbol("tau")
SELF = {
    "sin y": (lambda y: sp.sin(y), 0.5, 2 * sp.atan(sp.tan(sp.Rational(1, 4)) * sp.exp(tau))),
    "-y^3": (lambda y: -y**3, 0.75, sp.Rational(3, 4) / sp.sqrt(1 + 2 * sp.Rational(9, 16) * tau)),
    "exp(-y)": (lambda y: sp.exp(-y), 0.5, sp.log(tau + sp.exp(sp.Rational(1, 2)))),
    "1/y": (lambda y: 1 / y, 1.25, sp.sqrt(sp.Rational(25, 16) + 2 * tau)),
    "y log y": (lambda y: y * sp.log(y), 2.0, sp.exp(sp.log(2) * sp.exp(tau))),
    "y^1.5": (lambda y: y ** sp.Float(1.5), 0.5, (sp.sqrt(2) - tau / 2) ** -2),
}

XS = [sp.Symbol(f"x{i}") for i in range(len(RULES))]
YS = [sp.Symbol(f"y{i}") for i in range(len(SELF))]


@pytest.fixture(scope="module")
def rules_module():
    eqs = {t: 1, e: e}
    eqs.update({xr: g for xr, g in zip(XS, RULES.values())})
    eqs.update({yr: f(yr) for yr, (f, _, _) in zip(YS, SELF.values())})
    system = System(eqs, parameters={lam: LAM}, name="ad_rules")
    return system, codegen.load(system)


@pytest.fixture(scope="module")
def rules_coefficients(rules_module):
    system, mod = rules_module
    X = np.zeros((system.dimension, ORDER + 1))
    X[0, 0], X[1, 0] = T0, E0
    X[2 + len(RULES):, 0] = [y0 for _, y0, _ in SELF.values()]
    mod.taylor_coefficients(system.parameter_array(), X, ORDER)
    return X


def reference(expr, var, n):
    """Taylor coefficients c_0..c_{n-1} of expr(var) at var = 0, at 60 digits (mpmath.taylor:
    high-order derivatives by arbitrary-precision differences)."""
    f = sp.lambdify(var, expr, "mpmath")
    with mpmath.workdps(60):
        return np.array([float(c) for c in mpmath.taylor(f, 0, n - 1)])


def g_reference(g):
    return reference(g.subs({t: sp.Rational(T0) + s, e: sp.Rational(E0) * sp.exp(s), lam: sp.Rational(LAM)}), s, ORDER)


def rel_err(got, want):
    return np.max(np.abs(got - want) / np.abs(want))


@pytest.mark.parametrize("rule", list(RULES))
def test_each_rule_gives_the_taylor_coefficients_of_its_operation_to_1e_13(rules_coefficients, rule):
    i = 2 + list(RULES).index(rule)
    got = rules_coefficients[i, 1:] * np.arange(1, ORDER + 1)   # g_k = (k + 1) x_{k+1}
    want = g_reference(RULES[rule])
    assert np.all(np.abs(want) > 1e-12), "a reference coefficient near zero makes a relative test meaningless"
    assert rel_err(got, want) <= 1e-13, (rule, rel_err(got, want))


@pytest.mark.parametrize("rule", ["div", "rational power -1/3", "sqrt", "parameter power"])
def test_the_high_precision_reference_equals_sympys_own_series(rule):
    g = RULES[rule].subs({t: sp.Rational(T0) + s, e: sp.Rational(E0) * sp.exp(s), lam: sp.Rational(LAM)})
    series = sp.series(g, s, 0, ORDER).removeO()
    exact = np.array([float(sp.N(series.coeff(s, k), 30)) for k in range(ORDER)])
    assert rel_err(g_reference(RULES[rule]), exact) <= 1e-15


@pytest.mark.parametrize("name", list(SELF))
def test_a_rule_fed_its_own_output_gives_the_series_of_the_exact_solution(rules_coefficients, name):
    i = 2 + len(RULES) + list(SELF).index(name)
    want = reference(SELF[name][2], tau, ORDER + 1)
    assert want[0] == SELF[name][1]
    assert rel_err(rules_coefficients[i], want) <= 1e-13, (name, rel_err(rules_coefficients[i], want))


def test_rhs_is_the_equations_evaluated_and_a_zero_denominator_gives_inf_not_an_exception(rules_module):
    system, mod = rules_module
    rng = np.random.default_rng(5)
    y = rng.uniform(0.3, 0.9, system.dimension)
    dy = np.empty(system.dimension)
    mod.rhs(y, system.parameter_array(), dy)
    f = sp.lambdify([system.states, lam], list(system.rhs))
    np.testing.assert_allclose(dy, f(y, LAM), rtol=1e-14)
    y[2 + len(RULES) + list(SELF).index("1/y")] = 0.0
    mod.rhs(y, system.parameter_array(), dy)
    assert math.isinf(dy[2 + len(RULES) + list(SELF).index("1/y")])


def test_common_subexpressions_are_one_node():
    x, y = sp.symbols("x y")
    system = System({x: sp.sin(x * y) + sp.cos(x * y), y: sp.exp(x * y) * sp.sin(x * y)})
    d = codegen.decompose(system)
    kinds = [n.kind for n in d.nodes]
    assert kinds.count("mul") == 2      # x y once, and exp(.) sin(.)
    assert kinds.count("sin") == 1 and kinds.count("cos") == 1 and kinds.count("exp") == 1


# ---------------------------------------------------------------------- Hénon–Heiles against DOP853
def taylor_orbit(mod, P, y0, dt, steps, order=20):
    from explorer.kernels.taylor import evaluate

    X = np.zeros((len(y0), order + 1))
    W = np.empty((max(mod.N_WORK, 1), order + 1))
    y = np.array(y0, dtype=float)
    out = [y.copy()]
    for _ in range(steps):
        X[:, 0] = y
        mod.taylor_coefficients_into(P, X, order, W)
        evaluate(X, order, dt, y)
        out.append(y.copy())
    return np.array(out)


@pytest.mark.parametrize("value", [1.0, 0.5])
def test_henon_heiles_taylor_steps_agree_with_dop853_and_conserve_the_energy(value):
    from scipy.integrate import solve_ivp

    system = henon_heiles().with_(lam=value)
    mod = codegen.load(system)
    P = system.parameter_array()
    y0 = np.array([0.1, -0.2, 0.35, 0.1])
    dt, steps = 0.05, 200
    orbit = taylor_orbit(mod, P, y0, dt, steps)

    def f(_, y):
        dy = np.empty(4)
        mod.rhs(y, P, dy)
        return dy

    ref = solve_ivp(f, (0, dt * steps), y0, method="DOP853", rtol=1e-13, atol=1e-13,
                    t_eval=dt * np.arange(steps + 1))
    assert np.max(np.abs(orbit - ref.y.T)) <= 2e-12
    h0 = mod.energy(y0, P)
    lam_ = list(system.parameters)[0]
    exact_h0 = float(system.energy.subs(dict(zip(system.states, y0.tolist()))).subs(lam_, value))
    assert abs(h0 - exact_h0) <= 1e-16
    drift = max(abs(mod.energy(y, P) - h0) for y in orbit)
    assert drift <= 1e-13, drift


def test_another_parameter_value_uses_the_same_generated_module():
    a = henon_heiles()
    b = a.with_(lam=0.25)
    assert codegen.load(a) is codegen.load(b)
    dy = np.empty(4)
    codegen.load(b).rhs(np.array([0.5, 0.5, 0.0, 0.0]), b.parameter_array(), dy)
    # dpx/dt = -x - 2 lam x y = -0.5 - 0.125
    assert dy[2] == -0.625 and dy[3] == -0.5


# ---------------------------------------------------------------------- the on-disk cache
def test_the_module_is_written_once_under_its_content_key_and_reused(tmp_path, monkeypatch):
    monkeypatch.setenv("EXPLORER_SYSTEMS_CACHE", str(tmp_path / "systems"))
    system, q, v = oscillator()
    mod = codegen.load(system)
    path = tmp_path / "systems" / f"oscillator_{codegen.module_key(system)}.py"
    assert mod.__file__ == str(path) and path.exists()
    stamp = path.stat().st_mtime_ns
    import sys

    del sys.modules[mod.__name__]       # as a new process would: found on disk, not rewritten
    again = codegen.load(system)
    assert again is not mod and again.__file__ == str(path) and path.stat().st_mtime_ns == stamp
    assert "taylor_coefficients" in path.read_text() and "def crossings_taylor" in path.read_text()
    other = System({q: v, v: -2 * q}, name="oscillator")
    assert codegen.module_key(other) != codegen.module_key(system)


def test_a_change_of_a_kernel_the_generated_code_calls_changes_the_module_key(tmp_path, monkeypatch):
    """numba's cache of the generated crossings integrator does not follow its callees in
    explorer.kernels and explorer.integrate.lane_parts: the key does, so a changed kernel gives a new
    module file."""
    system, _, _ = oscillator()
    key = codegen.module_key(system)
    kernels = tmp_path / "explorer"
    (kernels / "kernels").mkdir(parents=True)
    (kernels / "integrate").mkdir()
    (kernels / "kernels" / "taylor.py").write_text("a")
    (kernels / "integrate" / "simd.py").write_text("b")
    (kernels / "integrate" / "layout.py").write_text("d")
    (kernels / "integrate" / "lane_parts.py").write_text("e")
    (kernels / "_jit.py").write_text("c")
    monkeypatch.setattr(codegen, "__file__", str(kernels / "integrate" / "codegen.py"))
    codegen._callee_digest.cache_clear()
    try:
        first = codegen.module_key(system)
        assert first != key
        (kernels / "kernels" / "taylor.py").write_text("a changed")
        codegen._callee_digest.cache_clear()
        second = codegen.module_key(system)
        assert second not in (first, key)
        (kernels / "integrate" / "lane_parts.py").write_text("e changed")
        codegen._callee_digest.cache_clear()
        assert codegen.module_key(system) not in (first, second, key)
    finally:
        monkeypatch.undo()
        codegen._callee_digest.cache_clear()
    assert codegen.module_key(system) == key


def test_cache_directory_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.delenv("EXPLORER_SYSTEMS_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert codegen.cache_directory() == tmp_path / "explorer" / "systems"
    monkeypatch.setenv("EXPLORER_SYSTEMS_CACHE", str(tmp_path / "mine"))
    assert codegen.cache_directory() == tmp_path / "mine"


def test_an_operation_the_generator_does_not_know_is_refused():
    x = sp.Symbol("x")
    with pytest.raises(ParameterError, match="Abs"):
        System({x: sp.Abs(x)})


# ---------------------------------------------------------------------- variational equations
def test_variational_coefficients_are_the_derivative_of_the_state_coefficients():
    """D_k = d X_k / d x0 . d0: against a central difference of the generated state coefficients."""
    base = henon_heiles()
    var = codegen.load(base.variational(1))
    mod = codegen.load(base)
    P = base.parameter_array()
    order = 16
    x0 = np.array([0.1, -0.2, 0.35, 0.1])
    d0 = np.array([0.3, -0.5, 0.2, 0.7])
    Z = np.zeros((8, order + 1))
    Z[:4, 0], Z[4:, 0] = x0, d0
    var.taylor_coefficients(P, Z, order)
    eps = 1e-6
    plus, minus = np.zeros((4, order + 1)), np.zeros((4, order + 1))
    plus[:, 0], minus[:, 0] = x0 + eps * d0, x0 - eps * d0
    mod.taylor_coefficients(P, plus, order)
    mod.taylor_coefficients(P, minus, order)
    fd = (plus - minus) / (2 * eps)
    assert np.max(np.abs(Z[4:] - fd)) <= 1e-8 * np.max(np.abs(fd))


# ---------------------------------------------------------------------- the SIMD form
def lane_states(system, rng):
    """LANES states of ``system`` (rows of X[0]) in the domain of its operations."""
    from explorer.integrate.simd import LANES

    if system.name == "ad_rules":
        X0 = np.empty((system.dimension, LANES))
        X0[0] = rng.uniform(0.1, 0.4, LANES)
        X0[1] = rng.uniform(1.2, 1.6, LANES)
        X0[2:] = rng.uniform(0.4, 0.8, (system.dimension - 2, LANES))
        return X0
    return rng.uniform(-0.5, 0.5, (system.dimension, LANES))


@pytest.mark.parametrize("which", ["ad_rules", "henon_heiles", "chaplygin_variational1"])
def test_each_lane_of_the_simd_form_equals_the_scalar_recurrence_bit_for_bit(rules_module, which):
    from explorer.integrate.simd import LANES

    system = {"ad_rules": rules_module[0], "henon_heiles": henon_heiles(),
              "chaplygin_variational1": chaplygin.variational(vectors=1)}[which]
    # Chaplygin's as its indicators load it (tangent.indicators_module): the module the product runs
    mod = codegen.load(system, orbit=chaplygin.system() if which == "chaplygin_variational1" else None)
    P = system.parameter_array() if which != "chaplygin_variational1" else mp_.packed_params(
        mp_.FIGURE4.with_(mu=0.5))
    order = 18
    X0 = lane_states(system, np.random.default_rng(8))
    XL = np.zeros((order + 1, system.dimension, LANES))
    XL[0] = X0
    WL = np.zeros((order + 1, max(mod.N_WORK, 1), LANES))
    mod.taylor_coefficients_lanes(P, XL, order, WL)
    for lane in range(LANES):
        X = np.zeros((system.dimension, order + 1))
        X[:, 0] = X0[:, lane]
        mod.taylor_coefficients(P, X, order)
        assert np.all(np.isfinite(X))
        assert np.array_equal(XL[:, :, lane].T.view(np.uint64), X.view(np.uint64)), lane


def test_vector_arithmetic_is_written_as_simd_calls_with_scalars_splatted_and_scalar_arithmetic_kept():
    source = '''\
def f(P, X, W, order):
    s1 = P[0] * 2.0 - 1.0
    u2 = vget(X, 0, 0) * vget(X, 0, 1)
    acc = vzero()
    for j in range(order):
        acc = acc - (s1 * (order - j) - j) * u2
    vset(W, 0, 0, -acc / order)
'''
    body = codegen.vector_calls(source).splitlines()[1:]
    assert [line.strip() for line in body] == [
        "s1 = P[0] * 2.0 - 1.0",
        "u2 = vmul(vget(X, 0, 0), vget(X, 0, 1))",
        "acc = vzero()",
        "for j in range(order):",
        "acc = vsub(acc, vmul(vsplat(s1 * (order - j) - j), u2))",
        "vset(W, 0, 0, vdiv(vneg(acc), vsplat(order)))",
    ]


def test_every_simd_call_the_generated_recurrences_make_is_an_intrinsic_of_explorer_integrate_simd():
    from explorer.integrate import simd

    text = codegen.recurrence(chaplygin.variational(vectors=1)).lanes
    called = set(re.findall(r"\b(v[a-z_]+)\(", text))
    assert {"vadd", "vsub", "vmul", "vget", "vset"} <= called
    assert called <= codegen.VECTOR_RESULTS | {"vset"}
    assert all(callable(getattr(simd, name)) for name in codegen.VECTOR_RESULTS)


class _Counted:
    """A number whose arithmetic with series values counts itself in ``COUNTS`` (by the name of the
    vector intrinsic that does it on lanes); a plain float's arithmetic, a scalar's, is not counted."""

    COUNTS: dict = {}

    def __init__(self, x):
        self.x = x

    def _op(name, fn, swap=False):    # a factory of methods
        def op(a, b):
            _Counted.COUNTS[name] += 1
            a, b = (b, a) if swap else (a, b)
            return _Counted(fn(getattr(a, "x", a), getattr(b, "x", b)))
        return op

    __add__, __radd__ = _op("vadd", float.__add__), _op("vadd", float.__add__, True)
    __sub__, __rsub__ = _op("vsub", float.__sub__), _op("vsub", float.__sub__, True)
    __mul__, __rmul__ = _op("vmul", float.__mul__), _op("vmul", float.__mul__, True)
    __truediv__, __rtruediv__ = _op("vdiv", float.__truediv__), _op("vdiv", float.__truediv__, True)

    def __neg__(self):
        _Counted.COUNTS["vneg"] += 1
        return _Counted(-self.x)


@pytest.mark.parametrize("nvec", [0, 2])
def test_the_roofline_counts_of_the_simd_recurrence_are_the_scalar_recurrences_operations_on_series(nvec):
    """tools/gen_lanes.py's operation_counts (benchmarks/bench_roofline.py's flops per step), which runs
    the SIMD text with counting intrinsics, counts each operation of the scalar recurrence on a series
    value once: the same operations, run on one lane."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))
    import gen_lanes

    orbit = chaplygin.system()
    system = chaplygin.variational(vectors=nvec) if nvec else orbit
    r = codegen.recurrence(system, decomposition=codegen.decompose_extending(orbit, system))
    ns = {"np": np, "math": math, "njit": lambda *a, **k: a[0] if a and callable(a[0]) else (lambda f: f)}
    exec(compile(re.sub(r"^from explorer\..*$", "", r.scalar, flags=re.M), "<scalar>", "exec"), ns)
    order = 12
    X = np.full((system.dimension, order + 1), _Counted(0.0), dtype=object)
    X[:, 0] = [_Counted(0.5) for _ in range(system.dimension)]
    W = np.full((max(r.n_work, 1), order + 1), _Counted(0.0), dtype=object)
    _Counted.COUNTS = dict.fromkeys(("vadd", "vsub", "vmul", "vneg", "vdiv"), 0)
    ns["taylor_coefficients_into"](np.ones(9), X, order, W)
    assert _Counted.COUNTS["vmul"] > 0 and _Counted.COUNTS == gen_lanes.operation_counts(order, nvec)
