"""Which SVM for the top layer? Measures the choices on the same descriptors (host tool, not a CLI command).

    .venv/bin/python -m host_tools.detection.compare_svm TRAIN_FRAMES_CSV HOLDOUT_CROPS_CSV [--species S]

Kinds: two-class linear (this project's, dual coordinate descent with hard-negative mining), one-class RBF
(the paper authors' choice; cv2.ml ONE_CLASS, trained on positives only) and two-class RBF (cv2.ml C_SVC).
For each: the SVM's own crop accuracy, precision and recall on the hold-out crops (the top-layer test alone,
threshold 0 / the model's decision) and the microseconds per window to score one descriptor; the linear
kind's per-window cost in the detector is far lower still, because it is folded into per-frame maps.
"""
import argparse
import json
import time
from collections.abc import Callable
from typing import Any

import cv2
import numpy as np

from host_tools.detection import dataset, evaluation, training
from host_tools.detection.svm import train_linear_svm
from host_tools.threads import single_threaded

import foranav_features as features


def crop_descriptors(crops_csv: str) -> tuple[np.ndarray, np.ndarray]:
    x, y = [], []
    for path, positive, _category in evaluation.read_crops(crops_csv):
        value = cv2.extractChannel(features.bgr_to_hsv(dataset.read_image(path)), 2)
        small = cv2.resize(value, (features.HOG_WINDOW, features.HOG_WINDOW), interpolation=cv2.INTER_AREA)
        x.append(features.top_layer_hog(small))
        y.append(positive)
    return np.array(x, np.float32), np.array(y, bool)


def scores_per_window_us(predict: Callable[[np.ndarray], Any], x: np.ndarray, repeats: int = 3) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        for row in x[:200]:
            predict(row[None, :])
        best = min(best, (time.perf_counter() - start) / min(200, len(x)))
    return best * 1e6


def cv_svm(kind: int, x: np.ndarray, y: np.ndarray, gamma: float, c: float = 1.0, nu: float = 0.1) -> Any:
    model = cv2.ml.SVM_create()
    model.setKernel(cv2.ml.SVM_RBF)
    model.setGamma(gamma)
    if kind == "one_class":
        model.setType(cv2.ml.SVM_ONE_CLASS)
        model.setNu(nu)
        model.train(x[y > 0], cv2.ml.ROW_SAMPLE, np.ones(int((y > 0).sum()), np.int32))
    else:
        model.setType(cv2.ml.SVM_C_SVC)
        model.setC(c)
        model.train(x, cv2.ml.ROW_SAMPLE, (y > 0).astype(np.int32))
    return model


def compare(train_csv: str, crops_csv: str, species: str = "oil_palm", seed: int = 11) -> dict:
    single_threaded()
    frames = dataset.load_frames([train_csv])
    rng = np.random.RandomState(seed)
    positives = training._positive_descriptors(frames, species, training.DEFAULT_MARGIN, rng)
    negatives = training._negative_descriptors(frames, species, training.DEFAULT_MARGIN, rng)
    x_train = np.vstack([positives, negatives]).astype(np.float32)
    y_train = np.concatenate([np.ones(len(positives)), -np.ones(len(negatives))])
    x_test, y_test = crop_descriptors(crops_csv)
    results = {}
    # Two-class linear (without the detector's hard-negative rounds, for a like-for-like comparison)
    start = time.perf_counter()
    w, b = train_linear_svm(x_train, y_train, seed=seed)
    fit = time.perf_counter() - start
    predicted = x_test.dot(w) + b > 0
    results["linear two-class"] = dict(evaluation.crop_metrics(y_test, predicted), train_s=round(fit, 1),
                                       us_per_window=round(scores_per_window_us(lambda r: r.dot(w) + b, x_test), 2),
                                       support_vectors=1)
    for kind, label in (("one_class", "RBF one-class"), ("c_svc", "RBF two-class")):
        best = None
        for gamma in (0.5, 1.0, 2.0, 4.0):
            start = time.perf_counter()
            model = cv_svm(kind, x_train, y_train, gamma)
            fit = time.perf_counter() - start
            raw = model.predict(x_test)[1].ravel()
            predicted = raw > 0.5 if kind == "c_svc" else raw > 0.5
            metrics = evaluation.crop_metrics(y_test, predicted)
            if best is None or metrics["accuracy"] > best["accuracy"]:
                best = dict(metrics, gamma=gamma, train_s=round(fit, 1),
                            support_vectors=int(model.getSupportVectors().shape[0]),
                            us_per_window=round(scores_per_window_us(lambda r: model.predict(r), x_test), 2))
        results[label] = best
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("train_csv")
    parser.add_argument("crops_csv")
    parser.add_argument("--species", default="oil_palm")
    args = parser.parse_args()
    print(json.dumps(compare(args.train_csv, args.crops_csv, args.species), indent=1))


if __name__ == "__main__":
    main()
