"""explorer: Poincaré sections and chaos for Chaplygin's equations of a heavy
rigid body moving in an ideal fluid with circulation (Borisov & Mamaev).

See README.md for the quick start and ../shared/MODEL.md (R1-R10) for the
equations every module cites.
"""
__version__ = "0.1.0"
