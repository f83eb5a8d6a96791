"""Figure 4: the sweep of the scene preset ``figure4`` (sections + separatrices)."""
from pathlib import Path

from explorer.app.paper._common import Outcome
from explorer.app.paper._sweeps import _quick_note, ensure_sweep

#: the figure's name (``explorer figures --only figure4``) and what it shows
NAME = "figure4"
DESCRIPTION = "the sweep of the preset figure4 (sections + separatrices)"


def figure4_figure(out_dir, *, results_dir="results", quick=False, quiet=True):
    """Figure 4 from the preset scene's store (computed if needed): runner.draw_figure."""
    from explorer.app import runner

    scene, out, reduced, summary = ensure_sweep("figure4", results_dir=results_dir, quick=quick, quiet=quiet)
    stem = Path(out_dir) / "figure4"
    paths = runner.draw_figure(scene, out, stem)
    msg = f"from {out}" + (f"; {_quick_note(scene)}" if reduced else "")
    return [Path(p) for p in paths], msg, {"store": str(out), "reduced": reduced, "summary": summary}


def build(out_dir, *, results_dir="results", quick=False, benchmark=None, quiet=True) -> Outcome:
    paths, msg, data = figure4_figure(out_dir, results_dir=results_dir, quick=quick, quiet=quiet)
    return Outcome(NAME, "written", paths, msg, data)
