"""Physics layer: the model of docs/model.md and nothing else.

- :mod:`explorer.model.parameters` -- parameters and presets, the energy, the
  Casimir, the extra integrals, the section and its allowed region (numpy,
  vectorised; what a physicist checks against docs/model.md R1-R11);
- :mod:`explorer.model.equations` -- the same vector field compiled for the
  integrators: right-hand side (R3), exact sub-flows (R4), Taylor recurrences,
  variational equations, the section function;
- :mod:`explorer.model.exact` -- closed-form solutions used as references.

``from explorer import model`` gives the names of ``parameters`` (this package
re-exports them) without importing Numba.
"""
from explorer.model.parameters import *  # noqa: F401,F403
from explorer.model.parameters import __all__  # noqa: F401
