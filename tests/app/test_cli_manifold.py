"""`python -m explorer manifold`: the documented JSON, the reversor's symmetry of its output, bad input."""
import json

import numpy as np
import pytest

from explorer.app import cli


def test_manifold_json_has_the_documented_shape_and_a_lobe_pair(capsys):
    code = cli.main(["manifold", "--mu", "0.03", "--arclength", "6", "--json"])
    out, _ = capsys.readouterr()
    assert code == 0
    d = json.loads(out)
    assert set(d) >= {"orbit", "branches", "homoclinic_points", "heteroclinic_points", "lobes", "flux"}
    assert d["heteroclinic_points"] == []                     # a fixed point has no other saddle point
    assert d["orbit"]["period"] == 1 and len(d["orbit"]["points"]) == 1
    assert np.prod(d["orbit"]["eigenvalues"]) == pytest.approx(1.0, abs=1e-9)
    assert sorted((b["kind"], b["sign"]) for b in d["branches"]) == [("stable", -1), ("stable", 1),
                                                                     ("unstable", -1), ("unstable", 1)]
    for b in d["branches"]:
        assert np.asarray(b["points"]).shape[1] == 2 and b["status"] == "arclength"
    hp = np.asarray(d["homoclinic_points"])
    # reversible scene: the mirror image (p1, -p2) of every homoclinic point is one
    for x in hp:
        assert np.min(np.linalg.norm(hp - [x[0], -x[1]], axis=1)) < 1e-9
    assert len(d["lobes"]) == 2 and d["flux"] == pytest.approx(d["lobes"][0]["area"])
    assert abs(d["lobes"][0]["area"] - d["lobes"][1]["area"]) < 1e-5


@pytest.mark.slow
def test_manifold_json_lists_the_heteroclinic_points_of_a_period_2_orbit(capsys):
    """W^u of point 0 of the period-2 saddle orbit meets W^s of point 1: points located to 1e-10,
    none of them on a branch of the same point."""
    code = cli.main(["manifold", "--mu", "0.03", "--guess=-1.8408,0", "--period", "2", "--arclength", "3",
                     "--json"])
    out, _ = capsys.readouterr()
    assert code == 0
    d = json.loads(out)
    het = d["heteroclinic_points"]
    assert het and all(h["from"] == 0 and h["to"] == 1 and h["residual"] < 1e-10 for h in het)
    x0, x1 = np.asarray(d["orbit"]["points"])
    for h in het:
        assert min(np.linalg.norm(np.asarray(h["point"]) - x) for x in (x0, x1)) > 1e-3


@pytest.mark.parametrize("args, word", [(["--arclength", "0"], "arclength"), (["--period", "0"], "period"),
                                        (["--mu", "3.5", "--guess", "-0.4,0", "--period", "1", "--max-points", "2"],
                                         "max_points")])
def test_manifold_bad_input_is_one_line_with_exit_2(args, word, capsys):
    code = cli.main(["manifold", *args])
    _, err = capsys.readouterr()
    assert code == 2 and word in err and len(err.strip().splitlines()) == 1
