"""Figure 2: Chaplygin's case, closed curves {H = h} n {F = c} in (p1, p2, M), one panel per
energy interval of the seed (below, inside, above the unstable band of I)."""
import math

import numpy as np

from explorer.app.paper._common import (
    _FS,
    _SMALL,
    CHAPLYGIN,
    DENSE_TOL,
    FIGURE2_ENERGIES,
    Drawn,
    Outcome,
    _new_figure,
    _rc,
    save,
)
from explorer.app.paper._dense import _state5, closed_curves, dense_orbits, meridian_points
from explorer.app.paper.chaplygin import (
    _aj,
    branch_stable,
    chaplygin_F,
    chaplygin_H,
    check_chaplygin,
    critical_c,
    critical_h,
    relative_equilibrium,
)

#: the figure's name (``explorer figures --only figure2``) and what it shows
NAME = "figure2"
DESCRIPTION = "Chaplygin's case: closed curves {H = h} n {F = c} in (p1, p2, M), one panel per energy interval"
#: the 3D axes' grid: light and thin, under the curves
GRID_COLOR, GRID_WIDTH = (0.88, 0.88, 0.88, 1.0), 0.3


def _figure2_levels(prm, h, n_levels, min_per_interval=2):
    """Values of c for the curves of one panel: n_levels uniform in (min F, max F) on the
    ellipsoid, at least ``min_per_interval`` (equally spaced) in every interval between
    critical values, none within 8 % of an interval's width from a critical value.
    Returns (levels, critical list)."""
    c1, c2 = critical_c(prm)
    hI = math.sqrt(2 * prm.b * h)
    crit = [(-hI, "I-"), (hI, "I+")]
    for branch, cj in (("II", c1), ("III", c2)):
        a = _aj(prm, branch)
        if h > prm.b * prm.lam ** 2 / (2 * a * a):
            crit.append((a * h / prm.lam + prm.lam * prm.b / (2 * a), branch))
    crit.sort()
    lo, hi = crit[0][0], crit[-1][0]
    uniform = lo + (hi - lo) * (np.arange(n_levels) + 0.5) / n_levels
    levels = []
    for (ca, _), (cb, _) in zip(crit[:-1], crit[1:]):
        w = cb - ca
        if w <= 0:
            continue
        inside = [c for c in uniform if ca + 0.08 * w < c < cb - 0.08 * w]
        if len(inside) < min_per_interval:
            inside = list(ca + w * (np.arange(min_per_interval) + 1.0) / (min_per_interval + 1))
        levels += inside
    return sorted(levels), crit


def _separatrix_III(prm, h, c, *, dt, tol, t_max=60.0):
    """Heteroclinic curves of the saddles III at F = c: integrated forward from their meridian
    points until they reach a saddle (within 1e-3); the backward half is the mirror image
    p2 -> -p2 (the reversibility (p2, t) -> (-p2, -t) of R6)."""
    pts = meridian_points(prm, h, c)
    if not len(pts):
        return []
    sad = np.array([relative_equilibrium("III", c, prm, s) for s in (1, -1)])
    near = np.zeros(len(pts), bool)
    ends = np.full(len(pts), -1)

    def stop(k, Y):
        d = np.min(np.linalg.norm(Y[:, None, :3] - sad[None], axis=2), axis=1)
        for i in np.flatnonzero((d < 1e-3) & ~near):
            near[i] = True
            ends[i] = k
        return bool(np.all(near))

    t, Ys = dense_orbits(prm, _state5(pts), t_max, dt, tol=tol, stop=stop)
    out = []
    for i in range(len(pts)):
        k = ends[i] if ends[i] > 0 else len(t)
        fwd = Ys[:k + 1, i, :3]
        back = fwd[::-1] * np.array([1.0, -1.0, 1.0])
        out.append(np.vstack([back[:-1], fwd]))
    return out


def figure2_figure(params=CHAPLYGIN, energies=FIGURE2_ENERGIES, *, n_levels=9, dt=0.02, tol=DENSE_TOL, dpi=200,
            elev=24.0, azim=-55.0) -> Drawn:
    """The seed's Figure 2: curves {H = h} n {F = c} in (p1, p2, M), one panel per energy interval,
    separatrices in red (R7 for I, integrated for III), permanent rotations marked (filled: stable).
    data["panels"][i]: h, curves, separatrices, equilibria, levels, critical."""
    from explorer.model import exact

    prm = check_chaplygin(params)
    h1, h2 = critical_h(prm)
    panels = []
    for h in energies:
        levels, crit = _figure2_levels(prm, h, n_levels)
        curves = closed_curves(prm, h, levels, dt=dt, tol=tol)
        seps = []
        c1, c2 = critical_c(prm)
        cI = math.sqrt(2 * prm.b * h)
        if c1 < cI < c2:   # the upper pole I is a saddle: its homoclinic loops R7
            tt = np.linspace(-30.0, 30.0, 3001)
            for s in (1, -1):
                p1, p2, M, _phi = exact.homoclinic(prm.as_array(), cI, tt, sign=s)
                seps.append(np.column_stack([p1, p2, M]))
        for cval, kind in crit:
            if kind == "III":
                seps += _separatrix_III(prm, h, cval, dt=dt, tol=tol)
        eq = []
        for cval, kind in crit:
            if kind in ("I+", "I-"):
                y = np.array([0.0, 0.0, cval])
                st = branch_stable("I", cval, prm) if cval not in (c1, c2) else True
                eq.append(("I", y, st))
            else:
                for s in (1, -1):
                    eq.append((kind, relative_equilibrium(kind, cval, prm, s), kind == "II"))
        panels.append({"h": h, "curves": curves, "separatrices": seps, "equilibria": eq, "levels": levels,
                       "critical": crit})
    fig = _draw_figure2(prm, panels, (h1, h2), dpi=dpi, elev=elev, azim=azim)
    return Drawn(fig, {"panels": panels, "params": prm.as_dict()})


def _interval_title(h, h1, h2, k):
    tag = "abcdefgh"[k]
    if h < h1:
        rel = rf"$h = {h:g} < b\lambda^2/2a_1^2 = {h1:g}$"
    elif h < h2:
        rel = rf"${h1:g} < h = {h:g} < b\lambda^2/2a_2^2 = {h2:g}$"
    else:
        rel = rf"$h = {h:g} > b\lambda^2/2a_2^2 = {h2:g}$"
    return f"({tag}) " + rel


def _ellipsoid_silhouette(R, eye, n=400):
    """The outline of the ellipsoid sum (x_i/R_i)^2 = 1 seen along ``eye`` (orthographic):
    its intersection with the plane through 0 normal to A eye, A = diag(1/R^2)."""
    nrm = eye / R ** 2
    nrm = nrm / np.linalg.norm(nrm)
    u = np.cross(nrm, [0.0, 0.0, 1.0] if abs(nrm[2]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(nrm, u)
    th = np.linspace(0, 2 * math.pi, n)
    d = np.cos(th)[:, None] * u + np.sin(th)[:, None] * v
    s = 1.0 / np.sqrt(np.sum((d / R) ** 2, axis=1))
    return d * s[:, None]


def _split_visible(y, R, eye):
    """Split a polyline on the ellipsoid into runs in front of (normal . eye >= 0) and behind it."""
    vis = (y / R ** 2) @ eye >= 0
    runs = []
    start = 0
    for k in range(1, len(y) + 1):
        if k == len(y) or vis[k] != vis[start]:
            seg = y[start:min(k + 1, len(y))]
            runs.append((bool(vis[start]), seg))
            start = k
    return runs


def _draw_figure2(prm, panels, hcrit, *, dpi, elev, azim):
    import matplotlib as mpl
    import mpl_toolkits.mplot3d  # noqa: F401  (registers the 3d projection)
    from matplotlib.ticker import MaxNLocator

    h1, h2 = hcrit
    n = len(panels)
    eye = np.array([math.cos(math.radians(elev)) * math.cos(math.radians(azim)),
                    math.cos(math.radians(elev)) * math.sin(math.radians(azim)), math.sin(math.radians(elev))])
    with _rc():
        fig = _new_figure((3.4 * n, 4.1), dpi=dpi, layout=None)
        for k, p in enumerate(panels):
            h = p["h"]
            R = np.array([math.sqrt(2 * prm.a1 * h), math.sqrt(2 * prm.a2 * h), math.sqrt(2 * prm.b * h)])
            # a 3D axis takes its grid's colour and width from rcParams when it is made
            with mpl.rc_context({"grid.color": GRID_COLOR, "grid.linewidth": GRID_WIDTH}):
                ax = fig.add_axes([k / n + 0.005, 0.085, 1.0 / n - 0.01, 0.79], projection="3d", proj_type="ortho")
            ax.view_init(elev=elev, azim=azim)
            # faint ellipsoid and its outline
            uu, vv = np.meshgrid(np.linspace(0, 2 * math.pi, 60), np.linspace(0, math.pi, 30))
            ax.plot_surface(R[0] * np.cos(uu) * np.sin(vv), R[1] * np.sin(uu) * np.sin(vv), R[2] * np.cos(vv),
                            color="0.85", alpha=0.12, linewidth=0, shade=False, zorder=0)
            sil = _ellipsoid_silhouette(R, eye)
            ax.plot(sil[:, 0], sil[:, 1], sil[:, 2], color="0.35", lw=0.6, zorder=1)
            for cur in p["curves"]:
                for front, seg in _split_visible(cur["y"], R, eye):
                    ax.plot(seg[:, 0], seg[:, 1], seg[:, 2], color="k" if front else "0.72",
                            lw=0.75 if front else 0.5, zorder=3 if front else 2, gid="curve")
            for sep in p["separatrices"]:
                for front, seg in _split_visible(sep, R, eye):
                    ax.plot(seg[:, 0], seg[:, 1], seg[:, 2], color="#c0392b" if front else "#eaa39b",
                            lw=1.2 if front else 0.8, zorder=4 if front else 2, gid="separatrix")
            for kind, y, st in p["equilibria"]:
                front = (y / R ** 2) @ eye >= -1e-12
                ax.scatter([y[0]], [y[1]], [y[2]], s=14, marker="o", depthshade=False, zorder=5,
                           facecolors=("k" if st else "white"), edgecolors="k" if front else "0.6",
                           linewidths=0.8, gid=f"eq-{kind}")
                if kind == "I":
                    pos = y + np.array([0.09 * R[0], 0.0, 0.07 * R[2] * (1 if y[2] > 0 else -1)])
                else:
                    pos = y * np.array([1.2, 1.2, 1.0]) + np.array([0.0, 0.0, 0.06 * R[2]])
                ax.text(pos[0], pos[1], pos[2], kind, fontsize=_SMALL, ha="center", va="center",
                        color="k" if front else "0.55", zorder=6)
            ax.set_xlim(-R[0], R[0])
            ax.set_ylim(-R[1], R[1])
            ax.set_zlim(-R[2], R[2])
            ax.set_box_aspect(tuple(R), zoom=1.12)
            ax.set_xlabel("$p_1$", fontsize=_FS, labelpad=-5)
            ax.set_ylabel("$p_2$", fontsize=_FS, labelpad=-5)
            ax.set_zlabel("$M$", fontsize=_FS, labelpad=-6)
            ax.tick_params(labelsize=6, pad=-2.5)
            for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
                axis.set_pane_color((1, 1, 1, 0))
                axis.set_major_locator(MaxNLocator(3, symmetric=True))
            fig.text((k + 0.5) / n, 0.905, _interval_title(h, h1, h2, k), ha="center", va="center", fontsize=_FS)
        fig.text(0.5, 0.985, r"$\lambda = %g,\ b = %g,\ a_1 = %g,\ a_2 = %g,\ \chi = \zeta = \mu = 0$.  "
                 r"Black: $\{H = h\}\cap\{F = c\}$ (integrated), light: behind the ellipsoid; red: separatrices; "
                 r"$\bullet$ stable, $\circ$ unstable permanent rotations I, II, III"
                 % (prm.lam, prm.b, prm.a1, prm.a2), ha="center", va="top", fontsize=_SMALL)
    return fig


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    d = figure2_figure(n_levels=6 if quick else 9, dt=0.04 if quick else 0.02)
    curves = [(p["h"], c) for p in d.data["panels"] for c in p["curves"]]
    dH = max(float(np.max(np.abs(chaplygin_H(CHAPLYGIN, c["y"]) - h))) for h, c in curves)
    dF = max(float(np.max(np.abs(chaplygin_F(CHAPLYGIN, c["y"]) - c["c"]))) for h, c in curves)
    return Outcome(NAME, "written", save(d, out_dir, NAME),
                   f"{len(curves)} integrated curves, max |H - h| {dH:.1e}, max |F - c| {dF:.1e}", d.data)
