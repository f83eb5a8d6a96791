"""Analysis layer: arrays in, arrays (and frozen result objects) out; no files, no figures.

- :mod:`explorer.analysis.sections` -- crossings of the section: validation, method dispatch;
- :mod:`explorer.analysis.lyapunov` -- chaos indicators (mLCE, MEGNO, FLI) of many orbits;
- :mod:`explorer.analysis.fixedpoints` -- the section map, Newton, continuation, separatrices;
- :mod:`explorer.analysis.melnikov` -- the Melnikov integral along R7 and the measured splitting;
- :mod:`explorer.analysis.trajectory` -- the full system R1: the body's path in the plane;
- :mod:`explorer.analysis.seeds` -- initial conditions on the allowed region of the section;
- :mod:`explorer.analysis.sweep` -- a sweep as the pure map ``task(spec, i)`` over chunks.

Imports: kernels, model, integrate.
"""
