"""A two-class linear SVM trained by dual coordinate descent (Hsieh et al., ICML 2008; liblinear's
L2-regularised L1-loss solver). Pure numpy, deterministic for a given seed, no scikit-learn needed.

    minimise  0.5 |w|^2 + sum_i C_i max(0, 1 - y_i (w . x_i + b))

The bias is learned as the weight of a constant feature (so it is lightly regularised, as in liblinear).
C_i is C scaled per class so that positives and negatives weigh the same in total.
"""
import numpy as np

BIAS_FEATURE = 1.0


def train_linear_svm(features: np.ndarray, labels: np.ndarray, c: float = 1.0, seed: int = 0, max_epochs: int = 60,
                     tolerance: float = 1e-3) -> tuple[np.ndarray, float]:
    """features (n, d), labels in {-1, +1} -> (weights (d,) float32, bias float)."""
    x = np.asarray(features, np.float64)
    y = np.where(np.asarray(labels) > 0, 1.0, -1.0)
    n_pos, n_neg = int((y > 0).sum()), int((y < 0).sum())
    if n_pos == 0 or n_neg == 0:
        raise ValueError("need positive and negative examples (got %d and %d)" % (n_pos, n_neg))
    xa = np.hstack([x, np.full((len(x), 1), BIAS_FEATURE)])
    upper = np.where(y > 0, c * len(y) / (2.0 * n_pos), c * len(y) / (2.0 * n_neg))
    diagonal = (xa * xa).sum(axis=1)
    alpha = np.zeros(len(y))
    w = np.zeros(xa.shape[1])
    rng = np.random.RandomState(seed)
    for _epoch in range(max_epochs):
        largest_violation = 0.0
        for i in rng.permutation(len(y)):
            gradient = y[i] * xa[i].dot(w) - 1.0
            if alpha[i] == 0.0:
                projected = min(gradient, 0.0)
            elif alpha[i] == upper[i]:
                projected = max(gradient, 0.0)
            else:
                projected = gradient
            largest_violation = max(largest_violation, abs(projected))
            if projected != 0.0 and diagonal[i] > 0:
                old = alpha[i]
                alpha[i] = min(max(old - gradient / diagonal[i], 0.0), upper[i])
                w += (alpha[i] - old) * y[i] * xa[i]
        if largest_violation < tolerance:
            break
    return w[:-1].astype(np.float32), float(w[-1] * BIAS_FEATURE)
