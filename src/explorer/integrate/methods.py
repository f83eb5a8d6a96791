"""The method registry (docs/architecture.md, docs/methods.md): :data:`REGISTRY` maps a method
name to its :class:`Method`; what a method's kind selects (setting, preparation, loops) is one
:class:`Kind` of :data:`KINDS`.
"""
from __future__ import annotations

import importlib
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from explorer import model
from explorer.kernels import splitting
from explorer.kernels.taylor_order import order_for_tolerance
from explorer.model import validation

#: tolerances accepted by the adaptive methods (below ~ 50 eps the error control only chases
#: round-off)
MIN_TOL = 1e-16
MAX_TOL = 1e-2
# ---- default tolerances: one per purpose, named here once (docs/methods.md, "Default tolerances")
#: crossings of the section and chaos indicators
DEFAULT_TOL = 1e-13
#: the section map, evaluated hundreds of times (Newton, continuation, manifolds, rotation numbers)
MAP_TOL = 1e-15
#: the full system R1 with the body's position (trajectory; DOP853's rtol = atol)
TRAJECTORY_TOL = 1e-12
#: the step of the splitting methods when none is given, for every command
DEFAULT_DT = 0.05
#: a fixed step may turn the fastest motion of the orbit (model.max_rate) by at most half a turn
#: (Nyquist), else the orbit is not integrated (status UNRESOLVED; docs/methods.md)
MAX_STEP_PHASE = math.pi


@dataclass(frozen=True)
class Prepared:
    """A method with its setting validated: what its drivers need and what is recorded."""

    method: Method
    settings: dict
    tol: float = 0.0
    order: int = 0
    dt: float = 0.0
    flow_ids: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    fracs: np.ndarray = field(default_factory=lambda: np.zeros(0))


def _taylor(method: Method, tol: float) -> Prepared:
    order = order_for_tolerance(tol)
    return Prepared(method, {"tol": tol, "order": order}, tol=tol, order=order)


def _dop853(method: Method, tol: float) -> Prepared:
    return Prepared(method, {"rtol": tol, "atol": tol}, tol=tol)


def _split(method: Method, dt: float) -> Prepared:
    from explorer.model.equations import N_FLOWS

    ids, fracs = splitting.flow_sequence(splitting.SCHEMES[method.name][0], N_FLOWS)
    return Prepared(method, {"dt": dt, "order": method.order}, dt=dt,
                    flow_ids=np.ascontiguousarray(ids, dtype=np.int64),
                    fracs=np.ascontiguousarray(fracs, dtype=np.float64))


@dataclass(frozen=True)
class Kind:
    """A kind of integrator: everything the user layer selects by a method's ``kind``."""

    name: str
    setting: str
    prepare: Callable[[Method, float], Prepared]
    crossings: tuple[str, str]
    #: the one-vector indicator loop (None: the kind has ``tangent_ext``)
    tangent: tuple[str, str] | None
    args: tuple[str, ...]
    #: nvec -> the generated module whose indicator drivers run one or two deviation vectors and early stops
    tangent_ext: tuple[str, str] | None = None
    #: a run stopped at a step cap and continued from its carry gives the uninterrupted run's
    #: numbers (false for DOP853, whose continued rows differ in the last digits:
    #: tests/analysis/test_streaming.py)
    resumes_at_any_step: bool = True

    def loop(self, which: str):
        """The compiled loop ``which`` (``crossings``, ``tangent`` or ``tangent_ext``)."""
        module, name = getattr(self, which)
        return getattr(importlib.import_module(module), name)


#: every kind of integrator: a new kind is its loops and one entry here
KINDS: dict[str, Kind] = {k.name: k for k in (
    Kind("taylor", "tol", _taylor, ("explorer.integrate.lanes", "run_taylor_lanes_batch"),
         None, ("order",),
         tangent_ext=("explorer.integrate.tangent", "indicators_module")),
    Kind("dop853", "tol", _dop853, ("explorer.integrate.drivers", "run_dop853_batch"),
         ("explorer.integrate.tangent", "run_tangent_dop853_batch"), ("tol", "tol"),   # rtol = atol = tol
         resumes_at_any_step=False),
    Kind("split", "dt", _split, ("explorer.integrate.drivers", "run_split_batch"),
         ("explorer.integrate.tangent", "run_tangent_split_batch"), ("dt", "flow_ids", "fracs")),
)}


@dataclass(frozen=True)
class Method:
    """One integrator: ``kind`` names its :class:`Kind` in :data:`KINDS` (``taylor``, ``dop853``
    or ``split``); ``order`` the nominal order (None: chosen from the tolerance); ``reference``
    the paper it follows."""

    name: str
    kind: str
    order: int | None
    reference: str

    @property
    def loops(self) -> Kind:
        """Its kind's entry of :data:`KINDS`."""
        return KINDS[self.kind]

    @property
    def adaptive(self) -> bool:
        return self.setting == "tol"

    @property
    def setting(self) -> str:
        """The accuracy knob: ``tol`` (adaptive methods) or ``dt`` (fixed step)."""
        return self.loops.setting

    def prepare(self, *, tol=None, dt=None) -> Prepared:
        """Validate the method's setting (``tol`` in [MIN_TOL, MAX_TOL] or ``dt`` > 0; the other one
        too when given) and derive what its drivers need."""
        values = {"tol": tol, "dt": dt}
        for name, value in values.items():
            if name != self.setting and value is not None:
                _validate(name, value)
        return self.loops.prepare(self, _validate(self.setting, values[self.setting]))


def check_setting(name: str, value, label: str | None = None) -> float:
    """A tolerance in [MIN_TOL, MAX_TOL] (``name`` "tol") or a step > 0 ("dt"); ParameterError
    naming it as ``label`` (default ``name``) otherwise."""
    label = name if label is None else label
    if name == "tol":
        return validation.real(label, value, MIN_TOL, MAX_TOL)
    return validation.real(label, value, 0.0, lo_open=True)


_validate = check_setting


def unresolved(prep: Prepared, P, Y) -> np.ndarray:
    """Mask (N,) of the orbits of ``Y`` (N, 5) whose motion the fixed step of ``prep`` does not
    resolve: dt * model.max_rate(y) > ``MAX_STEP_PHASE``."""
    if prep.method.adaptive:
        return np.zeros(len(Y), bool)
    with np.errstate(over="ignore", invalid="ignore"):
        return ~(prep.dt * model.max_rate(P, Y) <= MAX_STEP_PHASE)


def _args(prep: Prepared) -> tuple:
    return tuple(getattr(prep, a) for a in prep.method.loops.args)


def run_crossings(prep: Prepared, Y0, P, cphi, sphi, direction, tmax, max_steps, carry, limits, data, count,
                  status, final, info):
    """Crossings of the section for every orbit of ``Y0`` (arrays filled in place), a block
    continued from ``carry`` up to ``limits`` (:mod:`explorer.integrate.drivers`)."""
    prep.method.loops.loop("crossings")(Y0, P, cphi, sphi, direction, tmax, *_args(prep), max_steps, carry,
                                        limits, data, count, status, final, info)


def start_carry(Y0, P, cphi, sphi, carry):
    """The carry of a run's first block (:func:`explorer.integrate.drivers.start_carry`: H0 and
    sin(phi - phi0) of each start state)."""
    from explorer.integrate import drivers

    drivers.start_carry(Y0, P, cphi, sphi, carry)


def run_tangent(prep: Prepared, Y0, V0, P, T, max_steps, hist_t, hist, res, status, final, steps, stop):
    """Chaos indicators (one deviation vector) for every orbit of ``Y0`` over [0, T]; an orbit still
    running when ``stop[0]`` is set ends with STATUS_CANCELLED at its next step (analysis.budget)."""
    prep.method.loops.loop("tangent")(Y0, V0, P, T, *_args(prep), max_steps, hist_t, hist, res, status,
                                      final, steps, stop)


REGISTRY: dict[str, Method] = {
    "taylor": Method("taylor", "taylor", None, "A. Jorba, M. Zou, Experiment. Math. 14 (2005) 99-117"),
    "dop853": Method("dop853", "dop853", 8, "E. Hairer, S. P. Nørsett, G. Wanner, Solving ODEs I, II.10"),
    **{name: Method(name, "split", order, ref) for name, (_w, order, ref) in
       ((n, splitting.SCHEMES[n][:3]) for n in splitting.SCHEMES)},
}
#: every method name, adaptive ones first
METHODS = tuple(REGISTRY)
ADAPTIVE_METHODS = tuple(n for n, m in REGISTRY.items() if m.adaptive)
SPLIT_METHODS = tuple(n for n, m in REGISTRY.items() if not m.adaptive)


def get(name) -> Method:
    """The method called ``name`` (ParameterError naming the known methods otherwise)."""
    if name not in REGISTRY:
        raise validation.ParameterError(f"method must be one of {', '.join(METHODS)}; got {name!r}")
    return REGISTRY[name]
