"""The one registry of chaos indicators (docs/commands/lyapunov.md): the columns of the tangent
loops' result row ``RES_*`` and extra row ``EXT_*``, and :data:`INDICATORS`, the plain-data table
every layer reads (pure Python).  A new indicator: docs/contributing.md.
"""
from __future__ import annotations

from dataclasses import dataclass

#: layout of the accumulator vector
ACC_LOG, ACC_W, ACC_YINT, ACC_FLI, ACC_Y, ACC_T = range(6)
N_ACC = 6
#: layout of the per-orbit result row (and of history rows)
RES_T, RES_MLCE, RES_MEGNO, RES_Y, RES_FLI = range(5)
N_RES = 5
#: layout of the extra result row of two deviation vectors and early classification
EXT_SALI, EXT_GALI2, EXT_EARLY = range(3)
N_EXT = 3

#: the row an indicator is read from: the tangent loops' result row or extra row, or (ORBIT) none of
#: them: computed from the orbit's section returns (frequency diffusion), one value per orbit
RESULT, EXTRA, ORBIT = "result", "extra", "orbit"


@dataclass(frozen=True)
class Indicator:
    """One chaos indicator: where the tangent loops put it and how every layer shows it."""

    name: str
    row: str
    column: int
    title: str
    description: str
    default: bool = True
    dtype: str = "float64"

    @property
    def vectors(self) -> int:
        """Deviation vectors it needs (2 for the extra row: only the methods whose kind has the loop
        of two vectors compute it, :func:`explorer.analysis.lyapunov.methods_for`; 0 for ORBIT)."""
        return {EXTRA: 2, ORBIT: 0}.get(self.row, 1)

    @property
    def tangent(self) -> bool:
        """Whether the tangent loops compute it (:func:`explorer.analysis.lyapunov.indicators`)."""
        return self.row != ORBIT

    @property
    def in_history(self) -> bool:
        """Whether the history rows (the result row at the history times) have its column."""
        return self.row == RESULT


#: every chaos indicator, in the order of output lines and JSON keys
INDICATORS = (
    Indicator("mlce", RESULT, RES_MLCE, "finite-time mLCE",
              "finite-time maximal Lyapunov exponent ln(|w(T)| / |w(0)|) / T (Benettin et al. 1980)"),
    Indicator("megno", RESULT, RES_MEGNO, "MEGNO",
              "mean MEGNO <Y>(T) (Cincotta & Simó 2000): -> 0 stable periodic, -> 2 quasi-periodic, grows if chaotic"),
    Indicator("fli", RESULT, RES_FLI, "FLI",
              "fast Lyapunov indicator max_{t <= T} ln |w(t)| (Froeschlé, Lega & Gonczi 1997)"),
    Indicator("sali", EXTRA, EXT_SALI, "SALI",
              "smaller alignment index min(|w1 + w2|, |w1 - w2|) of two unit deviation vectors (Skokos 2001)",
              default=False),
    Indicator("gali2", EXTRA, EXT_GALI2, "GALI2",
              "generalized alignment index |w1 ^ w2| of two unit deviation vectors (Skokos et al. 2007)",
              default=False),
    Indicator("frequency_diffusion", ORBIT, 0, "frequency diffusion",
              "log10 |nu1 - nu2| of the weighted-Birkhoff rotation numbers around [lyapunov] center of the first "
              "and second N returns (Laskar 1990; Das, Sander, Yorke & Meiss 2017)", default=False),
)
#: the names, in table order
NAMES = tuple(i.name for i in INDICATORS)
#: the indicators of the tangent loops (those :func:`explorer.analysis.lyapunov.indicators` computes)
TANGENT = tuple(i for i in INDICATORS if i.tangent)
TANGENT_NAMES = tuple(i.name for i in TANGENT)
#: computed unless ``which`` says otherwise
DEFAULT_NAMES = tuple(i.name for i in INDICATORS if i.default)
#: name -> Indicator
BY_NAME = {i.name: i for i in INDICATORS}
