"""Physics layer (docs/model.md): re-exports :mod:`explorer.model.parameters` without importing
Numba; :mod:`~explorer.model.equations` is the compiled field, :mod:`~explorer.model.exact` the
closed-form references.
"""
from explorer.model.parameters import *  # noqa: F401,F403
from explorer.model.parameters import __all__  # noqa: F401
