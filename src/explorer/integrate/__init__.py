"""Integration layer: the compiled stepping loops that drive the kernels with this model's field.

- :mod:`explorer.integrate.drivers` -- per-orbit loops and parallel batch drivers for DOP853 and
  the splitting compositions (arrays in, status codes out), and what every crossing loop shares
  (carry, kept crossings, outputs);
- :mod:`explorer.integrate.lanes` -- the Taylor crossing loop, on 8-lane SIMD vectors with a
  shared queue of orbits (a lone orbit is one lane); the recurrence's lane kernel
  ``_lanes_generated`` is written by ``tools/gen_lanes.py`` from the scalar one, the vector
  operations are :mod:`explorer.integrate.simd`;
- :mod:`explorer.integrate.tangent` -- the same loops with tangent dynamics: chaos indicators
  and the section return map with its Jacobian.

Imports: kernels and model only.
"""
