"""Chaplygin's reduced equations (docs/model.md R3) as a :class:`~explorer.model.system.System`,
for the Taylor generator (docs/systems.md): the state (p1, p2, M, g1, g2), the parameters the
entries of the packed vector in :data:`~explorer.model.parameters.PARAM_NAMES` order (so the
generated code reads ``packed_params(params)`` as its P), and the energy H of R3.

The right-hand sides are polynomials in the state, collected by monomial (``sympy.Poly``): each
product of two state variables is one Cauchy product, scaled once (M p2, M p1, p1 p2, M g2, M g1:
five per order), and the variational equations likewise (one product per pair of a state variable
and a deviation).  tools/gen_lanes.py writes the engine's recurrences from these systems.
"""
from __future__ import annotations

import sympy as sp

from explorer.model.parameters import FIGURE4, PARAM_NAMES, packed_params
from explorer.model.system import System

__all__ = ["PARAMETERS", "STATES", "system", "variational"]

#: the state symbols (p1, p2, M, g1, g2), (g1, g2) = (sin phi, cos phi)
STATES = sp.symbols("p1 p2 M g1 g2")
#: the parameter symbols, in the order of the packed vector P
PARAMETERS = sp.symbols(" ".join(PARAM_NAMES))
#: each parameter's symbol by its name (the packed order may change; docs/contributing.md)
_SYMBOL = dict(zip(PARAM_NAMES, PARAMETERS))


def equations():
    """The right-hand sides of R3, {state: derivative}, and the energy H."""
    p1, p2, m, g1, g2 = STATES
    a1, a2, b, lam, chi, zeta, mu, xi, eta = (_SYMBOL[n] for n in "a1 a2 b lam chi zeta mu xi eta".split())
    w = m / b
    # docs/model.md R3, expanded: dp/dt = (M/b) J (p - s) - mu g - lam J A p
    f1 = m * p2 / b - zeta * w - mu * g1 - lam * p2 / a2
    f2 = -m * p1 / b + chi * w - mu * g2 + lam * p1 / a1
    # dM/dt = (p - s, J A p) - mu (r, J g) = (1/a2 - 1/a1) p1 p2 - (chi/a2) p2 + (zeta/a1) p1 - mu (xi g2 - eta g1)
    f3 = (1 / a2 - 1 / a1) * (p1 * p2) - chi / a2 * p2 + zeta / a1 * p1 - mu * xi * g2 + mu * eta * g1
    f4 = m * g2 / b
    f5 = -m * g1 / b
    energy = (sp.Rational(1, 2) * (p1 ** 2 / a1 + p2 ** 2 / a2 + m ** 2 / b)
              - mu / lam * ((p1 - chi) * g2 - (p2 - zeta) * g1) + mu * (xi * g1 + eta * g2))
    return {x: _collected(f, STATES) for x, f in zip(STATES, (f1, f2, f3, f4, f5))}, energy


def _collected(f, symbols):
    """``f`` as a sum of monomials in ``symbols``, each with its coefficient (a parameter expression)."""
    return sp.Poly(f, *symbols).as_expr()


def system(params=FIGURE4) -> System:
    """R3 as a System with the values of ``params`` (a :class:`~explorer.model.parameters.Params`,
    a mapping or 9 numbers, validated by :func:`~explorer.model.parameters.packed_params`)."""
    P = packed_params(params)
    eqs, energy = equations()
    return System(eqs, parameters=dict(zip(PARAMETERS, (float(v) for v in P))), energy=energy, name="chaplygin")


def variational(params=FIGURE4, vectors: int = 1) -> System:
    """:meth:`System.variational` of :func:`system` (the symbolic Jacobian times each deviation
    vector), its right-hand sides collected by monomial of the state and the deviations."""
    v = system(params).variational(vectors)
    return System({x: _collected(f, v.states) for x, f in zip(v.states, v.rhs)}, parameters=dict(v.parameters),
                  name=v.name)
