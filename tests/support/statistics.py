"""Statistical helpers shared by the sampling tests."""

import numpy as np
from scipy import stats


def chi_square_pvalue(observed, probabilities):
    """p-value of Pearson's chi-square test of histogram counts against the bins' probabilities;
    adjacent bins are pooled until each pool expects at least 5 samples."""
    observed, probabilities = np.ravel(observed), np.ravel(probabilities)
    expected = probabilities * observed.sum()
    pools_o, pools_e, o, e = [], [], 0.0, 0.0
    for oi, ei in zip(observed, expected):
        o, e = o + oi, e + ei
        if e >= 5:
            pools_o.append(o)
            pools_e.append(e)
            o, e = 0.0, 0.0
    pools_o[-1] += o
    pools_e[-1] += e
    pools_o, pools_e = np.array(pools_o), np.array(pools_e)
    statistic = np.sum((pools_o - pools_e) ** 2 / pools_e)
    return stats.chi2.sf(statistic, pools_o.size - 1)
