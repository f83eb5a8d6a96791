"""The physics a reader checks against docs/model.md (R1-R11), in plain numpy, vectorised over
the last axis of y = (p1, p2, M, g1, g2), (g1, g2) = (sin phi, cos phi) (R3).  :data:`PARAMETERS`
is the one table of the model parameters (docs/model.md, "Notation"); the compiled field is
:mod:`explorer.model.equations`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

import numpy as np

from explorer.model.validation import ParameterError, magnitude, real


@dataclass(frozen=True)
class Parameter:
    """One model parameter: its row of the table "Notation" (docs/model.md) and everything the
    layers show of it."""

    name: str
    symbol: str
    latex: str
    meaning: str
    help: str
    constraint: str = ""
    why: str = ""


#: the model parameters in the order of the packed vector ``P`` handed to the kernels
PARAMETERS = (
    Parameter("a1", "a1", "a_1", "added mass along body axis 1", "added mass along axis 1 (> 0)", "positive",
              "a mass or moment of inertia"),
    Parameter("a2", "a2", "a_2", "added mass along body axis 2", "added mass along axis 2 (> 0)", "positive",
              "a mass or moment of inertia"),
    Parameter("b", "b", "b", "added moment of inertia", "added moment of inertia (> 0)", "positive",
              "a mass or moment of inertia"),
    Parameter("lam", "λ", r"\lambda", "circulation x density (lambda = I rho)", "circulation x density (!= 0)",
              "nonzero",
              "the reduced system (docs/model.md R3) needs circulation (lam = 0 is the full system R1 only)"),
    Parameter("chi", "χ", r"\chi", "circulation-asymmetry term, s = (chi, zeta)", "asymmetry term chi"),
    Parameter("zeta", "ζ", r"\zeta", "circulation-asymmetry term, s = (chi, zeta)", "asymmetry term zeta"),
    Parameter("mu", "μ", r"\mu", "weight", "weight (>= 0)", "nonnegative", "the weight"),
    Parameter("xi", "ξ", r"\xi", "centre of mass in body axes, r = (xi, eta)", "centre of mass xi"),
    Parameter("eta", "η", r"\eta", "centre of mass in body axes, r = (xi, eta)", "centre of mass eta"),
)
PARAM_NAMES = tuple(p.name for p in PARAMETERS)
#: name -> Parameter
PARAMETER = {p.name: p for p in PARAMETERS}
#: number of model parameters (the length of the packed vector)
N_PARAMS = len(PARAMETERS)
A1, A2, B, LAM, CHI, ZETA, MU, XI, ETA = (PARAM_NAMES.index(n) for n in
                                          ("a1", "a2", "b", "lam", "chi", "zeta", "mu", "xi", "eta"))
__all__ = [
    "A1",
    "A2",
    "B",
    "LAM",
    "CHI",
    "ZETA",
    "MU",
    "XI",
    "ETA",
    "P1",
    "P2",
    "M",
    "G1",
    "G2",
    "PARAM_NAMES",
    "PARAMETERS",
    "PARAMETER",
    "N_PARAMS",
    "Parameter",
    "STATE_DIM",
    "ParameterError",
    "Params",
    "FIGURE4",
    "FIGURE4_H",
    "packed_params",
    "with_value",
    "energy",
    "energy_gradient",
    "energy_full",
    "casimir",
    "rhs",
    "chaplygin_integral",
    "kozlov_integral",
    "case3_integral",
    "hess_eta",
    "hess_function",
    "section_gamma",
    "section_M2",
    "is_admissible",
    "allowed_ellipse",
    "section_state",
    "describe_region",
    "max_rate",
]

# Layout of the reduced state (docs/model.md R3).
P1, P2, M, G1, G2 = range(5)
STATE_DIM = 5


@dataclass(frozen=True)
class Params:
    """Model parameters of Chaplygin's equations (docs/model.md, R1/R3), validated on construction
    from :data:`PARAMETERS` (finite; a1, a2, b > 0; mu >= 0; lam != 0)."""

    a1: float = 1.0
    a2: float = 0.5
    b: float = 2.0
    lam: float = 1.0
    chi: float = 0.0
    zeta: float = 0.0
    mu: float = 0.0
    xi: float = 0.0
    eta: float = 0.0

    def __post_init__(self):
        for f in fields(self):
            object.__setattr__(self, f.name, magnitude(f.name, getattr(self, f.name)))
        for p in PARAMETERS:
            check_constraint(p, getattr(self, p.name))

    def as_array(self) -> np.ndarray:
        """Packed float64 vector [a1, a2, b, lam, chi, zeta, mu, xi, eta] for the kernels."""
        return np.array([getattr(self, n) for n in PARAM_NAMES], dtype=np.float64)

    def as_dict(self) -> dict:
        return {n: getattr(self, n) for n in PARAM_NAMES}

    def with_(self, **changes) -> Params:
        """A copy with some parameters changed (validated again)."""
        return replace(self, **changes)

    @classmethod
    def from_array(cls, P) -> Params:
        return cls(**{n: float(P[i]) for i, n in enumerate(PARAM_NAMES)})


if tuple(f.name for f in fields(Params)) != PARAM_NAMES:
    raise ImportError("explorer.model.parameters: the fields of Params must be PARAM_NAMES in order")


def check_constraint(p: Parameter, value: float) -> None:
    """Raise ParameterError naming ``p`` if the finite ``value`` violates its constraint."""
    if p.constraint == "positive" and not value > 0.0:
        raise ParameterError(f"{p.name} must be > 0 ({p.why}), got {value!r}")
    if p.constraint == "nonnegative" and not value >= 0.0:
        raise ParameterError(f"{p.name} must be >= 0 ({p.why}), got {value!r}")
    if p.constraint == "nonzero" and value == 0.0:
        raise ParameterError(f"{p.name} must be nonzero: {p.why}")


#: docs/model.md R9: the scene of the seed's Figure 4 (xi, eta not given: 0).
FIGURE4 = Params(a1=1.0, a2=0.5, b=2.0, lam=1.0, chi=0.0, zeta=0.0, mu=0.0, xi=0.0, eta=0.0)
#: docs/model.md R9: the energy level of Figure 4.
FIGURE4_H = 2.0


def packed_params(params) -> np.ndarray:
    """The packed float64 vector (a1, a2, b, lam, chi, zeta, mu, xi, eta) of a parameter set,
    validated (docs/model.md R3: a1, a2, b > 0, lam != 0, all finite), of a :class:`Params`, a
    mapping of names (the others from Figure 4) or a sequence of 9 numbers."""
    if isinstance(params, Params):
        return params.as_array()
    if isinstance(params, dict):
        return Params(**params).as_array()
    return Params.from_array(params).as_array()


def with_value(params, h: float, name: str, value):
    """``(params, h)`` with one model parameter or the energy ``h`` (``name == "h"``) replaced."""
    if name == "h":
        return params, real("h", value)
    return params.with_(**{name: real(name, value)}), h


def energy(params, y) -> np.ndarray:
    """docs/model.md R3: H = 1/2(p1^2/a1 + p2^2/a2 + M^2/b) - (mu/lam)(p - s, J g) + mu (r, g),
    with (p - s, J g) = (p1 - chi) g2 - (p2 - zeta) g1."""
    P = packed_params(params)
    y = np.asarray(y, dtype=np.float64)
    p1, p2, m, g1, g2 = y[..., P1], y[..., P2], y[..., M], y[..., G1], y[..., G2]
    kinetic = 0.5 * (p1 * p1 / P[A1] + p2 * p2 / P[A2] + m * m / P[B])
    pJg = (p1 - P[CHI]) * g2 - (p2 - P[ZETA]) * g1
    return kinetic - (P[MU] / P[LAM]) * pJg + P[MU] * (P[XI] * g1 + P[ETA] * g2)


def energy_gradient(params, y) -> np.ndarray:
    """grad H of docs/model.md R3 (analytic), along the last axis of y = (p1, p2, M, g1, g2):
    (p1/a1 - k g2, p2/a2 + k g1, M/b, k (p2 - zeta) + mu xi, -k (p1 - chi) + mu eta), k = mu/lam."""
    P = packed_params(params)
    y = np.asarray(y, dtype=np.float64)
    p1, p2, m, g1, g2 = y[..., P1], y[..., P2], y[..., M], y[..., G1], y[..., G2]
    k = P[MU] / P[LAM]
    return np.stack([p1 / P[A1] - k * g2, p2 / P[A2] + k * g1, m / P[B],
                     k * (p2 - P[ZETA]) + P[MU] * P[XI], -k * (p1 - P[CHI]) + P[MU] * P[ETA]], axis=-1)


def energy_full(P, y) -> np.ndarray:
    """docs/model.md R1 (numpy twin of :func:`explorer.model.equations.energy_full`):
    H = 1/2(p1^2/a1 + p2^2/a2 + M^2/b) + mu (y + xi g1 + eta g2), along the last axis of the full
    state (p1, p2, M, g1, g2, x, y); ``P`` is not validated (R1 allows lam = 0)."""
    P = np.asarray(P, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    p1, p2, m, g1, g2, yy = y[..., P1], y[..., P2], y[..., M], y[..., G1], y[..., G2], y[..., 6]
    kin = 0.5 * (p1 ** 2 / P[A1] + p2 ** 2 / P[A2] + m ** 2 / P[B])
    return kin + P[MU] * (yy + P[XI] * g1 + P[ETA] * g2)


def casimir(y) -> np.ndarray:
    """docs/model.md R3: the Casimir g1^2 + g2^2 (equal to 1 on physical states)."""
    y = np.asarray(y, dtype=np.float64)
    return y[..., G1] ** 2 + y[..., G2] ** 2


def rhs(params, y) -> np.ndarray:
    """docs/model.md R3 (numpy twin of :func:`explorer.model.equations.rhs`):
    dp/dt = (M/b) J (p - s) - mu g - lam J A p;  dM/dt = (p - s, J A p) - mu (r, J g);
    dg/dt = (M/b) J g, with J v = (v2, -v1)."""
    P = packed_params(params)
    y = np.asarray(y, dtype=np.float64)
    p1, p2, m, g1, g2 = y[..., P1], y[..., P2], y[..., M], y[..., G1], y[..., G2]
    w = m / P[B]
    out = np.empty_like(y)
    out[..., P1] = w * (p2 - P[ZETA]) - P[MU] * g1 - P[LAM] * p2 / P[A2]
    out[..., P2] = -w * (p1 - P[CHI]) - P[MU] * g2 + P[LAM] * p1 / P[A1]
    out[..., M] = (p1 - P[CHI]) * p2 / P[A2] - (p2 - P[ZETA]) * p1 / P[A1] - P[MU] * (P[XI] * g2 - P[ETA] * g1)
    out[..., G1] = w * g2
    out[..., G2] = -w * g1
    return out


# ---------------------------------------------------------------- integrals (R5, R6)
def chaplygin_integral(params, y):
    """docs/model.md R5 case 1 (mu = 0): F = 1/2 |p - s|^2 + lam M."""
    P = packed_params(params)
    y = np.asarray(y, dtype=np.float64)
    return 0.5 * ((y[..., P1] - P[CHI]) ** 2 + (y[..., P2] - P[ZETA]) ** 2) + P[LAM] * y[..., M]


def kozlov_integral(params, y):
    """docs/model.md R5 case 2 (chi = zeta = 0, a1 = a2): F = M^2/(2b) + mu (r, g)."""
    P = packed_params(params)
    y = np.asarray(y, dtype=np.float64)
    return y[..., M] ** 2 / (2 * P[B]) + P[MU] * (P[XI] * y[..., G1] + P[ETA] * y[..., G2])


def case3_integral(params, y):
    """docs/model.md R5 case 3 (chi = -lam eta, zeta = lam xi, a1 = a2 = 1):
    F = 1/2 M^2 - lam b (M + (p, J r)) + mu b (r, g), with (p, J r) = p1 eta - p2 xi."""
    P = packed_params(params)
    y = np.asarray(y, dtype=np.float64)
    pJr = y[..., P1] * P[ETA] - y[..., P2] * P[XI]
    return (0.5 * y[..., M] ** 2 - P[LAM] * P[B] * (y[..., M] + pJr)
            + P[MU] * P[B] * (P[XI] * y[..., G1] + P[ETA] * y[..., G2]))


def hess_eta(params) -> float:
    """docs/model.md R5 case 4: the positive eta = sqrt(b (1/a2 - 1/a1)) of the Hess relation (a1 > a2)."""
    P = packed_params(params)
    if not P[A1] > P[A2]:
        raise ParameterError("the Hess relation needs a1 > a2")
    return math.sqrt(P[B] * (1.0 / P[A2] - 1.0 / P[A1]))


def hess_function(params, y):
    """docs/model.md R5 case 4 (chi = zeta = xi = 0, eta^2 = b(1/a2 - 1/a1)):
    F = M + eta p1 - lam b / a2, with dF/dt = (eta/b) p2 F."""
    P = packed_params(params)
    y = np.asarray(y, dtype=np.float64)
    return y[..., M] + P[ETA] * y[..., P1] - P[LAM] * P[B] / P[A2]


# ---------------------------------------------------------------- time scales (R3, R4)
def max_rate(params, y) -> np.ndarray:
    """An a-priori bound of the fastest rate (1/time) of the motion on the energy level of ``y``,
    for the whole orbit: the step of a fixed-step method resolves the motion only if
    dt * max_rate is small (the bound: docs/methods.md)."""
    P = packed_params(params)
    y = np.asarray(y, dtype=np.float64)
    k = P[MU] / abs(P[LAM]) if P[MU] != 0.0 else 0.0
    s = math.hypot(P[CHI], P[ZETA])
    r = math.hypot(P[XI], P[ETA])
    a, a_min = max(P[A1], P[A2]), min(P[A1], P[A2])
    with np.errstate(over="ignore", invalid="ignore"):
        E = np.maximum(energy(P, y) + k * s + P[MU] * r, 0.0)
        q = a * (k + np.sqrt(k * k + 2.0 * E / a))
        m = np.sqrt(2.0 * P[B] * (E + 0.5 * a * k * k))
        return np.maximum.reduce([m / P[B], np.full(np.shape(E), abs(P[LAM]) / a_min),
                                  np.sqrt((q + s) * q / (a_min * P[B])), np.full(np.shape(E),
                                                                                 math.sqrt(P[MU] * r / P[B]))])


# ---------------------------------------------------------------- the section (R9)
def section_gamma(phi0: float):
    """(g1, g2) = (sin phi0, cos phi0), exact at phi0 = pi (g = (0, -1))."""
    if phi0 == math.pi:
        return 0.0, -1.0
    return math.sin(phi0), math.cos(phi0)


def section_M2(params, p1, p2, h, phi0=math.pi):
    """M^2 on the section phi = phi0 at energy h (docs/model.md R9, generalised to any phi0):
    M^2 = 2b (h - 1/2(p1^2/a1 + p2^2/a2) + (mu/lam)(p - s, J g) - mu (r, g))."""
    P = packed_params(params)
    g1, g2 = section_gamma(phi0)
    p1 = np.asarray(p1, dtype=np.float64)
    p2 = np.asarray(p2, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        kinetic = 0.5 * (p1 * p1 / P[A1] + p2 * p2 / P[A2])
        pJg = (p1 - P[CHI]) * g2 - (p2 - P[ZETA]) * g1
        return 2.0 * P[B] * (h - kinetic + (P[MU] / P[LAM]) * pJg - P[MU] * (P[XI] * g1 + P[ETA] * g2))


def is_admissible(params, p1, p2, h, phi0=math.pi):
    """True where the point (p1, p2) lies in the allowed region of the section (M^2 >= 0)."""
    return section_M2(params, p1, p2, h, phi0) >= 0.0


def allowed_ellipse(params, h, phi0=math.pi):
    """The allowed region of the section (docs/model.md R9) as ``(c1, c2, r1, r2)``, the ellipse
    ((p1-c1)/r1)^2 + ((p2-c2)/r2)^2 <= 1, or ``None`` when it is empty."""
    P = packed_params(params)
    h = magnitude("h", h)
    g1, g2 = section_gamma(phi0)
    k1 = (P[MU] / P[LAM]) * g2
    k2 = (P[MU] / P[LAM]) * g1
    c1, c2 = P[A1] * k1, -P[A2] * k2
    R = (h - P[MU] * (P[XI] * g1 + P[ETA] * g2) - (P[MU] / P[LAM]) * (P[CHI] * g2 - P[ZETA] * g1)
         + 0.5 * P[A1] * k1 * k1 + 0.5 * P[A2] * k2 * k2)
    if R < 0.0:
        return None
    return c1, c2, math.sqrt(2.0 * P[A1] * R), math.sqrt(2.0 * P[A2] * R)


def section_state(params, p1, p2, h, phi0=math.pi, direction=1):
    """Full states y = (p1, p2, M, g1, g2) on phi = phi0 at energy h, M = +-sqrt(M^2) by
    ``direction``; ParameterError naming the first point outside the allowed region."""
    h = magnitude("h", h)
    p1 = np.atleast_1d(np.asarray(p1, dtype=np.float64))
    p2 = np.atleast_1d(np.asarray(p2, dtype=np.float64))
    p1, p2 = np.broadcast_arrays(p1, p2)
    m2 = section_M2(params, p1, p2, h, phi0)
    bad = ~(m2 >= 0.0)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise ParameterError(
            f"start point (p1, p2) = ({p1[i]:g}, {p2[i]:g}) lies outside the allowed region of the section "
            f"at h = {h:g} (M^2 = {m2[i]:.3g} < 0); allowed: {describe_region(params, h, phi0)}")
    g1, g2 = section_gamma(phi0)
    y = np.empty(p1.shape + (STATE_DIM,), dtype=np.float64)
    y[..., P1] = p1
    y[..., P2] = p2
    y[..., M] = (1.0 if direction >= 0 else -1.0) * np.sqrt(m2)
    y[..., G1] = g1
    y[..., G2] = g2
    return y


def describe_region(params, h, phi0=math.pi) -> str:
    e = allowed_ellipse(params, h, phi0)
    if e is None:
        return "none (the region is empty at this energy)"
    c1, c2, r1, r2 = e
    return f"({_shifted('p1', c1)}/{r1:.6g})^2 + ({_shifted('p2', c2)}/{r2:.6g})^2 <= 1"


def _shifted(name: str, c: float) -> str:
    """``name - c`` with its sign written once: ``(p1 + 0.1)`` for c = -0.1, ``p2`` for c = 0 or -0."""
    text = f"{abs(c):.6g}"
    if float(text) == 0.0:
        return name
    return f"({name} {'+' if c < 0 else '-'} {text})"
