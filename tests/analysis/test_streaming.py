"""Streamed crossings (sections.iter_crossings): blocks of bounded size whose rows, final states,
statuses and budgets are bit for bit those of one uninterrupted run, for every method, and a run
continued from a block's state (a checkpoint) ends where the uninterrupted one ends."""
import numpy as np
import pytest

from explorer import model
from explorer.analysis import sections
from explorer.integrate import drivers, layout
from explorer.kernels import Status
from explorer.model import ParameterError

PRM = model.FIGURE4.with_(mu=0.5)
P1 = np.linspace(-0.5, 0.5, 9)
P2 = np.zeros(9) + 0.1
PTS = np.column_stack([P1, P2])
METHODS = {"taylor": dict(tol=1e-12), "dop853": dict(tol=1e-11), "split6": dict(dt=0.05)}


def _gather(blocks, n):
    rows = [[] for _ in range(n)]
    last = None
    for b in blocks:
        for i, j in enumerate(b.index):
            assert b.start[i] == sum(len(r) for r in rows[j])   # blocks follow each other
            rows[j].append(b.rows(i))
        last = b
    return [np.concatenate(r) if r else np.zeros((0, 5)) for r in rows], last.state


def _assert_same_run(ref, rows, st):
    for j in range(len(rows)):
        np.testing.assert_array_equal(rows[j], ref.orbit(j))
    np.testing.assert_array_equal(st.done, ref.count)
    np.testing.assert_array_equal(st.status, ref.status)
    np.testing.assert_array_equal(st.y, ref.final)
    np.testing.assert_array_equal(st.info, ref.info)


@pytest.mark.parametrize("method", list(METHODS))
@pytest.mark.parametrize("block", [1, 7, 100])
def test_streamed_blocks_are_bit_identical_to_one_run(method, block):
    # direction 0 (both ways): steps holding two crossings fall on block boundaries too
    ref = sections.crossings(PRM, 2.0, PTS, n_crossings=250, method=method, direction=0, **METHODS[method])
    rows, st = _gather(sections.iter_crossings(PRM, 2.0, PTS, n_crossings=250, method=method, direction=0, block=block,
                                               **METHODS[method]), len(P1))
    _assert_same_run(ref, rows, st)
    assert st.blocks == -(-250 // block)


@pytest.mark.parametrize("method", list(METHODS))
def test_a_run_continued_from_a_blocks_state_ends_as_the_uninterrupted_run(method):
    ref = sections.crossings(PRM, 2.0, PTS, n_crossings=120, method=method, **METHODS[method])
    it = sections.iter_crossings(PRM, 2.0, PTS, n_crossings=120, method=method, block=25, **METHODS[method])
    first = [next(it), next(it)]          # "killed" after two blocks; their state was checkpointed
    saved = sections.StreamState.from_arrays(first[-1].state.as_arrays())
    rest = list(sections.iter_crossings(PRM, 2.0, PTS, n_crossings=120, method=method, block=25, state=saved,
                                        **METHODS[method]))
    rows, st = _gather(first + rest, len(P1))
    _assert_same_run(ref, rows, st)


@pytest.mark.parametrize("method", ["taylor", "split6"])
def test_blocks_cut_at_their_steps_are_bit_identical_to_one_run_and_keep_the_runs_step_budget(method):
    """step_block ends a block after that many steps of the least advanced orbit: the rows, states,
    statuses and the run's own step budget are those of one run, and no block lets an orbit
    take more than step_block steps beyond the least advanced one."""
    for max_steps in (10**6, 2500):
        ref = sections.crossings(PRM, 2.0, PTS, n_crossings=60, method=method, max_steps=max_steps, **METHODS[method])
        blocks = list(sections.iter_crossings(PRM, 2.0, PTS, n_crossings=60, method=method, max_steps=max_steps,
                                              block=40, step_block=300, **METHODS[method]))
        rows, st = _gather(blocks, len(P1))
        _assert_same_run(ref, rows, st)
        steps = [b.state.carry[:, layout.CARRY_STEPS] for b in blocks]
        assert all(np.max(b - a) <= 300 + np.ptp(a) for a, b in zip(steps, steps[1:]))
        assert len(blocks) > -(-60 // 40)      # the step cap, not only the crossing count, cut blocks
    assert np.any(ref.status == int(Status.MAX_STEPS))   # 2500 steps end the run, not a block's cap


def test_step_block_is_refused_for_dop853_whose_rows_a_cut_would_change():
    """DOP853 continued from a step cap does not give the uninterrupted rows (its kind says
    resumes_at_any_step=False); step_block names the methods it allows."""
    from explorer.integrate import methods
    assert not methods.get("dop853").loops.resumes_at_any_step
    with pytest.raises(ParameterError, match="step_block.*taylor"):
        next(sections.iter_crossings(PRM, 2.0, PTS, n_crossings=5, method="dop853", tol=1e-11, step_block=300))


def test_step_block_must_be_a_positive_integer():
    with pytest.raises(ParameterError, match="step_block"):
        next(sections.iter_crossings(PRM, 2.0, PTS, n_crossings=5, step_block=0))


def test_budgets_are_for_the_whole_run_not_the_block():
    # a time budget that ends the run inside the third block: same crossings and TMAX as one run
    ref = sections.crossings(PRM, 2.0, PTS, n_crossings=400, tmax=250.0, tol=1e-12)
    assert np.all(ref.status == int(Status.TMAX))
    rows, st = _gather(sections.iter_crossings(PRM, 2.0, PTS, n_crossings=400, tmax=250.0, tol=1e-12, block=10),
                       len(P1))
    _assert_same_run(ref, rows, st)
    ref = sections.crossings(PRM, 2.0, PTS, n_crossings=400, max_steps=3000, method="dop853", tol=1e-11)
    assert np.all(ref.status == int(Status.MAX_STEPS))
    rows, st = _gather(sections.iter_crossings(PRM, 2.0, PTS, n_crossings=400, max_steps=3000, method="dop853",
                                               tol=1e-11, block=10), len(P1))
    _assert_same_run(ref, rows, st)


def test_block_memory_does_not_grow_with_the_requested_crossings():
    it = sections.iter_crossings(PRM, 2.0, PTS[:2], n_crossings=10**12, tol=1e-12, block=50)
    b = next(it)
    assert b.data.shape == (2, 50 + drivers.MAX_ROOTS_PER_STEP, 5)
    assert np.all(b.count >= 50)
    it.close()


def test_a_result_larger_than_memory_is_refused_up_front_with_its_size():
    with pytest.raises(ParameterError, match=r"crossings: 2 orbits x 100000000000 crossings need 8 TB"):
        sections.crossings(PRM, 2.0, PTS[:2], n_crossings=10**11)
    with pytest.raises(ParameterError, match="block"):
        next(sections.iter_crossings(PRM, 2.0, PTS[:2], n_crossings=10, block=0))
