"""The only place that imports numba, lazily.  ``njit`` compiles with ``cache=True`` and never
``fastmath``; ``EXPLORER_NOJIT=1`` runs every kernel as plain Python.
"""
import os

NOJIT = os.environ.get("EXPLORER_NOJIT", "") not in ("", "0")

if NOJIT:  # pragma: no cover - debugging switch
    def njit(*args, **kwargs):
        if len(args) == 1 and callable(args[0]) and not kwargs:
            return args[0]
        return lambda f: f

    prange = range

    def set_num_threads(n):
        return None

    def get_num_threads():
        return 1

    def max_threads():
        return 1
else:
    def njit(*args, **kwargs):
        """``numba.njit`` with ``cache=True`` (and never fastmath)."""
        import numba

        kwargs.setdefault("cache", True)
        if kwargs.get("fastmath"):
            raise ValueError("fastmath is forbidden in explorer kernels")
        if len(args) == 1 and callable(args[0]):
            return numba.njit(**kwargs)(args[0])
        return numba.njit(*args, **kwargs)

    def set_num_threads(n):
        import numba

        numba.set_num_threads(n)

    def get_num_threads():
        import numba

        return numba.get_num_threads()

    def max_threads():
        """Numba's NUMBA_NUM_THREADS: the most threads a parallel loop can use in this process."""
        import numba

        return numba.config.NUMBA_NUM_THREADS

    def __getattr__(name):
        if name == "prange":
            import numba

            return numba.prange
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
