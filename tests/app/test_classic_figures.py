"""The figures of the classic systems (explorer.app.classic_figures), on tiny sizes."""
import numpy as np

from explorer.app import classic_figures as cf
from explorer.model import classic

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def test_each_classic_figure_is_written_as_a_png_by_main(tmp_path, capsys):
    assert cf.main(["--out-dir", str(tmp_path), "--quick"]) == 0
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["classic_arenstorf.png", "classic_double_pendulum.png", "classic_henon_heiles.png"]
    for name in names:
        data = (tmp_path / name).read_bytes()
        assert data.startswith(PNG_MAGIC) and len(data) > 5000
    assert capsys.readouterr().out.count(".png") == 3


def test_main_exits_2_when_the_output_directory_cannot_be_made(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    assert cf.main(["--out-dir", str(blocker / "sub"), "--quick"]) == 2
    assert "error:" in capsys.readouterr().err


def test_the_arenstorf_orbit_of_the_figure_returns_to_its_start_after_one_period():
    t, states = cf.arenstorf_orbit(n=8)
    assert t[-1] == classic.ARENSTORF_PERIOD and states.shape == (9, 4)
    assert np.max(np.abs(states[-1] - states[0])) <= 1e-10


def test_the_drawn_boundaries_enclose_the_section_points():
    """Every point of the tiny sections lies inside the curve the figure draws around it."""
    from matplotlib.path import Path

    for s in cf.henon_heiles_sections(seeds=2, n_crossings=10) + [cf.double_pendulum_section(seeds=2,
                                                                                              n_crossings=10)]:
        pts = s["points"].reshape(-1, 2)
        assert Path(np.column_stack(s["boundary"])).contains_points(pts).all()
