"""The Systems the tests share (docs/systems.md): one definition of each, so that the suite generates
and compiles one module per system (explorer.integrate.codegen keys a module by the system's content
hash and its name).  The examples of docs/systems.md write Hénon–Heiles with the same equations and
name, so they use the same modules (tests/model/test_system.py checks the hashes)."""
import sympy as sp

import explorer as ex
from explorer.model import classic

x, y, px, py, lam = sp.symbols("x y px py lam")
#: Hénon–Heiles is even in x: (x, y, px, py) -> (-x, y, px, -py) reverses time (classic's reversor)
HH_REVERSOR = {x: -x, y: y, px: px, py: -py}


def henon_heiles(value=1.0):
    """:func:`explorer.model.classic.henon_heiles` at lam = ``value``: states (x, y, px, py), its
    reversor :data:`HH_REVERSOR`."""
    return classic.henon_heiles(value)


def henon_heiles_without_reversor(value=1.0):
    """Hénon–Heiles declaring no reversor (what needs one refuses its map)."""
    hh = classic.henon_heiles(value)
    return ex.System(dict(zip(hh.states, hh.rhs)), parameters=dict(hh.parameters), energy=hh.energy, name=hh.name)


def oscillator():
    """dq/dt = v, dv/dt = -q: no energy declared.  Returns the system and its symbols q, v."""
    q, v = sp.symbols("q v")
    return ex.System({q: v, v: -q}, name="oscillator"), q, v


def pole():
    """ds/dt = 1, dw/dt = 1/s: w has a pole at s = 0.  Returns the system and its symbols s, w."""
    s, w = sp.symbols("s w")
    return ex.System({s: sp.Integer(1), w: 1 / s}, name="pole"), s, w



def henon_heiles_map(energy=1 / 8):
    """The section map of :func:`henon_heiles` on x = 0 (px > 0) at ``energy``, coords (y, py), px from
    the energy (docs/systems.md "Section map"; ``explorer serve --system tests.systems:henon_heiles_map``)."""
    return ex.SectionMap(henon_heiles(), energy, section=x, direction=+1, coords=(y, py), solve=px)
