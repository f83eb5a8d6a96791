"""The Melnikov figure (:func:`explorer.app.melnikov_figure.melnikov_figure`)."""


from explorer.app.paper._common import Drawn, Outcome, save

#: the figure's name (``explorer figures --only melnikov``) and what it shows
NAME = "melnikov"
DESCRIPTION = "the Melnikov integral against ur24 and the measured splitting"


def melnikov_figure(*, quick=False) -> Drawn:
    from explorer.app.melnikov_figure import melnikov_figure as mf

    kw = dict(mus=(1e-3, 3e-3), n_measured=4) if quick else {}
    return Drawn(mf(**kw), {"quick": quick})


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    d = melnikov_figure(quick=quick)
    return Outcome(NAME, "written", save(d, out_dir, NAME), data=d.data)
