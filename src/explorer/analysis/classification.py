"""How a chaos indicator classifies an orbit: chaotic or regular by a threshold (docs/chaos_map.md).

One rule serves :class:`explorer.Indicators`, the chaos maps' cells and a sweep's panels: an orbit
is chaotic beyond the threshold (above it for mLCE, MEGNO, FLI and frequency diffusion, below it
for SALI and GALI_2) or when it was stopped early as chaotic; it is valid when it was stopped
early, or integrated to the end with a finite value.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["CLASS_NAMES", "FREQUENCY", "RULES", "class_text", "default_threshold", "fraction", "orbit_classes"]


@dataclass(frozen=True)
class _Rule:
    """How an indicator classifies and compares: chaotic ``above`` the threshold (else below),
    compared in log (values at least ``floor``) or as is."""

    above: bool
    log: bool
    floor: float


#: the indicator of :func:`explorer.frequency_diffusion` (log10 |nu1 - nu2|)
FREQUENCY = "frequency_diffusion"
#: the indicators that classify, and their rules
RULES = {"mlce": _Rule(True, True, 1e-4), "megno": _Rule(True, True, 0.5), "fli": _Rule(True, False, 0.0),
         "sali": _Rule(False, True, 1e-16), "gali2": _Rule(False, True, 1e-16),
         FREQUENCY: _Rule(True, False, 0.0)}   # log10 |nu1 - nu2| already
#: how a summary, a raster's title and an atlas name the indicator that classifies
CLASS_NAMES = {"megno": "MEGNO", "mlce": "mLCE", "fli": "FLI", "sali": "SALI", "gali2": "GALI2",
               FREQUENCY: "log10 |nu1 - nu2|"}


def default_threshold(indicator: str, tmax: float) -> float:
    """The class threshold of ``indicator`` at time T: <Y> > 4 (MEGNO); mLCE > 3 ln T / T (the
    regular envelope); FLI > 2 ln T (|w| grows linearly on a torus); SALI, GALI_2 < 1e-8; frequency
    diffusion log10 |nu1 - nu2| > -6 (docs/chaos_map.md)."""
    T = max(float(tmax), math.e)
    return {"megno": 4.0, "mlce": 3.0 * math.log(T) / T, "fli": 2.0 * math.log(T), FREQUENCY: -6.0}.get(indicator,
                                                                                                      1e-8)


def orbit_classes(values, indicator: str, threshold: float, early=None, ok=None) -> tuple:
    """(chaotic, valid) per orbit with ``values`` of ``indicator``: chaotic beyond ``threshold``
    (:data:`RULES`) or stopped ``early`` (nonzero); valid when stopped early, or finite and
    integrated to the end (``ok``, all when None)."""
    v = np.asarray(values, float)
    early = np.zeros(v.shape, bool) if early is None else np.asarray(early) > 0
    with np.errstate(invalid="ignore"):
        beyond = v > threshold if RULES[indicator].above else v < threshold
    finite = np.isfinite(v) if ok is None else np.isfinite(v) & np.asarray(ok, bool)
    return early | beyond, early | finite


def fraction(chaotic, valid) -> tuple:
    """(fraction p, binomial standard error, n) of the ``valid`` orbits that are ``chaotic``: the error
    is sqrt(p (1 - p) / n), at least 1 / (2 n) so that a sample all of one class does not claim
    none; (NaN, NaN, 0) when no orbit is valid."""
    valid = np.asarray(valid, bool)
    n = int(valid.sum())
    if n == 0:
        return float("nan"), float("nan"), 0
    p = float(np.mean(np.asarray(chaotic, bool)[valid]))
    return p, math.sqrt(max(p * (1 - p), 0.25 / n) / n), n


def class_text(indicator: str, threshold: float) -> str:
    """How :func:`orbit_classes` classifies, as text: ``MEGNO > 4``, ``SALI < 1e-08``."""
    return f"{CLASS_NAMES[indicator]} {'>' if RULES[indicator].above else '<'} {threshold:.3g}"
