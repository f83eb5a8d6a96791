"""The body's path in the plane (:func:`explorer.app.trajectory_figure.path_figure`)."""


from explorer.app.paper._common import Drawn, Outcome, save

#: the figure's name (``explorer figures --only trajectory``) and what it shows
NAME = "trajectory"
DESCRIPTION = "the body's path in the plane (full system R1)"


def trajectory_figure(*, quick=False) -> Drawn:
    from explorer.analysis.trajectory import full_params, initial_state, trajectory
    from explorer.app.trajectory_figure import path_figure
    from explorer.integrate.methods import TRAJECTORY_TOL

    prm = full_params(None)
    T, n = (60.0, 4001) if quick else (300.0, 20001)
    res = trajectory(prm, initial_state(prm, 0.5, 0.0, 2.0, 0.0), T, n, TRAJECTORY_TOL, phi_start=0.0)
    return Drawn(path_figure(res, prm), {"T": T, "status": res["status"]})


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    d = trajectory_figure(quick=quick)
    return Outcome(NAME, "written", save(d, out_dir, NAME), data=d.data)
