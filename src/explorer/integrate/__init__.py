"""Integration layer: the compiled stepping loops that drive the kernels with this model's field.

- :mod:`explorer.integrate.drivers` -- per-orbit loops and parallel batch drivers for the
  adaptive Taylor method, DOP853 and the splitting compositions (arrays in, status codes out);
- :mod:`explorer.integrate.lanes` -- the Taylor batch on 8-lane SIMD vectors, bit-identical to
  the scalar driver, with a shared queue of orbits (``_lanes_generated`` is written by
  ``tools/gen_lanes.py`` from the scalar recurrence);
- :mod:`explorer.integrate.tangent` -- the same loops with tangent dynamics: chaos indicators
  and the section return map with its Jacobian.

Imports: kernels and model only.
"""
