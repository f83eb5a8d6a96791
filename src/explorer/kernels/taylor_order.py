"""The order rule of the Taylor method (Jorba & Zou 2005, section 3.2) in plain Python."""
import math

MIN_ORDER = 4
MAX_ORDER = 40


def order_for_tolerance(tol):
    """Jorba-Zou optimal order p = ceil(-ln(tol)/2 + 1), clipped to [MIN_ORDER, MAX_ORDER]."""
    p = int(math.ceil(-math.log(tol) / 2.0 + 1.0))
    return max(MIN_ORDER, min(MAX_ORDER, p))
