"""Analysis layer: arrays in, arrays (and frozen result objects) out; no files, no figures.

- :mod:`explorer.analysis.sections` -- crossings of the section: validation, method dispatch;
- :mod:`explorer.analysis.lyapunov` -- chaos indicators (mLCE, MEGNO, FLI) of many orbits;
- :mod:`explorer.analysis.section_map` -- the section map P and its Jacobian (:class:`SectionMap`);
- :mod:`explorer.analysis.periodic` -- periodic orbits of any period: Newton, search, symmetry, continuation;
- :mod:`explorer.analysis.fixedpoints` -- fixed points (period 1), separatrices;
- :mod:`explorer.analysis.continuation` -- parameter stepping shared by fixed points and periodic orbits;
- :mod:`explorer.analysis.melnikov` -- the Melnikov integral along R7 and the measured splitting;
- :mod:`explorer.analysis.trajectory` -- the full system R1: the body's path in the plane;
- :mod:`explorer.analysis.seeds` -- initial conditions on the allowed region of the section;
- :mod:`explorer.analysis.sweep` -- a sweep as the pure map ``task(spec, i)`` over chunks.

Imports: kernels, model, integrate.
"""
