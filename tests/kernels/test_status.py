"""Status codes: the typed enum and the plain ints the kernels use are the same values, and
the values stored in existing HDF5 files (status_names attribute) keep their meaning."""
import numpy as np

from explorer import model
from explorer.analysis import sections
from explorer.kernels import STATUS_NAMES, Status, status


def test_status_values_are_the_stored_codes():
    # files written since the first release store these codes; renumbering would change old data
    # (new codes are appended: UNRESOLVED, a fixed step that does not resolve the motion; CANCELLED,
    # a caller's stop switch)
    assert [(s.name, int(s)) for s in Status] == [("DONE", 0), ("TMAX", 1), ("NONFINITE", 2),
                                                  ("MAX_STEPS", 3), ("STEP_UNDERFLOW", 4), ("UNRESOLVED", 5),
                                                  ("CANCELLED", 6)]
    assert STATUS_NAMES == {int(s): s.description for s in Status}
    assert status.STATUS_TMAX == Status.TMAX and isinstance(status.STATUS_TMAX, int)


def test_a_driver_status_reads_back_as_the_enum():
    prm = model.FIGURE4.with_(mu=0.5)
    y0 = model.section_state(prm, np.array([0.1, 0.1]), np.zeros(2), 2.0)
    done = sections.crossings(prm, states=y0, n_crossings=5, tmax=1e3, threads=1)
    res = sections.crossings(prm, states=y0, n_crossings=5, tmax=1.0, threads=1)  # a crossing takes about 4.4
    assert done.status_of(0) is Status.DONE and res.status_of(1) is Status.TMAX
    assert res.status_name(1) == Status.TMAX.description == "time budget exhausted"
