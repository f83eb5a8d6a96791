"""Crossings of the Poincaré section phi = phi0 for many orbits at once (user level).

:func:`crossings` validates its input, picks the compiled batch driver of the
method (:mod:`explorer.integrate.drivers`), runs it in parallel over orbits with numba
threads and returns a :class:`Crossings` whose status codes are already
named.  Arrays in, arrays out: no I/O here.

Methods
-------
``taylor``  adaptive Taylor series, order from ``tol`` (Jorba & Zou 2005);
            crossings are roots of the step's Taylor polynomial.
``dop853``  adaptive Dormand-Prince 8(5,3) (Hairer, Nørsett & Wanner, Solving
            ODEs I, II.5); crossings are roots of its 7th-order dense output.
``split2`` ... ``split8`` (and the variants in ``kernels.splitting.SCHEMES``)
            fixed-step symmetric compositions of the exact sub-flows of
            MODEL.md R4 (Strang; Yoshida 1990; Kahan & Li 1997); they keep the
            Casimir to round-off and the energy error bounded; crossings are
            roots in tau of g(Psi_tau(y)), Psi the composition step itself.
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field

import numpy as np

from explorer import model
from explorer._jit import get_num_threads, max_threads, set_num_threads
from explorer.integrate import methods
from explorer.integrate.methods import ADAPTIVE_METHODS, MAX_TOL, METHODS, MIN_TOL, SPLIT_METHODS
from explorer.kernels import STATUS_NAMES, Status
from explorer.model import ParameterError, validation

__all__ = ["ADAPTIVE_METHODS", "DEFAULT_DT", "DEFAULT_MAX_STEPS", "DEFAULT_TOL", "MAX_TOL", "METHODS", "MIN_TOL",
           "SPLIT_METHODS", "Crossings", "crossings", "energy_warning", "max_energy_error", "section_crossings"]

DEFAULT_TOL = 1e-13
DEFAULT_DT = 0.05
DEFAULT_MAX_STEPS = 10**9
#: a run whose energy error exceeds this fraction of max(|h|, 1) gets a warning: its step
#: (splitting) or tolerance is too coarse for the scene to trust the section's fine structure
ENERGY_WARN_REL = 1e-6


@dataclass(frozen=True)
class Crossings:
    """Result of :func:`crossings` for N orbits and up to K crossings each.

    data[i, k] = (t, p1, p2, M, H - H0) for k < count[i]; rows beyond are NaN.
    status[i] is a code of ``kernels.STATUS_*``; ``status_name(i)`` names it.
    final[i] is the state where orbit i stopped; info[i] = (t_end, steps, Casimir error).
    """

    data: np.ndarray
    count: np.ndarray
    status: np.ndarray
    final: np.ndarray
    info: np.ndarray
    method: str
    settings: dict = field(default_factory=dict)

    def orbit(self, i: int) -> np.ndarray:
        """The crossings of orbit i as an array (count_i, 5)."""
        return self.data[i, : self.count[i]]

    def status_name(self, i: int) -> str:
        return STATUS_NAMES[int(self.status[i])]

    def status_of(self, i: int) -> Status:
        """Why orbit i stopped, as a :class:`~explorer.kernels.Status`."""
        return Status(int(self.status[i]))


def max_energy_error(data) -> float:
    """max |H - H0| over the crossings in ``data`` (rows (t, p1, p2, M, H - H0), NaN padding
    ignored); 0.0 if there are none."""
    dh = np.abs(np.asarray(data, dtype=np.float64)[..., 4])
    dh = dh[np.isfinite(dh)]
    return float(dh.max()) if dh.size else 0.0


def energy_warning(max_dh: float, h: float, setting: str) -> str | None:
    """A one-line warning when the energy error max_dh exceeds ENERGY_WARN_REL * max(|h|, 1),
    naming the setting to refine; None otherwise."""
    limit = ENERGY_WARN_REL * max(abs(h), 1.0)
    if max_dh <= limit:
        return None
    return (f"energy error up to {max_dh:.2e} (> {limit:.0e} = {ENERGY_WARN_REL:g} x max(|h|, 1)): "
            f"{setting} is too coarse for this orbit; refine it to trust the section")


def crossings(params, y0, n_crossings: int, *, method: str = "taylor", tol: float = DEFAULT_TOL,
              dt: float | None = None, tmax: float | None = None, max_steps: int = DEFAULT_MAX_STEPS,
              phi0: float = math.pi, direction: int = 1, threads: int | None = None) -> Crossings:
    """Integrate each initial state of ``y0`` ((N, 5) or (5,)) until it has crossed the section
    phi = phi0 ``n_crossings`` times in ``direction`` (+1: dphi/dt > 0, -1: < 0, 0: both), or until
    its time budget ``tmax`` (default 100 * n_crossings) or step budget ``max_steps`` runs out.

    ``tol`` is the tolerance of the adaptive methods, ``dt`` the fixed step of the splitting
    methods (default 0.05).  ``threads`` sets numba's thread count for this call (default: all).
    A start point lying on the section is not reported as a crossing.
    """
    P = validation.packed_params(params)
    m = methods.get(method)
    if not isinstance(n_crossings, numbers.Integral) or n_crossings < 1:
        raise ParameterError(f"crossings must be an integer >= 1, got {n_crossings!r}")
    if direction not in (-1, 0, 1):
        raise ParameterError(f"direction must be +1, -1 or 0 (both), got {direction!r}")
    phi0 = float(phi0)
    if not math.isfinite(phi0):
        raise ParameterError(f"phi0 must be finite, got {phi0!r}")
    tmax = 100.0 * n_crossings if tmax is None else validation.real("tmax", tmax, 0.0, lo_open=True)
    if not isinstance(max_steps, numbers.Integral) or max_steps < 1:
        raise ParameterError(f"max_steps must be an integer >= 1, got {max_steps!r}")
    Y0 = np.ascontiguousarray(np.atleast_2d(np.asarray(y0, dtype=np.float64)))
    if Y0.ndim != 2 or Y0.shape[1] != model.STATE_DIM:
        raise ParameterError(f"y0 must have shape (N, 5) = (p1, p2, M, g1, g2) per orbit, got {np.shape(y0)}")
    if not np.all(np.isfinite(Y0)):
        i = int(np.flatnonzero(~np.all(np.isfinite(Y0), axis=1))[0])
        raise ParameterError(f"y0 must be finite; orbit {i} has {Y0[i].tolist()}")
    with np.errstate(over="ignore", invalid="ignore"):
        H0 = model.energy(P, Y0)
    if not np.all(np.isfinite(H0)):
        i = int(np.flatnonzero(~np.isfinite(H0))[0])
        raise ParameterError(f"y0 must have a finite energy; orbit {i} has H = {H0[i]!r}")
    g1, g2 = model.section_gamma(phi0)
    sphi, cphi = g1, g2
    N, K = Y0.shape[0], int(n_crossings)
    data = np.full((N, K, 5), np.nan)
    count = np.zeros(N, np.int64)
    status = np.zeros(N, np.int64)
    final = np.zeros((N, 5))
    info = np.zeros((N, 3))
    settings = {"method": method, "phi0": phi0, "direction": int(direction), "tmax": tmax,
                "max_steps": int(max_steps), "n_crossings": K}
    old_threads = get_num_threads()
    if threads is not None:
        set_num_threads(validation.threads(threads, max_threads()))
    try:
        prep = m.prepare(tol=tol, dt=DEFAULT_DT if dt is None else dt)
        settings.update(prep.settings)
        methods.run_crossings(prep, Y0, P, cphi, sphi, int(direction), tmax, int(max_steps), data, count, status,
                              final, info)
    finally:
        if threads is not None:
            set_num_threads(old_threads)
    return Crossings(data, count, status, final, info, method, settings)


def section_crossings(params, p1, p2, h: float, n_crossings: int, *, phi0: float = math.pi,
                      direction: int = 1, **kwargs) -> Crossings:
    """Start orbits on the section phi = phi0 at energy h from the points (p1, p2) (M from the
    energy, MODEL.md R9; sign of M from ``direction``) and return their next crossings."""
    h = float(h)
    if not math.isfinite(h):
        raise ParameterError(f"h must be finite, got {h!r}")
    Y0 = model.section_state(params, p1, p2, h, phi0, direction if direction != 0 else 1)
    return crossings(params, Y0, n_crossings, phi0=phi0, direction=direction, **kwargs)
