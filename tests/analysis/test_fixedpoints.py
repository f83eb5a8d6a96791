"""Fixed points of the section map: analytic solution I, Jacobian, continuation, separatrices."""
import json
import math

import numpy as np
import pytest

import reference
from explorer import model
from explorer.analysis import fixedpoints as fpm
from explorer.analysis.section_map import SectionMap
from explorer.app import cli


def test_fixed_point_at_mu0_is_solution_I_with_the_analytic_eigenvalues():
    """docs/model.md R6/R9: p = 0 is solution I, c = sqrt(2 b h) = 2 sqrt 2 in the unstable band (2, 4)."""
    fp = fpm.find_fixed_point(model.FIGURE4, 2.0, (0.05, -0.03))
    assert np.abs(fp.point).max() < 1e-12
    ev, tr = fpm.analytic_eigenvalues_solution_I(model.FIGURE4, 2.0)
    np.testing.assert_allclose(np.sort(np.real(fp.eigenvalues)), np.sort(np.real(ev)), rtol=1e-9)
    assert fp.trace == pytest.approx(tr, rel=1e-10) and not fp.stable
    assert fp.det == pytest.approx(1.0, abs=1e-10)
    assert fp.return_time == pytest.approx(2 * math.pi * 2.0 / math.sqrt(8.0), rel=1e-12)


def test_solution_I_outside_the_band_is_elliptic_with_the_analytic_rotation():
    h = 5.0  # c = sqrt(20) > lam b / a2 = 4: stable
    fp = fpm.find_fixed_point(model.FIGURE4, h, (0.01, 0.0))
    ev, tr = fpm.analytic_eigenvalues_solution_I(model.FIGURE4, h)
    assert fp.stable and abs(tr) < 2
    assert fp.trace == pytest.approx(tr, abs=1e-9)
    np.testing.assert_allclose(np.abs(fp.eigenvalues), 1.0, atol=1e-9)


@pytest.mark.parametrize("mu,x", [(0.5, (-0.1, 0.2)), (2.0, (-0.5, -0.3))])
def test_section_map_jacobian_matches_finite_differences(mu, x):
    smap = SectionMap(model.FIGURE4.with_(mu=mu, xi=0.1, chi=0.05), 2.0)
    r = smap(np.array(x))
    eps = 1e-6
    fd = np.column_stack([(smap(np.array(x) + eps * e, jacobian=False).point
                           - smap(np.array(x) - eps * e, jacobian=False).point) / (2 * eps) for e in np.eye(2)])
    # (central differences with eps = 1e-6 carry an O(eps^2 |D^3 P|) error: entries reach 1e3 here)
    np.testing.assert_allclose(r.jacobian, fd, atol=1e-4 * max(1.0, np.abs(fd).max()))


def test_backward_map_inverts_the_forward_map():
    smap = SectionMap(model.FIGURE4.with_(mu=0.3), 2.0)
    x = np.array([0.4, -0.2])
    fwd = smap(x)
    back = smap(fwd.point, backward=True)
    np.testing.assert_allclose(back.point, x, atol=1e-10)
    assert back.time == pytest.approx(-fwd.time, rel=1e-10)
    np.testing.assert_allclose(back.jacobian @ fwd.jacobian, np.eye(2), atol=1e-8)


@pytest.mark.cpu_dependent
def test_continuation_in_mu_finds_the_stability_change_of_the_central_point():
    br = fpm.continue_branch(model.FIGURE4, 2.0, "mu", 0.0, 4.0, 0.25)
    assert [b["type"] for b in br.bifurcations] == ["tangent"]
    mu_b = br.bifurcations[0]["value"]
    assert 2.5 < mu_b < 3.5
    below = fpm.find_fixed_point(model.FIGURE4.with_(mu=mu_b - 1e-3), 2.0, br.orbits[12].point)
    above = fpm.find_fixed_point(model.FIGURE4.with_(mu=mu_b + 1e-3), 2.0, br.orbits[12].point)
    assert not below.stable and above.stable
    assert below.trace > 2 > above.trace
    assert all(abs(p.det - 1) < 1e-8 for p in br.orbits)


def _distance_to_polyline(points, curve):
    a, b = curve[:-1], curve[1:]
    d = []
    for p in points:
        ab = b - a
        t = np.clip(np.sum((p - a) * ab, axis=1) / np.maximum(np.sum(ab * ab, axis=1), 1e-300), 0, 1)
        d.append(np.min(np.linalg.norm(a + t[:, None] * ab - p, axis=1)))
    return np.array(d)


@pytest.mark.parametrize("stable", [False, True])
def test_manifolds_are_invariant(stable):
    """Images of points between the samples of a separatrix lie on the separatrix: the midpoints
    of the segments of the branch to 4 images of the fundamental domain, mapped once (backward
    for the stable one), lie on the branch to 5 images."""
    fp = fpm.find_fixed_point(model.FIGURE4.with_(mu=0.01), 2.0)
    short = fpm.manifold(fp.params, fp.h, fp, stable=stable, iterations=4, max_gap=0.01)
    curve = fpm.manifold(fp.params, fp.h, fp, stable=stable, iterations=5, max_gap=0.01)
    assert len(curve) > len(short) > 50
    np.testing.assert_array_equal(curve[:len(short) - 1], short[:-1])    # the growth goes on from there
    smap = SectionMap(fp.params, fp.h, tol=1e-14)
    mids = 0.5 * (short[1:-1:7] + short[2::7])
    imgs = np.array([smap(m, backward=stable, jacobian=False).point for m in mids])
    assert np.max(_distance_to_polyline(imgs, curve)) < 2e-3
    # and the curve leaves the fixed point along the eigenvector of the (un)stable eigenvalue,
    # here taken from a central-difference Jacobian of the map (independent of fp.jacobian,
    # which comes from the tangent dynamics)
    assert np.linalg.norm(curve[0] - fp.point) < 1e-12
    eps = 1e-6
    J = np.empty((2, 2))
    for k in range(2):
        dx = np.zeros(2)
        dx[k] = eps
        J[:, k] = (smap(fp.point + dx, jacobian=False).point - smap(fp.point - dx, jacobian=False).point) / (2 * eps)
    w, V = np.linalg.eig(J)
    v = np.real(V[:, int(np.argmin(np.abs(w)) if stable else np.argmax(np.abs(w)))])
    for x in curve[1:4]:
        d = (x - fp.point) / np.linalg.norm(x - fp.point)
        assert abs(d[0] * v[1] - d[1] * v[0]) < 1e-5, (d, v)


def test_separatrices_are_the_branches_grow_branch_grows_to_their_images_of_the_fundamental_domain():
    """One manifold algorithm: each separatrix is manifolds.grow_branch's branch of the saddle
    (both signs of W^u, then of W^s), bit for bit, ending after ``iterations`` images of the
    fundamental domain (or at ``arclength``)."""
    from explorer.analysis import manifolds as mf

    smap = SectionMap(model.FIGURE4.with_(mu=0.03), 2.0)
    fp = fpm.find_fixed_point(smap, (0.0, 0.0))
    seps = fpm.separatrices(smap, fp, iterations=2)
    sd = mf.saddle(smap, fp)
    for curve, (stable, sign) in zip(seps, ((False, 1), (False, -1), (True, 1), (True, -1))):
        b = mf.grow_branch(sd, stable=stable, sign=sign, arclength=math.inf, generations=2)
        assert b.status == "generations"
        np.testing.assert_array_equal(curve, b.points)
        assert (b.sigma[-1] - b.curve.sigma0) / b.curve.L == pytest.approx(3.0)   # domain + 2 images
    short = fpm.separatrices(smap, fp, iterations=6, arclength=0.5)
    assert all(0.5 <= np.sum(np.linalg.norm(np.diff(c, axis=0), axis=1)) < 0.5 + 0.02 for c in short)


@pytest.mark.cpu_dependent
def test_elliptic_point_has_no_separatrices():
    fp = fpm.find_fixed_point(model.FIGURE4.with_(mu=4.0), 2.0, (-2.16, 0.0))
    assert fp.stable
    with pytest.raises(model.ParameterError, match="elliptic"):
        fpm.manifold(fp.params, fp.h, fp)


@pytest.mark.cpu_dependent
def test_fixedpoint_cli_json_and_continuation(capsys):
    assert cli.main(["fixedpoint", "--json"]) == 0
    doc = json.loads(capsys.readouterr()[0])
    assert {"p1", "p2", "trace", "eigenvalues", "stable"} <= set(doc)
    assert doc["stable"] is False and abs(doc["trace"] - reference.trace_solution_I(1.0, 0.5, 2.0, 1.0, 2.0)) < 1e-8
    assert cli.main(["fixedpoint", "--continue", "mu", "2.5", "3.5", "0.25", "--guess=-1.2,0", "--json"]) == 0
    doc = json.loads(capsys.readouterr()[0])
    assert len(doc["branch"]) == 5 and [b["type"] for b in doc["bifurcations"]] == ["tangent"]


@pytest.mark.parametrize("args,fragment", [
    (["--guess", "9,9"], "outside the allowed region"),
    (["--guess", "a,b"], "--guess must be two numbers"),
    (["--continue", "nu", "0", "1", "0.5"], "--continue PARAM must be one of"),
    (["--continue", "mu", "0", "1", "-0.5"], "STEP of the sign"),
    (["--b", "-1"], "b must be > 0"),
])
def test_fixedpoint_cli_bad_input(args, fragment, capsys):
    code = cli.main(["fixedpoint"] + args)
    _, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1 and fragment in err


def test_central_point_changes_stability_where_an_independent_bisection_says():
    """mu* of Figure 4's central fixed point from scipy's DOP853 alone (tests/reference.py:
    fixed point on the symmetry line by the secant method, trace by central differences of the
    map, bisection of trace - 2): the package's fixed point is hyperbolic just below, elliptic
    just above, with trace 2 at mu*.  The verdicts are taken 0.01 in mu from mu*, where the trace is about
    0.04 from 2: no last-bit difference between CPUs can flip them."""
    mu_star = reference.figure4_stability_change_mu()
    assert 2.9 < mu_star < 3.05
    for d, stable in ((-0.01, False), (0.01, True)):
        fp = fpm.find_fixed_point(model.FIGURE4.with_(mu=mu_star + d), 2.0, (-1.5, 0.0))
        assert fp.stable is stable, (d, fp.trace)
    fp = fpm.find_fixed_point(model.FIGURE4.with_(mu=mu_star), 2.0, (-1.5, 0.0))
    assert abs(fp.trace - 2.0) < 1e-5, fp.trace


def test_trace_of_solution_I_equals_its_closed_form():
    """docs/model.md R6: at mu = 0 the trace at p = 0 is 2 cosh(k) (tests/reference.py writes the
    linearisation independently of fixedpoints.analytic_eigenvalues_solution_I)."""
    fp = fpm.find_fixed_point(model.FIGURE4, 2.0)
    assert abs(fp.trace - reference.trace_solution_I(1.0, 0.5, 2.0, 1.0, 2.0)) < 1e-8


@pytest.mark.cpu_dependent
def test_newton_converges_from_a_guess_near_the_regions_edge():
    """mu = 0.03: a guess on p2 = 0 at 0.9 of the allowed region's half-axis from its centre.
    The fixed-point Newton of before (no residual test in its line search) stopped there with
    'did not converge'; the one Newton of every period converges to the elliptic point, which
    an independent scipy secant on the symmetry line confirms."""
    prm = model.FIGURE4.with_(mu=0.03)
    c1, _c2, r1, _r2 = model.allowed_ellipse(prm, 2.0)
    fp = fpm.find_fixed_point(prm, 2.0, (c1 - 0.9 * r1, 0.0))
    assert fp.stable and not fp.degenerate and fp.residual < 1e-12
    p1 = reference.symmetric_fixed_point(prm.as_array(), 2.0, fp.point[0] + 1e-3)
    assert fp.point[0] == pytest.approx(p1, abs=1e-9) and abs(fp.point[1]) < 1e-12
    np.testing.assert_allclose(reference.section_map_p(prm.as_array(), p1, 0.0, 2.0), (p1, 0.0), atol=1e-9)


@pytest.mark.cpu_dependent
def test_fixedpoint_and_periodic_continuations_report_the_same_touch_of_minus_two(capsys):
    """One continuation for both commands: over mu = 3.5 .. 12 the central point's trace touches
    -2 (near mu = 5.59) without crossing; `fixedpoint --continue` reported 'none in range' where
    `periodic -K 1 --continue` found the touch."""
    args = ["--continue", "mu", "3.5", "12", "0.5", "--guess=-1.84,0", "--json"]
    assert cli.main(["fixedpoint"] + args) == 0
    fixed = json.loads(capsys.readouterr()[0])
    assert cli.main(["periodic", "-K", "1"] + args) == 0
    periodic = json.loads(capsys.readouterr()[0])
    assert fixed["bifurcations"] == periodic["bifurcations"]
    touches = [b for b in fixed["bifurcations"] if b["type"] == "touch -2"]
    assert len(touches) == 1 and 5.0 < touches[0]["value"] < 6.2 and abs(touches[0]["trace"] + 2) < 1e-6
    fp = fpm.follow(model.FIGURE4, 2.0, "mu", 3.5, touches[0]["value"], (-1.84, 0.0))
    assert fp.trace == pytest.approx(-2.0, abs=1e-6)     # the touch, checked by a fresh Newton


def test_section_map_object_iterates_inverts_and_differentiates_consistently():
    """The public SectionMap: iterate(x, n) are n applications of the map, inverse undoes one,
    jacobian is that of a call; scipy's map gives the same first image."""
    import explorer as ex

    prm = model.FIGURE4.with_(mu=0.3)
    smap = ex.SectionMap(prm, 2.0)
    x = np.array([0.4, -0.2])
    orbit = smap.iterate(x, 3)
    assert orbit.shape == (4, 2) and np.array_equal(orbit[0], x)
    np.testing.assert_allclose(orbit[1], reference.section_map_p(prm.as_array(), *x, 2.0), atol=1e-9)
    np.testing.assert_allclose(smap.inverse(orbit[3]), orbit[2], atol=1e-10)
    np.testing.assert_allclose(smap.iterate(orbit[3], 3, backward=True)[-1], x, atol=1e-9)
    np.testing.assert_array_equal(smap.jacobian(x), smap(x).jacobian)
    with pytest.raises(model.ParameterError, match="tol must be in"):
        ex.SectionMap(prm, 2.0, tol=0.5)
