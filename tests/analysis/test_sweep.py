"""`python -m explorer sweep`: store, resume, skip, determinism across jobs and backends, errors."""
import os
import random
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

import reference
from explorer.app import cli
from explorer.io import store

SMALL = """
name = "small"
[model]
mu = 0.0
[energy]
h = 2.0
[sweep]
parameter = "mu"
values = [0.1, 0.6, 1.5]
[seeds]
kind = "grid"
n = 24
[integration]
method = "taylor"
tol = 1e-12
crossings = 40
tmax = 400.0
[figure]
layout = "row"
"""


def write_scene(tmp_path, text=SMALL, name="scene.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def sweep(args, capsys=None):
    code = cli.main(["sweep"] + [str(a) for a in args] + ["--quiet"])
    out = capsys.readouterr() if capsys is not None else None
    return code, out


def datasets(path):
    """Every dataset of the store (panel data only; attrs with timestamps excluded), panel by panel
    (HDF5's visit does not cross the external links to the panel files)."""
    out = {}
    with h5py.File(path, "r") as f:
        for p in f["panels"]:
            def visit(name, obj, p=p):
                if isinstance(obj, h5py.Dataset):
                    out[f"panels/{p}/{name}"] = obj[()]
            f["panels"][p].visititems(visit)
    return out


def assert_same_data(a, b):
    da, db = datasets(a), datasets(b)
    assert sorted(da) == sorted(db)
    for k in da:
        np.testing.assert_array_equal(da[k], db[k], err_msg=k)


def test_sweep_writes_every_panel_and_the_figure(tmp_path, capsys):
    scene = write_scene(tmp_path)
    out = tmp_path / "r.h5"
    code, (stdout, _) = sweep([scene, "--out", out, "--figure", tmp_path / "fig"], capsys)
    assert code == 0
    assert "3 panels (3 computed, 0 already stored)" in stdout
    data = store.read_store(out)
    assert sorted(data.panels) == [0, 1, 2]
    for i, pd in data.panels.items():
        n = len(pd.arrays["count"])
        assert 15 <= n <= 40
        assert pd.arrays["offsets"][-1] == len(pd.arrays["crossings"]) == pd.arrays["count"].sum()
        assert np.all(np.isfinite(pd.arrays["crossings"]))
    assert (tmp_path / "fig.png").stat().st_size > 10000
    assert (tmp_path / "fig.pdf").read_bytes()[:4] == b"%PDF"
    # provenance
    assert data.attrs["scene_name"] == "small" and "parameter = \"mu\"" in data.attrs["scene"]


def test_rerun_skips_complete_panels_and_recomputes_only_a_changed_one(tmp_path, capsys):
    scene = write_scene(tmp_path)
    out = tmp_path / "r.h5"
    sweep([scene, "--out", out, "--no-figure"], capsys)
    before = datasets(out)
    code, (stdout, _) = sweep([scene, "--out", out, "--no-figure"], capsys)
    assert code == 0 and "(0 computed, 3 already stored)" in stdout
    scene2 = write_scene(tmp_path, SMALL.replace("[0.1, 0.6, 1.5]", "[0.1, 0.7, 1.5]"), "scene2.toml")
    code, (stdout, _) = sweep([scene2, "--out", out, "--no-figure"], capsys)
    assert "(1 computed, 2 already stored)" in stdout
    after = datasets(out)
    for k in before:
        if k.startswith("panels/001"):
            continue
        np.testing.assert_array_equal(before[k], after[k])
    assert not np.array_equal(before["panels/001/crossings"], after["panels/001/crossings"])
    code, (stdout, _) = sweep([scene2, "--out", out, "--no-figure", "--force"], capsys)
    assert "(3 computed, 0 already stored)" in stdout


def test_summary_gives_the_energy_error_and_warns_when_the_step_is_too_coarse(tmp_path, capsys):
    scene = write_scene(tmp_path)
    code, (stdout, _) = sweep([scene, "--out", tmp_path / "a.h5", "--no-figure"], capsys)
    data = store.read_store(tmp_path / "a.h5")
    dh = max(np.abs(p.crossings[:, 4]).max() for p in data.panels.values())
    assert code == 0 and f"max |H - H0| over all crossings {dh:.1e}" in stdout
    assert "warning" not in stdout
    coarse = write_scene(tmp_path, SMALL.replace('method = "taylor"\ntol = 1e-12',
                                                 'method = "split4"\ndt = 0.5'), "coarse.toml")
    code, (stdout, _) = sweep([coarse, "--out", tmp_path / "b.h5", "--no-figure"], capsys)
    assert code == 0 and "warning: energy error up to" in stdout and "dt = 0.5 ([integration])" in stdout


def test_jobs_1_and_2_give_identical_files(tmp_path, capsys):
    """Sections and an adaptive map of each panel (one task per map panel, docs/scenes.md, "Adaptive
    maps"; 128 x 128 cells, the first raster the default lattice of 64 cells a side refines, T = 10)
    store the same arrays, masks and classes computed in joblib worker processes as in this one."""
    scene = write_scene(tmp_path, SMALL + "[compute]\nlyapunov = true\n[lyapunov]\ntime = 10.0\nmap_resolution = 128\n")
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    assert sweep([scene, "--out", a, "--no-figure", "--jobs", "1"], capsys)[0] == 0
    assert sweep([scene, "--out", b, "--no-figure", "--jobs", "2"], capsys)[0] == 0
    assert_same_data(a, b)
    panels = store.read_store(b).panels
    assert all(0.05 < panels[i].extra["map_computed"].mean() < 0.9 for i in panels)     # adaptive
    assert any(panels[i].extra["map_chaotic"].any() for i in panels)


def test_dask_local_cluster_gives_the_same_file(tmp_path, capsys):
    distributed = pytest.importorskip("distributed")
    scene = write_scene(tmp_path)
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    assert sweep([scene, "--out", a, "--no-figure"], capsys)[0] == 0
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        code, _ = sweep([scene, "--out", b, "--no-figure", "--backend", "dask", "--scheduler",
                         cluster.scheduler_address], capsys)
    assert code == 0
    assert_same_data(a, b)


KILL_SCENE = SMALL.replace("values = [0.1, 0.6, 1.5]", "values = [0.1, 0.3, 0.6, 0.9, 1.2, 1.5]") \
    .replace("n = 24", "n = 60").replace("crossings = 40", "crossings = 300") \
    .replace("tmax = 400.0", "tmax = 3000.0")


def _stored_panels(path):
    """Indices of the panels committed to the store at path (none if there is no file yet)."""
    return sorted(store.read_store(path).panels) if path.exists() else []


def test_killed_sweep_resumes_to_the_same_file(tmp_path):
    """SIGKILL a sweep subprocess again and again, rerun to completion, compare with an
    uninterrupted run: identical data, nothing lost, nothing duplicated, no temporary left.

    The kills do not depend on how fast the machine is: every other run is killed the moment
    it has committed a new panel (the file then holds a part of the sweep, the case resuming
    must handle), the others at a random moment within the uninterrupted run's wall time
    (start-up, compilation, mid-panel, mid-commit).  A run that finishes before its kill
    starts the next round on a fresh file.  After every kill the file opens and every panel
    it holds equals the reference panel; the last file is then completed."""
    scene = write_scene(tmp_path, KILL_SCENE)
    ref = tmp_path / "ref.h5"
    out = tmp_path / "killed.h5"
    cmd = [sys.executable, "-m", "explorer", "sweep", str(scene), "--no-figure", "--quiet"]
    t0 = time.perf_counter()
    subprocess.run(cmd + ["--out", str(ref)], check=True, capture_output=True, timeout=600)
    wall = time.perf_counter() - t0
    reference = datasets(ref)
    npanels = len(_stored_panels(ref))
    assert npanels == 6
    rng = random.Random(7)
    kills = partial_kills = 0
    for attempt in range(40):
        if kills >= 4 and partial_kills >= 2:
            break
        before = len(_stored_panels(out))
        if before == npanels:   # a run finished: start the next round on a fresh file
            out.unlink()
            before = 0
        proc = subprocess.Popen(cmd + ["--out", str(out)], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        if attempt % 2 == 0:    # kill as soon as this run has committed a panel
            deadline = time.perf_counter() + 600
            while proc.poll() is None and time.perf_counter() < deadline:
                if len(_stored_panels(out)) > before:
                    break
                time.sleep(0.005)
        else:
            time.sleep(rng.uniform(0.05, wall))
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
            kills += 1
            proc.wait()
            stored = _stored_panels(out)   # opens, whatever the moment of the kill
            partial_kills += 0 < len(stored) < npanels
            now = datasets(out) if out.exists() else {}
            for k, v in now.items():
                np.testing.assert_array_equal(v, reference[k], err_msg=k)
        proc.wait()
    assert kills >= 4 and partial_kills >= 2, (kills, partial_kills)
    # the resuming run (in this process: what it resumes from is the killed processes' file)
    assert cli.main(["sweep", str(scene), "--no-figure", "--quiet", "--out", str(out)]) == 0
    assert_same_data(ref, out)
    assert not list(tmp_path.glob("killed.h5.tmp-*"))
    with h5py.File(out, "r") as f:   # nor a panel file that the store does not link
        linked = {os.path.basename(f["panels"].get(n, getlink=True).filename) for n in f["panels"]}
    assert set(os.listdir(f"{out}.panels")) == linked


@pytest.mark.parametrize("args,fragment", [
    (["no-such-scene"], "no-such-scene"),
    (["figure4", "--jobs", "0"], "--jobs must be >= 1"),
    (["figure4", "--scheduler", "tcp://127.0.0.1:1"], "--scheduler needs --backend dask"),
    (["figure4", "--backend", "spark"], "--backend"),
])
def test_bad_sweep_input_gives_one_line_and_status_2(args, fragment, capsys):
    code = cli.main(["sweep"] + args)
    _, err = capsys.readouterr()
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and fragment in err and "Traceback" not in err


def test_corrupt_output_file_is_refused_not_overwritten(tmp_path, capsys):
    scene = write_scene(tmp_path)
    out = tmp_path / "bad.h5"
    out.write_bytes(b"not an hdf5 file at all" * 10)
    code = cli.main(["sweep", str(scene), "--out", str(out), "--quiet", "--no-figure"])
    _, err = capsys.readouterr()
    assert code == 2 and str(out) in err and len(err.strip().splitlines()) == 1
    assert out.read_bytes().startswith(b"not an hdf5")


CHAOS = """
name = "chaos_small"
[sweep]
parameter = "mu"
values = [0.0, 0.5, 4.0]
[seeds]
kind = "grid"
n = 40
[integration]
crossings = 20
tmax = 300.0
[compute]
sections = true
lyapunov = true
separatrices = true
[lyapunov]
time = 300.0
threshold = 4.0
[figure]
share_scale = false
"""


def test_sweep_stores_chaos_indicators_fraction_and_separatrices(tmp_path, capsys):
    scene = write_scene(tmp_path, CHAOS)
    out = tmp_path / "c.h5"
    code, (stdout, _) = sweep([scene, "--out", out, "--figure", tmp_path / "c"], capsys)
    assert code == 0
    assert "chaotic fraction" in stdout
    data = store.read_store(out)
    fr = []
    for i in range(3):
        pd = data.panels[i]
        n = pd.n_orbits
        for k in ("megno", "mlce", "fli", "lyapunov_status"):
            assert pd.extra[k].shape == (n,)
        fr.append(pd.attrs["chaotic_fraction"])
        assert 0 <= pd.attrs["chaotic_fraction_error"] < 0.2
    # mu = 0 is integrable (Chaplygin): almost nothing chaotic; mu = 0.5: almost everything
    assert fr[0] < 0.1 and fr[1] > 0.8
    # separatrices where the central fixed point is hyperbolic (mu = 0, 0.5), none where stable (mu = 4)
    import json
    fp = [json.loads(data.panels[i].attrs["fixed_point"]) for i in range(3)]
    assert [f["stable"] for f in fp] == [False, False, True]
    assert len(data.panels[0].separatrices()) == 4 and data.panels[2].separatrices() == []
    assert abs(fp[0]["p1"]) < 1e-12 and abs(fp[0]["trace"] - reference.trace_solution_I(1.0, 0.5, 2.0, 1.0, 2.0)) < 1e-8
    for suffix in ("", "_chaosmap", "_fraction"):
        assert (tmp_path / f"c{suffix}.png").stat().st_size > 5000
        assert (tmp_path / f"c{suffix}.pdf").exists()


def test_run_sweep_returns_a_report_and_a_rerun_computes_nothing(tmp_path, capsys):
    """The Python entry point: a frozen report (no printing); the counts agree with the store."""
    import dataclasses

    from explorer.app.runner import format_report, run_sweep

    path = write_scene(tmp_path)
    out = tmp_path / "small.h5"
    first = run_sweep(path, out, draw=False, progress=False)
    assert capsys.readouterr().out == ""
    assert first.computed == (0, 1, 2) and first.n_panels == 3 and first.figure == ()
    data = store.read_store(out)
    assert first.crossings == sum(int(data.panels[i].arrays["count"].sum()) for i in range(3))
    assert first.orbits == sum(len(data.panels[i].arrays["count"]) for i in range(3))
    assert 0.0 < first.max_dh < 1e-8
    with pytest.raises(dataclasses.FrozenInstanceError):
        first.orbits = 0
    again = run_sweep(path, out, draw=False, progress=False)
    assert again.computed == () and again.crossings == 0
    assert "0 computed, 3 already stored" in format_report(again)


def test_a_new_megno_threshold_reclassifies_the_stored_fraction_without_recomputing(tmp_path):
    """Issue 14 point 6: the threshold is outside the panel hash, and the stored chaotic_fraction
    follows it (recomputed from the stored MEGNO values, atomically)."""
    from explorer.analysis.lyapunov import chaotic_fraction
    from explorer.app.runner import run_sweep

    text = SMALL.replace("n = 24", "n = 12").replace("crossings = 40", "crossings = 5") + \
        "[compute]\nlyapunov = true\n[lyapunov]\ntime = 200.0\nthreshold = 4.0\n"
    out = tmp_path / "small.h5"
    first = run_sweep(write_scene(tmp_path, text), out, draw=False, progress=False)
    before = {i: store.read_store(out).panels[i].extra["megno"].copy() for i in range(3)}
    again = run_sweep(write_scene(tmp_path, text.replace("threshold = 4.0", "threshold = 2.5")), out,
                      draw=False, progress=False)
    assert first.computed == (0, 1, 2) and again.computed == () and again.restamped == (0, 1, 2)
    data = store.read_store(out)
    changed = 0
    for i in range(3):
        pd = data.panels[i]
        assert np.array_equal(pd.extra["megno"], before[i])          # nothing recomputed
        ok = pd.extra["lyapunov_status"] == 0
        frac, err, _ = chaotic_fraction(pd.extra["megno"], 2.5, ok)
        assert pd.attrs["class_indicator"] == "megno" and pd.attrs["class_threshold"] == 2.5
        assert pd.attrs["chaotic_fraction"] == frac and pd.attrs["chaotic_fraction_error"] == err
        changed += frac != chaotic_fraction(pd.extra["megno"], 4.0, ok)[0]
    assert changed >= 1   # the threshold really moved some orbits across (else the test proves nothing)
    third = run_sweep(write_scene(tmp_path, text.replace("threshold = 4.0", "threshold = 2.5")), out,
                      draw=False, progress=False)
    assert third.restamped == ()


MAP_SCENE = """
name = "map"
[model]
a1 = 1.0
a2 = 0.5
b = 2.0
lam = 1.0
mu = 0.02
[energy]
h = 2.0
[compute]
sections = false
lyapunov = true
[lyapunov]
time = 100.0
indicators = ["megno", "sali"]
map_resolution = 64
"""


def test_an_adaptive_map_panel_fills_some_cells_computes_the_rest_as_the_exact_map_bit_for_bit_and_agrees(monkeypatch):
    """docs/scenes.md, "Adaptive maps": the computed cells of an adaptive map panel are the exact
    panel's same cells bit for bit (every indicator array), the filled ones leave >= 99.5 % of the
    cells in the same class (MEGNO > threshold) and the chaotic fraction within 0.5 points."""
    from explorer.analysis import sweep
    from explorer.io.scene import parse_scene

    monkeypatch.setattr(sweep, "MAP_COARSE", 16)         # a 64-cell map from a lattice of 16 a side
    panels = {}
    for key, text in (("adaptive", MAP_SCENE), ("exact", MAP_SCENE + "exact = true\n")):
        spec = sweep.build_spec(parse_scene(text), [0], chunk_orbits=0)
        sweep.run(spec, lambda panel, arrays, key=key: panels.__setitem__(key, arrays))
    a, e = panels["adaptive"], panels["exact"]
    done = a["map_computed"]
    assert "map_computed" not in e and 0.2 < done.mean() < 0.9     # many cells were filled
    for k in ("megno", "sali", "gali2", "mlce", "fli", "lyapunov_status", "lyapunov_dh"):
        np.testing.assert_array_equal(a[k][done], e[k][done], err_msg=k)
    for k in ("sali", "gali2", "mlce", "fli", "lyapunov_dh"):
        assert np.isnan(a[k][~done]).all(), k              # a filled cell has its MEGNO only
    assert np.isfinite(a["megno"]).all()
    thr = 4.0
    same = sweep.classify(a, "megno", thr)[0] == sweep.classify(e, "megno", thr)[0]
    assert same.mean() >= 0.995
    fa, fe = sweep.panel_fraction(a, "megno", thr)[0], sweep.panel_fraction(e, "megno", thr)[0]
    assert 0.05 < fe < 0.95 and abs(fa - fe) <= 0.005


def test_an_adaptive_fli_map_panel_is_classified_by_fli_stored_with_its_mask_and_agrees_with_the_exact_map(
        tmp_path, monkeypatch):
    """docs/scenes.md, "Adaptive maps", for a map of another indicator than MEGNO: the refinement
    follows FLI at its own threshold (2 ln T); the stored panel's computed cells are the exact
    panel's bit for bit (every indicator array), ``map_computed`` and ``map_chaotic`` read back from
    the store, >= 99.5 % of the cells in the same FLI class as the exact map's, and the panel's
    chaotic fraction is FLI's (attributes ``class_indicator``, ``class_threshold``, the summary)."""
    import math

    from explorer.analysis import sweep
    from explorer.app.runner import format_report, run_sweep
    from explorer.io.scene import parse_scene

    monkeypatch.setattr(sweep, "MAP_COARSE", 16)         # a 64-cell map from a lattice of 16 a side
    text = MAP_SCENE.replace('indicators = ["megno", "sali"]', 'indicators = ["megno", "fli"]\nmap_indicator = "fli"')
    exact: dict = {}
    sweep.run(sweep.build_spec(parse_scene(text + "exact = true\n"), [0], chunk_orbits=0),
              lambda panel, arrays: exact.update(arrays))
    report = run_sweep(parse_scene(text), tmp_path / "a.h5", draw=False, progress=False)
    pd = store.read_store(tmp_path / "a.h5").panels[0]
    a, done = pd.extra, pd.extra["map_computed"]
    assert 0.2 < done.mean() < 0.9                                          # many cells were filled
    for k in ("megno", "fli", "mlce", "lyapunov_status"):
        np.testing.assert_array_equal(a[k][done], exact[k][done], err_msg=k)
    assert np.isnan(a["megno"][~done]).all() and np.isfinite(a["fli"]).all()   # a filled cell has its FLI only
    thr = 2 * math.log(100.0)
    chaotic_a, _ = sweep.classify(a, "fli", thr)
    chaotic_e, ok = sweep.classify(exact, "fli", thr)
    np.testing.assert_array_equal(a["map_chaotic"][done], chaotic_e[done])   # the stored class of a computed cell
    assert (chaotic_a == chaotic_e).mean() >= 0.995
    fe = sweep.panel_fraction(exact, "fli", thr)[0]
    assert 0.05 < fe < 0.95 and abs(pd.attrs["chaotic_fraction"] - fe) <= 0.005
    assert pd.attrs["class_indicator"] == "fli" and pd.attrs["class_threshold"] == thr
    assert f"(FLI > {thr:.3g})" in format_report(report)


def test_an_adaptive_frequency_diffusion_map_panel_computes_its_cells_as_the_exact_path(monkeypatch):
    """docs/scenes.md, "Adaptive maps": a frequency-diffusion map is refined by its own values (chaotic
    above -6); each computed cell's frequency diffusion and tangent indicators are the exact path's
    (explorer.frequency_diffusion on the panel's section map, seed for seed) bit for bit."""
    from explorer.analysis import sweep
    from explorer.io.scene import parse_scene

    monkeypatch.setattr(sweep, "MAP_COARSE", 2)          # an 8-cell map from a lattice of 2 a side
    text = (MAP_SCENE.replace("time = 100.0", "time = 5.0").replace("map_resolution = 64", "map_resolution = 8")
            .replace('indicators = ["megno", "sali"]', 'indicators = ["megno", "frequency_diffusion"]\n'
                     'map_indicator = "frequency_diffusion"\ncenter = [0.0, 0.0]\ndiffusion_iterates = 10'))
    spec = sweep.build_spec(parse_scene(text), [0], chunk_orbits=0)
    got: dict = {}
    sweep.run(spec, lambda panel, arrays: got.update(arrays))
    done = got["map_computed"]
    assert 3 <= done.sum() < len(done) and np.isfinite(got["frequency_diffusion"]).all()
    exact = spec.indicator_arrays(spec.panels[0], np.flatnonzero(done))[1]
    for k in ("frequency_diffusion", "megno", "fli", "lyapunov_status"):
        np.testing.assert_array_equal(got[k][done], exact[k], err_msg=k)
    chaotic = sweep.classify(got, "frequency_diffusion", -6.0)[0]
    np.testing.assert_array_equal(got["map_chaotic"], chaotic)

