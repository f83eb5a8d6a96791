"""The columns of the crossing drivers' ``carry`` and ``limits``, in plain Python (re-exported by
:mod:`explorer.integrate.drivers`)."""
from explorer.kernels.taylor_order import MAX_ORDER

#: columns of ``carry``
CARRY_T = 0
CARRY_TC = 1
CARRY_G = 2
CARRY_STEPS = 3
CARRY_H0 = 4
CARRY_HABS = 5
N_CARRY = 6
#: columns of ``limits``
LIMIT_TARGET = 0
LIMIT_ROOM = 1
#: the most crossings one step can add past a block's target (roots of one step: the Taylor
#: polynomial of degree <= MAX_ORDER, DOP853's dense output of degree 7, a splitting step 2)
MAX_ROOTS_PER_STEP = MAX_ORDER
