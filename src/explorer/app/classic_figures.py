"""Figures of the classic systems of :mod:`explorer.model.classic` (docs/classic.md): the Hénon–Heiles
sections at E = 1/12, 1/8, 1/6, Arenstorf's orbit of the restricted three-body problem and a section
of the double pendulum.  Each function computes with explorer and returns a matplotlib Figure;
``python -m explorer.app.classic_figures [--out-dir figures] [--quick]`` writes
``figures/classic_*.png``."""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from explorer.analysis.sections import crossings
from explorer.analysis.system_flow import flow
from explorer.analysis.system_section_map import SystemSectionMap
from explorer.app.figures import _matplotlib
from explorer.model import ParameterError, classic

__all__ = ["arenstorf_figure", "arenstorf_orbit", "double_pendulum_boundary", "double_pendulum_figure",
           "henon_heiles_boundary", "henon_heiles_figure", "main", "write_figures"]

#: resolution of the PNGs
DPI = 150
#: the energy of the double pendulum of the figure (unit masses, lengths and g: the bottom is -3, and th2
#: turns over from -1): a mixed section
PENDULUM_ENERGY = -1.4
#: the Taylor tolerance of the figures' orbits
TOL = 1e-13
_RC = {"mathtext.fontset": "dejavusans", "axes.linewidth": 0.6, "font.size": 9, "xtick.labelsize": 8,
       "ytick.labelsize": 8, "xtick.direction": "in", "ytick.direction": "in"}


def _figure(figsize):
    _matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def henon_heiles_boundary(E: float, lam: float = 1.0, n: int = 400):
    """The curve py^2 + y^2 - 2 lam y^3/3 = 2E bounding the section x = 0 of Hénon–Heiles at energy
    E (px = 0 on it): (y, py) arrays, the upper half then the lower, closed.  0 < E <= 1/(6 lam^2)."""
    roots = np.roots([-2.0 * lam / 3.0, 1.0, 0.0, -2.0 * E])     # y^2 - 2 lam y^3/3 - 2E = 0
    real = np.sort(roots[np.abs(roots.imag) <= 1e-6].real)     # E = 1/6: the double root y = 1
    lo, hi = real[real < 0].max(), real[real > 0].min()
    y = lo + (hi - lo) * 0.5 * (1.0 - np.cos(np.linspace(0.0, math.pi, n)))   # dense near the ends
    py = np.sqrt(np.maximum(2.0 * E - y**2 + 2.0 * lam * y**3 / 3.0, 0.0))
    return np.concatenate([y, y[::-1]]), np.concatenate([py, -py[::-1]])


def _seeds_inside(by, bp, n, shrink=0.97):
    """``n`` seeds on py = 0 and ``n // 2`` on the vertical through the middle of the region
    (by, bp), each pulled towards the centre by ``shrink``."""
    ylo, yhi = by.min(), by.max()
    mid = 0.5 * (ylo + yhi)
    ys = mid + shrink * (np.linspace(ylo, yhi, n + 2)[1:-1] - mid)
    top = np.interp(mid, by[: by.size // 2], bp[: bp.size // 2])
    ps = shrink * np.linspace(-top, top, n // 2 + 2)[1:-1]
    return np.array([(y, 0.0) for y in ys] + [(mid, p) for p in ps])


def henon_heiles_sections(energies=classic.HENON_HEILES_ENERGIES, *, seeds=16, n_crossings=300):
    """For each energy: the section map x = 0, px > 0 in (y, py), its crossings from the seeds and
    the energy curve.  Returns a list of dicts (energy, points (N, K, 2), energy error, boundary)."""
    hh = classic.henon_heiles()
    x, y, px, py = hh.states
    out = []
    for E in energies:
        smap = SystemSectionMap(hh, E, section=x, direction=1, coords=(y, py), solve=px, tol=TOL)
        by, bp = henon_heiles_boundary(E)
        res = crossings(smap, _seeds_inside(by, bp, seeds), n_crossings=n_crossings)
        out.append({"energy": E, "points": res.data[..., [2, 4]], "energy_error": float(np.nanmax(
            np.abs(res.data[..., -1]))), "boundary": (by, bp)})
    return out


def henon_heiles_figure(*, seeds=16, n_crossings=300):
    """Three panels, the sections x = 0 (px > 0) of Hénon–Heiles at E = 1/12, 1/8, 1/6 in the plane
    (y, py), as Hénon & Heiles 1964, with the curve that bounds each."""
    sections = henon_heiles_sections(seeds=seeds, n_crossings=n_crossings)
    with _matplotlib().rc_context(_RC):
        fig = _figure((10.0, 3.6))
        axes = fig.subplots(1, 3)
        for ax, s, label in zip(axes, sections, ("1/12", "1/8", "1/6")):
            pts = s["points"].reshape(-1, 2)
            ax.plot(*s["boundary"], color="0.3", lw=0.6)
            ax.plot(pts[:, 0], pts[:, 1], ",", color="k", rasterized=True)
            ax.set_title(rf"$E = {label}$   $|\Delta E| \leq$ {s['energy_error']:.0e}", fontsize=9)
            ax.set_xlabel("$y$")
            ax.set_xlim(-0.55, 1.05)
            ax.set_ylim(-0.6, 0.6)
        axes[0].set_ylabel("$p_y$")
    return fig


def arenstorf_orbit(n: int = 300, tol: float = 1e-15):
    """Arenstorf's orbit over one period T, sampled at t = kT/n (k = 0..n): (t, states (n + 1, 4)),
    read off the Taylor steps of one integration (:func:`explorer.analysis.system_flow.flow`)."""
    t = np.linspace(0.0, classic.ARENSTORF_PERIOD, n + 1)
    res = flow(classic.pcr3bp(classic.ARENSTORF_MU), states=[classic.ARENSTORF_STATE], times=t, tol=tol)
    return res.t, res.states[0]


def arenstorf_figure(*, n=300):
    """Arenstorf's periodic orbit in the rotating frame, the Earth (1 - mu at (-mu, 0)) and the Moon
    (mu at (1 - mu, 0)), and how far the orbit is from its start after one period."""
    t, states = arenstorf_orbit(n)
    mu = classic.ARENSTORF_MU
    closure = float(np.max(np.abs(states[-1] - states[0])))
    with _matplotlib().rc_context(_RC):
        fig = _figure((5.2, 4.6))
        ax = fig.subplots()
        ax.plot(states[:, 0], states[:, 1], color="#1f4e9c", lw=0.9)
        ax.plot([-mu], [0.0], "o", color="tab:green", ms=7, label=r"Earth, $1-\mu$")
        ax.plot([1.0 - mu], [0.0], "o", color="0.45", ms=4, label=r"Moon, $\mu$")
        ax.plot(states[0, 0], states[0, 1], "s", color="tab:red", ms=4, label="start, $t = 0$ and $T$")
        ax.set_aspect("equal")
        ax.set_xlabel("$x$")
        ax.set_ylabel("$y$")
        ax.legend(fontsize=7, loc="lower left", frameon=False)
        ax.set_title(rf"Arenstorf's orbit, $\mu = {mu}$, $T = {classic.ARENSTORF_PERIOD:.10f}$"
                     + f"\n|state(T) - state(0)| = {closure:.1e}", fontsize=8)
    return fig


def double_pendulum_boundary(E: float, m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=1.0, n=400):
    """The curve bounding the section th1 = 0 of the double pendulum at energy E in (th2, p2): the
    minimum of H over p1 at th1 = 0 is p2^2/(2 m2 l2^2) - (m1 + m2) g l1 - m2 g l2 cos th2 (the
    Schur complement of the mass matrix), so |p2| <= sqrt(2 m2 l2^2 (E + (m1 + m2) g l1 + m2 g l2 cos th2)).
    (th2, p2) arrays, closed; th2 in [-pi, pi] where the energy allows all angles."""
    c = (E + (m1 + m2) * g * l1) / (m2 * g * l2)        # cos th2 >= -c
    top = math.pi if c >= 1.0 else math.acos(-c)
    th = np.linspace(-top, top, n)
    p = np.sqrt(np.maximum(2.0 * m2 * l2**2 * (E + (m1 + m2) * g * l1 + m2 * g * l2 * np.cos(th)), 0.0))
    return np.concatenate([th, th[::-1]]), np.concatenate([p, -p[::-1]])


def double_pendulum_section(E=PENDULUM_ENERGY, *, seeds=16, n_crossings=300):
    """The section th1 = 0, dth1/dt > 0 of the double pendulum (unit parameters) at energy E in
    (th2, p2): points (N, K, 2), the largest |E - E0| and the boundary."""
    dp = classic.double_pendulum()
    th1, th2, p1, p2 = dp.states
    smap = SystemSectionMap(dp, E, section=th1, direction=1, coords=(th2, p2), solve=p1, tol=TOL)
    bt, bp = double_pendulum_boundary(E)
    res = crossings(smap, _seeds_inside(bt, bp, seeds), n_crossings=n_crossings)
    return {"energy": E, "points": res.data[..., [2, 4]], "energy_error": float(np.nanmax(np.abs(res.data[..., -1]))),
            "boundary": (bt, bp)}


def double_pendulum_figure(*, seeds=16, n_crossings=300):
    """The section th1 = 0 (dth1/dt > 0) of the double pendulum with unit masses, lengths and g at
    :data:`PENDULUM_ENERGY`, in the canonical plane (th2, p2), with the curve that bounds it."""
    s = double_pendulum_section(seeds=seeds, n_crossings=n_crossings)
    with _matplotlib().rc_context(_RC):
        fig = _figure((5.2, 4.4))
        ax = fig.subplots()
        pts = s["points"].reshape(-1, 2)
        ax.plot(*s["boundary"], color="0.3", lw=0.6)
        ax.plot(pts[:, 0], pts[:, 1], ",", color="k", rasterized=True)
        ax.set_xlabel(r"$\theta_2$")
        ax.set_ylabel("$p_2$")
        ax.set_title(rf"double pendulum, $\theta_1 = 0$, $\dot\theta_1 > 0$, $E = {s['energy']:g}$"
                     + rf"   $|\Delta E| \leq$ {s['energy_error']:.0e}", fontsize=8)
    return fig


def write_figures(out_dir="figures", *, quick=False):
    """Write classic_henon_heiles.png, classic_arenstorf.png and classic_double_pendulum.png into
    ``out_dir`` (``quick``: few orbits and crossings).  Returns the paths."""
    size = {"seeds": 4, "n_crossings": 20} if quick else {}
    figures = {"classic_henon_heiles": lambda: henon_heiles_figure(**size),
               "classic_arenstorf": lambda: arenstorf_figure(n=20 if quick else 300),
               "classic_double_pendulum": lambda: double_pendulum_figure(**size)}
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, make in figures.items():
        path = out / f"{name}.png"
        make().savefig(path, dpi=DPI, facecolor="white", metadata={"Software": None})
        paths.append(path)
    return paths


def main(argv=None) -> int:
    """``python -m explorer.app.classic_figures [--out-dir DIR] [--quick]``: exit 0, or 2 on bad input."""
    parser = argparse.ArgumentParser(prog="python -m explorer.app.classic_figures", description=__doc__)
    parser.add_argument("--out-dir", default="figures", help="where the PNGs go [%(default)s]")
    parser.add_argument("--quick", action="store_true", help="few orbits and crossings")
    args = parser.parse_args(argv)
    try:
        for path in write_figures(args.out_dir, quick=args.quick):
            print(path)
    except (ParameterError, OSError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
