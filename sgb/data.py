"""Datasets as arrays. Offline: ``digits`` (scikit-learn) and ``mnist1d`` (generated in code)."""

from typing import NamedTuple

import numpy as np


class Dataset(NamedTuple):
    """Train and test arrays; ``x`` float32 (n, features), ``y`` int32 (n,)."""

    name: str
    x_train: np.ndarray
    y_train: np.ndarray
    x_test: np.ndarray
    y_test: np.ndarray
    num_classes: int


def _standardise(x_train: np.ndarray, x_test: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    mean, std = x_train.mean(axis=0), x_train.std(axis=0) + 1e-6
    return ((x_train - mean) / std).astype(np.float32), ((x_test - mean) / std).astype(np.float32)


def digits(seed: int = 0, test_fraction: float = 0.25) -> Dataset:
    """scikit-learn's 8x8 handwritten digits (1797 images, 64 features, 10 classes)."""
    from sklearn.datasets import load_digits
    from sklearn.model_selection import train_test_split

    if not 0.0 < test_fraction < 1.0:
        raise ValueError(f"test_fraction must lie in (0, 1), got {test_fraction}")
    x, y = load_digits(return_X_y=True)
    x_tr, x_te, y_tr, y_te = train_test_split(
        x, y, test_size=test_fraction, random_state=seed, stratify=y
    )
    x_tr, x_te = _standardise(x_tr, x_te)
    return Dataset("digits", x_tr, y_tr.astype(np.int32), x_te, y_te.astype(np.int32), 10)


def mnist1d(seed: int = 0, num_samples: int = 5000) -> Dataset:
    """MNIST-1D (Greydanus, 2020): 40-sample 1-D signals of 10 digit templates, made in code."""
    from mnist1d.data import get_dataset_args, make_dataset

    args = get_dataset_args()
    args.num_samples = num_samples
    args.seed = seed
    data = make_dataset(args)
    x_tr, x_te = _standardise(np.asarray(data["x"]), np.asarray(data["x_test"]))
    return Dataset(
        "mnist1d",
        x_tr,
        np.asarray(data["y"], np.int32),
        x_te,
        np.asarray(data["y_test"], np.int32),
        10,
    )


OFFLINE_DATASETS = {"digits": digits, "mnist1d": mnist1d}


def load(name: str, seed: int = 0) -> Dataset:
    """Load a dataset by name."""
    if name not in OFFLINE_DATASETS:
        raise ValueError(f"unknown dataset {name!r}; available: {sorted(OFFLINE_DATASETS)}")
    return OFFLINE_DATASETS[name](seed=seed)
