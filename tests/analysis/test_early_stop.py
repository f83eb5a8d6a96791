"""Early classification ([lyapunov] early_stop): an orbit stops as chaotic when SALI < 1e-8 or
when <Y> has stayed above 8 over [t/2, t] with t >= 100; the chaotic fraction of every panel of
the `fraction` preset's panels that span regular to chaotic agrees with the full-T run within its
binomial error, in fewer steps."""

import numpy as np
import pytest

from explorer import model
from explorer.analysis import lyapunov
from explorer.analysis.lyapunov import chaotic_fraction
from explorer.analysis.seeds import seed_points
from explorer.io.scene import load_scene

#: the preset's panels checked: mostly regular (mu = 0.005), Figure 4's mixed (0.03), mixed with a
#: large sea (0.3) and nearly all chaotic (4); the other nine lie between these in kind
PANEL_MUS = (0.005, 0.03, 0.3, 4.0)


@pytest.mark.cpu_dependent
def test_early_stop_keeps_the_chaotic_fraction_of_the_fraction_preset():
    scene = load_scene("fraction")
    ly = scene.lyapunov
    full_steps = early_steps = 0
    panels = [i for i in range(scene.n_panels) if scene.panel(i)[0].mu in PANEL_MUS]
    assert len(panels) == len(PANEL_MUS)
    for i in panels:
        params, h, _label = scene.panel(i)
        p1, p2, _ = seed_points(scene.seeds, params, h, scene.integration.phi0)
        y0 = model.section_state(params, p1, p2, h, scene.integration.phi0)
        full = lyapunov.indicators(params, states=y0, tmax=ly.time, tol=ly.tol)
        early = lyapunov.indicators(params, states=y0, tmax=ly.time, tol=ly.tol, early_stop=True)
        full_steps += int(full.steps.sum())
        early_steps += int(early.steps.sum())
        ok = full.status == 0
        f_full, err, n = chaotic_fraction(full.megno, ly.threshold, ok)
        f_early = float(np.mean(early.chaotic(ly.threshold)[ok]))
        assert abs(f_early - f_full) <= err, (params.mu, f_full, f_early, err, n)
        # an orbit stopped early is chaotic in the full run too, but for a few borderline ones
        stopped = early.early > 0
        assert np.all(early.time[~stopped] == ly.time)
        assert np.mean(full.megno[stopped] > ly.threshold) >= 0.98 if stopped.any() else True
    # early stop saves work: counted in steps, not in seconds (the generic-CPU rerun runs this
    # test at the lowest priority beside the suite, tests/generic_cpu.py: its clock says nothing)
    assert early_steps < full_steps
