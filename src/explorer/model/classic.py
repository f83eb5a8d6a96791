"""Classic systems, ready made as :class:`~explorer.model.system.System` (docs/classic.md).

- :func:`henon_heiles`: Hénon & Heiles 1964 (Astron. J. 69, 73), states (x, y, px, py);
- :func:`pcr3bp`: the planar circular restricted three-body problem in the rotating frame, states
  (x, y, vx, vy), its energy the Jacobi constant C = 2 Omega - vx^2 - vy^2;
- :func:`double_pendulum`: two pendula in a plane, canonical states (th1, th2, p1, p2).

Each is a function of its parameters' values; ``system.with_(...)`` changes them without compiling
anything again.  The equations of the Hamiltonian systems are Hamilton's, ``sympy.diff`` of the
energy, so that the energy given is the one conserved.  Each declares the reversor that acts on
its usual section map (x = 0 with px > 0; y = 0 with vy > 0; th1 = 0 with dth1/dt > 0) as a
reflection, so that Greene's criterion and the symmetric periodic-orbit search take that map.
"""
from __future__ import annotations

import sympy as sp

from explorer.model.system import System

__all__ = ["ARENSTORF_MU", "ARENSTORF_PERIOD", "ARENSTORF_STATE", "HENON_HEILES_ENERGIES", "double_pendulum",
           "henon_heiles", "pcr3bp"]

#: the energies of the sections of Hénon & Heiles 1964 (x = 0 in the plane (y, py))
HENON_HEILES_ENERGIES = (1 / 12, 1 / 8, 1 / 6)

#: Arenstorf's periodic orbit of the restricted three-body problem, the test problem of Hairer,
#: Nørsett & Wanner, Solving Ordinary Differential Equations I (2nd ed. 1993), II.0 eq. (0.1)-(0.2):
#: mu, the start (x, y, vx, vy) and the period
ARENSTORF_MU = 0.012277471
ARENSTORF_STATE = (0.994, 0.0, 0.0, -2.00158510637908252240537862224)
ARENSTORF_PERIOD = 17.0652165601579625588917206249


def _hamiltonian(H, coordinates, momenta, parameters, name, reversor) -> System:
    """Hamilton's equations dq/dt = dH/dp, dp/dt = -dH/dq of ``H``, with ``H`` as the energy."""
    equations = {q: sp.diff(H, p) for q, p in zip(coordinates, momenta)}
    equations.update({p: -sp.diff(H, q) for q, p in zip(coordinates, momenta)})
    return System(equations, parameters=parameters, energy=H, name=name, reversor=reversor)


def henon_heiles(lam: float = 1.0) -> System:
    """H = (px^2 + py^2)/2 + (x^2 + y^2)/2 + lam (x^2 y - y^3/3) (Hénon & Heiles 1964 at lam = 1);
    states (x, y, px, py), parameter lam.  Bounded motion for 0 < E < 1/(6 lam^2).  H is even in x,
    so (x, y, px, py) -> (-x, y, px, -py) reverses time: on x = 0, px > 0 it is (y, py) -> (y, -py)."""
    x, y, px, py, lam_ = sp.symbols("x y px py lam")
    H = (px**2 + py**2) / 2 + (x**2 + y**2) / 2 + lam_ * (x**2 * y - y**3 / 3)
    return _hamiltonian(H, (x, y), (px, py), {lam_: lam}, "henon_heiles", {x: -x, y: y, px: px, py: -py})


def pcr3bp(mu: float = ARENSTORF_MU) -> System:
    """The planar circular restricted three-body problem in the frame rotating with the primaries
    (unit distance, unit angular velocity): masses 1 - mu at (-mu, 0) and mu at (1 - mu, 0),
    x'' - 2y' = dOmega/dx, y'' + 2x' = dOmega/dy with Omega = (x^2 + y^2)/2 + (1 - mu)/r1 + mu/r2
    (Szebehely 1967, Theory of Orbits, ch. 1).  States (x, y, vx, vy), parameter mu; the energy is
    the Jacobi constant C = 2 Omega - vx^2 - vy^2 (a section map's level is a value of C).  Its reversor
    (x, y, vx, vy) -> (x, -y, -vx, vy), the mirror in the line of the primaries with time reversed, is
    (x, vx) -> (x, -vx) on y = 0, vy > 0."""
    x, y, vx, vy, mu_ = sp.symbols("x y vx vy mu")
    r1 = sp.sqrt((x + mu_)**2 + y**2)
    r2 = sp.sqrt((x - 1 + mu_)**2 + y**2)
    omega = (x**2 + y**2) / 2 + (1 - mu_) / r1 + mu_ / r2
    equations = {x: vx, y: vy, vx: 2 * vy + sp.diff(omega, x), vy: -2 * vx + sp.diff(omega, y)}
    return System(equations, parameters={mu_: mu}, energy=2 * omega - vx**2 - vy**2, name="pcr3bp",
                  reversor={x: x, y: -y, vx: -vx, vy: vy})


def double_pendulum(m1: float = 1.0, m2: float = 1.0, l1: float = 1.0, l2: float = 1.0, g: float = 1.0) -> System:
    """Two pendula in a vertical plane (masses m1, m2 on massless rods l1, l2, gravity g), the
    angles th1, th2 from the downward vertical and their canonical momenta p1, p2:
    H = (m2 l2^2 p1^2 + (m1 + m2) l1^2 p2^2 - 2 m2 l1 l2 p1 p2 cos(th1 - th2))
        / (2 m2 l1^2 l2^2 (m1 + m2 sin^2(th1 - th2))) - (m1 + m2) g l1 cos th1 - m2 g l2 cos th2,
    the Legendre transform of the Lagrangian (p = M(th) dth/dt, M the mass matrix).  States
    (th1, th2, p1, p2), parameters m1, m2, l1, l2, g.  H is even in the angles, so (th1, th2, p1, p2)
    -> (-th1, -th2, p1, p2) reverses time: on th1 = 0, dth1/dt > 0 it is (th2, p2) -> (-th2, p2)."""
    th1, th2, p1, p2 = sp.symbols("th1 th2 p1 p2")
    m1_, m2_, l1_, l2_, g_ = sp.symbols("m1 m2 l1 l2 g")
    d = th1 - th2
    kinetic = ((m2_ * l2_**2 * p1**2 + (m1_ + m2_) * l1_**2 * p2**2 - 2 * m2_ * l1_ * l2_ * p1 * p2 * sp.cos(d))
               / (2 * m2_ * l1_**2 * l2_**2 * (m1_ + m2_ * sp.sin(d)**2)))
    H = kinetic - (m1_ + m2_) * g_ * l1_ * sp.cos(th1) - m2_ * g_ * l2_ * sp.cos(th2)
    return _hamiltonian(H, (th1, th2), (p1, p2), {m1_: m1, m2_: m2, l1_: l1, l2_: l2, g_: g}, "double_pendulum",
                        {th1: -th1, th2: -th2, p1: p1, p2: p2})
