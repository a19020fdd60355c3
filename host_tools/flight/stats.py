"""Small statistics for flight summaries (no scipy): mean and the 95 % confidence half-width of the mean."""
import math
from collections.abc import Sequence

# two-sided 95 % quantiles of Student's t (0.975 one-sided), by degrees of freedom
_T975 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262, 10: 2.228,
         11: 2.201, 12: 2.179, 13: 2.160, 14: 2.145, 15: 2.131, 16: 2.120, 17: 2.110, 18: 2.101, 19: 2.093,
         20: 2.086, 21: 2.080, 22: 2.074, 23: 2.069, 24: 2.064, 25: 2.060, 26: 2.056, 27: 2.052, 28: 2.048,
         29: 2.045, 30: 2.042, 40: 2.021, 60: 2.000, 120: 1.980}


def t_quantile_975(dof: int) -> float:
    """t_{0.975, dof}: exact table values, linear in 1/dof between them, 1.960 in the limit."""
    if dof < 1:
        raise ValueError("degrees of freedom must be >= 1")
    if dof in _T975:
        return _T975[dof]
    keys = sorted(_T975)
    if dof > keys[-1]:
        lo, hi, t_lo, t_hi = keys[-1], math.inf, _T975[keys[-1]], 1.960
    else:
        lo = max(k for k in keys if k < dof)
        hi = min(k for k in keys if k > dof)
        t_lo, t_hi = _T975[lo], _T975[hi]
    w = (1.0 / lo - 1.0 / dof) / (1.0 / lo - (0.0 if hi == math.inf else 1.0 / hi))
    return t_lo + w * (t_hi - t_lo)


def mean_ci95(values: Sequence[float]) -> tuple[float | None, float | None]:
    """(mean, 95 % CI half-width) of a sample; half-width None below two values, mean None if empty."""
    n = len(values)
    if n == 0:
        return None, None
    mean = sum(values) / n
    if n < 2:
        return mean, None
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1))
    return mean, t_quantile_975(n - 1) * sd / math.sqrt(n)
