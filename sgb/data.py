"""Datasets as arrays.

Offline: ``digits`` (scikit-learn) and ``mnist1d`` (generated in code).
``fashion-mnist``: read from Debian's ``dataset-fashion-mnist`` package
(``/usr/share/datasets/fashion-mnist``) or the cache, else downloaded; its files are
checked by the MD5 of their decompressed bytes (Debian re-compressed them).
Downloaded once and cached: ``mnist`` and ``cifar10``. Files are stored under
``$SGB_DATA_DIR`` (default ``~/.cache/sgb``) and checked against their MD5
checksums every time they are used; a missing, partial or corrupt file is
downloaded again, never used. A Fashion-MNIST copy that does not decompress, or whose
contents fail their check, is passed over for the next one. What cannot be read at all
(a directory where a file should be) is a ``sgb.validation.CorruptFile`` naming it.
"""

import gzip
import hashlib
import os
import pickle
import tarfile
import urllib.error
import urllib.request
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np

from sgb import validation
from sgb.validation import REDOWNLOAD, CorruptFile


class Dataset(NamedTuple):
    """Train and test arrays; ``x`` float32, (n, features) or images (n, height, width,
    channels); ``y`` int32 (n,)."""

    name: str
    x_train: np.ndarray
    y_train: np.ndarray
    x_test: np.ndarray
    y_test: np.ndarray
    num_classes: int


def of_classes(data: Dataset, classes) -> Dataset:
    """The examples of ``data``, train and test, whose label is one of ``classes``; the
    labels and ``num_classes`` unchanged."""
    keep = np.asarray(validation.integers("classes", tuple(classes), minimum=0))
    if keep.max() >= data.num_classes:
        raise ValueError(f"classes must lie in [0, {data.num_classes}), got {tuple(classes)}")
    train, test = np.isin(data.y_train, keep), np.isin(data.y_test, keep)
    return data._replace(
        x_train=data.x_train[train],
        y_train=data.y_train[train],
        x_test=data.x_test[test],
        y_test=data.y_test[test],
    )


def check_dataset(data: Dataset) -> Dataset:
    """``data`` if it can be trained and evaluated on: non-empty, finite ``x_train`` and
    ``x_test`` of one shape per example, as many int labels in [0, num_classes) as
    examples; else a ``ValueError`` (or ``TypeError``) naming the array."""
    validation.instance("data", data, Dataset)
    classes = validation.integer("num_classes", data.num_classes)
    for split in ("train", "test"):
        x = validation.finite_array(f"x_{split}", getattr(data, f"x_{split}"), min_ndim=2)
        y = validation.labels(f"y_{split}", getattr(data, f"y_{split}"), classes)
        if y.shape != (len(x),):
            raise ValueError(
                f"y_{split} must hold one label per example of x_{split} ({len(x)}), got "
                f"shape {tuple(y.shape)}"
            )
    if data.x_train.shape[1:] != data.x_test.shape[1:]:
        raise ValueError(
            f"x_train and x_test must have examples of one shape, got "
            f"{data.x_train.shape[1:]} and {data.x_test.shape[1:]}"
        )
    return data


class RemoteFile(NamedTuple):
    """A file to download: its name in the cache, mirror URLs tried in order, its MD5."""

    name: str
    urls: tuple[str, ...]
    md5: str


# MD5 sums as published with the files (and listed by torchvision's MNIST and CIFAR10 classes).
_MNIST_MIRRORS = (
    "https://ossci-datasets.s3.amazonaws.com/mnist/",
    "http://yann.lecun.com/exdb/mnist/",
)
MNIST_FILES = {
    split: RemoteFile(name, tuple(m + name for m in _MNIST_MIRRORS), md5)
    for split, name, md5 in (
        ("train_images", "train-images-idx3-ubyte.gz", "f68b3c2dcbeaaa9fbdd348bbdeb94873"),
        ("train_labels", "train-labels-idx1-ubyte.gz", "d53e105ee54ea40749a09fcbcd1e9432"),
        ("test_images", "t10k-images-idx3-ubyte.gz", "9fb629c4189551a2d022fa330f9573f3"),
        ("test_labels", "t10k-labels-idx1-ubyte.gz", "ec29112dd5afa0611ce80d1b7f02629c"),
    )
}
# Fashion-MNIST (Xiao, Rasul and Vollgraf, 2017): the official archive's .gz MD5s, and the
# MD5s of the decompressed IDX bytes, which any copy (official or Debian's) must match.
_FASHION_URL = "http://fashion-mnist.s3-website.eu-central-1.amazonaws.com/"
FASHION_MNIST_SYSTEM_DIR = Path("/usr/share/datasets/fashion-mnist")
FASHION_MNIST_FILES = {
    split: (RemoteFile(name, (_FASHION_URL + name,), gz_md5), raw_md5)
    for split, name, gz_md5, raw_md5 in (
        (
            "train_images",
            "train-images-idx3-ubyte.gz",
            "8d4fb7e6c68d591d4c3dfef9ec88bf0d",
            "f4a8712d7a061bf5bd6d2ca38dc4d50a",
        ),
        (
            "train_labels",
            "train-labels-idx1-ubyte.gz",
            "25c81989df183df01b3e8a0aad5dffbe",
            "9018921c3c673c538a1fc5bad174d6f9",
        ),
        (
            "test_images",
            "t10k-images-idx3-ubyte.gz",
            "bef4ecab320f06d8554ea6380940ec79",
            "8181f5470baa50b63fa0f6fddb340f0a",
        ),
        (
            "test_labels",
            "t10k-labels-idx1-ubyte.gz",
            "bb300cfdad3c16e7a12a480ee83cd310",
            "15d484375f8d13e6eb1aabb0c3f46965",
        ),
    )
}
CIFAR10_FILE = RemoteFile(
    "cifar-10-python.tar.gz",
    ("https://www.cs.toronto.edu/~kriz/cifar-10-python.tar.gz",),
    "c58f30108f718f92721af3b95e74349a",
)
OFFLINE_NAMES = ("digits", "mnist1d")


def data_dir() -> Path:
    """The cache directory: ``$SGB_DATA_DIR`` or ``~/.cache/sgb``."""
    return Path(os.environ.get("SGB_DATA_DIR", Path.home() / ".cache" / "sgb")).expanduser()


def md5sum(path: Path) -> str:
    """Hex MD5 digest of a file."""
    digest = hashlib.md5()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def download_url(url: str, path: Path) -> None:
    """Download ``url`` to ``path`` (via a temporary file, so a broken transfer leaves none)."""
    partial = path.with_name(path.name + ".part")
    with urllib.request.urlopen(url, timeout=60) as response, open(partial, "wb") as f:
        while chunk := response.read(1 << 20):
            f.write(chunk)
    partial.replace(path)


def fetch(remote: RemoteFile, directory: Path | None = None) -> Path:
    """Path of a verified local copy of ``remote``, downloading it if missing or corrupt.

    Raises ``RuntimeError`` if no mirror gives a file with the right checksum;
    the message names the offline datasets.
    """
    directory = data_dir() if directory is None else Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / remote.name
    if path.is_dir():
        raise CorruptFile(path, "is a directory, where a downloaded file belongs", REDOWNLOAD)
    if path.exists() and md5sum(path) == remote.md5:
        return path
    errors = []
    for url in remote.urls:
        try:
            download_url(url, path)
        except (urllib.error.URLError, OSError, TimeoutError) as error:
            errors.append(f"{url}: {error}")
            continue
        if md5sum(path) == remote.md5:
            return path
        errors.append(f"{url}: checksum mismatch")
        path.unlink()
    raise RuntimeError(
        f"could not download {remote.name} into {directory} ({'; '.join(errors)}). "
        f"Without internet use an offline dataset: {', '.join(OFFLINE_NAMES)}; "
        "or place the file there yourself (set SGB_DATA_DIR to choose the directory)."
    )


def parse_idx(raw: bytes) -> np.ndarray:
    """Parse an IDX file (the MNIST format: big-endian header, unsigned bytes) to an array."""
    if len(raw) < 4 or raw[0] != 0 or raw[1] != 0 or raw[2] != 0x08:
        raise ValueError("not an IDX file of unsigned bytes (magic number mismatch)")
    ndim = raw[3]
    shape = tuple(int.from_bytes(raw[4 + 4 * i : 8 + 4 * i], "big") for i in range(ndim))
    data = np.frombuffer(raw, dtype=np.uint8, offset=4 + 4 * ndim)
    if data.size != int(np.prod(shape)):
        raise ValueError(f"IDX header says shape {shape} but the file holds {data.size} values")
    return data.reshape(shape)


def _gunzip(path: Path) -> bytes:
    """The decompressed bytes of the gzip file ``path``; a ``CorruptFile`` naming it if it is
    not one, is cut short or cannot be read."""
    try:
        with gzip.open(path, "rb") as f:
            return f.read()
    except (OSError, EOFError, zlib.error) as error:
        raise CorruptFile(path, f"does not decompress ({error!r})", REDOWNLOAD) from error


def _read_idx_gz(path: Path) -> np.ndarray:
    raw = _gunzip(path)
    try:
        return parse_idx(raw)
    except ValueError as error:
        raise CorruptFile(path, f"is not an IDX file: {error}", REDOWNLOAD) from error


def _verified_idx(remote: RemoteFile, raw_md5: str, directories: list[Path]) -> np.ndarray:
    """The IDX array of the first copy of ``remote`` in ``directories`` whose decompressed
    bytes have MD5 ``raw_md5`` (a copy that does not decompress is passed over); failing
    all, a download into the cache (``fetch``, which replaces a corrupt cached copy)."""
    for directory in directories:
        path = directory / remote.name
        if path.is_file():
            try:
                raw = _gunzip(path)
            except CorruptFile:
                continue
            if hashlib.md5(raw).hexdigest() == raw_md5:
                return parse_idx(raw)
    path = fetch(remote, directories[-1])
    raw = _gunzip(path)
    if hashlib.md5(raw).hexdigest() != raw_md5:
        raise CorruptFile(path, "decompresses to contents that fail their MD5 check", REDOWNLOAD)
    return parse_idx(raw)


def parse_cifar10_tar(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(x_train, y_train, x_test, y_test) from CIFAR-10's python tarball; x uint8 NHWC."""

    def batches(tar: tarfile.TarFile, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
        xs, ys = [], []
        for name in names:
            member = tar.extractfile(f"cifar-10-batches-py/{name}")
            if member is None:
                raise ValueError(f"{path} has no batch {name}")
            batch = pickle.load(member, encoding="bytes")
            xs.append(np.asarray(batch[b"data"], np.uint8).reshape(-1, 3, 32, 32))
            ys.append(np.asarray(batch[b"labels"], np.int32))
        return np.concatenate(xs).transpose(0, 2, 3, 1), np.concatenate(ys)

    try:
        with tarfile.open(path, "r:gz") as tar:
            x_tr, y_tr = batches(tar, [f"data_batch_{i}" for i in range(1, 6)])
            x_te, y_te = batches(tar, ["test_batch"])
    except (OSError, EOFError, zlib.error, tarfile.TarError, pickle.UnpicklingError) as error:
        raise CorruptFile(
            path, f"is not CIFAR-10's python tarball ({error!r})", REDOWNLOAD
        ) from error
    except (ValueError, KeyError, TypeError) as error:
        raise CorruptFile(path, f"holds a malformed batch ({error!r})", REDOWNLOAD) from error
    return x_tr, y_tr, x_te, y_te


def _standardise(
    x_train: np.ndarray, x_test: np.ndarray, axis: int | tuple[int, ...] | None = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Shift and scale by the training set's mean and std along ``axis`` (None: global).

    A feature that is constant on the training set is only shifted (scale 1): dividing by
    its zero std would turn any test value off that constant into an enormous input.
    """
    mean = x_train.mean(axis=axis)
    std = x_train.std(axis=axis)
    std = np.where(std > 0.0, std, 1.0)
    return ((x_train - mean) / std).astype(np.float32), ((x_test - mean) / std).astype(np.float32)


def mnist(seed: int = 0, directory: Path | None = None) -> Dataset:
    """MNIST, 60k/10k 28x28 digits flattened to 784 features, standardised globally.

    ``seed`` is unused (the split is fixed); it keeps the loaders' signatures alike.
    """
    validation.seed("seed", seed)
    arrays = {split: _read_idx_gz(fetch(f, directory)) for split, f in MNIST_FILES.items()}
    return _idx_dataset("mnist", arrays)


def _idx_dataset(name: str, arrays: dict[str, np.ndarray]) -> Dataset:
    """28x28 IDX images flattened to 784 features and standardised globally; int32 labels."""
    x_tr = arrays["train_images"].reshape(len(arrays["train_images"]), -1).astype(np.float32)
    x_te = arrays["test_images"].reshape(len(arrays["test_images"]), -1).astype(np.float32)
    x_tr, x_te = _standardise(x_tr, x_te, axis=None)
    y_tr, y_te = arrays["train_labels"].astype(np.int32), arrays["test_labels"].astype(np.int32)
    return Dataset(name, x_tr, y_tr, x_te, y_te, 10)


def fashion_mnist(seed: int = 0, directory: Path | None = None) -> Dataset:
    """Fashion-MNIST, 60k/10k 28x28 clothing images flattened to 784 features, standardised
    globally. Looks in ``FASHION_MNIST_SYSTEM_DIR`` (Debian's package), then in ``directory``
    (default: the cache), then downloads; every copy is checked by its decompressed MD5.

    ``seed`` is unused (the split is fixed); it keeps the loaders' signatures alike.
    """
    validation.seed("seed", seed)
    directories = [FASHION_MNIST_SYSTEM_DIR, data_dir() if directory is None else Path(directory)]
    arrays = {
        split: _verified_idx(remote, raw_md5, directories)
        for split, (remote, raw_md5) in FASHION_MNIST_FILES.items()
    }
    return _idx_dataset("fashion-mnist", arrays)


def cifar10(seed: int = 0, directory: Path | None = None) -> Dataset:
    """CIFAR-10, 50k/10k 32x32 RGB images (n, 32, 32, 3), standardised per channel.

    ``seed`` is unused (the split is fixed); it keeps the loaders' signatures alike.
    """
    validation.seed("seed", seed)
    x_tr, y_tr, x_te, y_te = parse_cifar10_tar(fetch(CIFAR10_FILE, directory))
    x_tr, x_te = _standardise(x_tr.astype(np.float32), x_te.astype(np.float32), axis=(0, 1, 2))
    return Dataset("cifar10", x_tr, y_tr, x_te, y_te, 10)


def digits(seed: int = 0, test_fraction: float = 0.25) -> Dataset:
    """scikit-learn's 8x8 handwritten digits (1797 images, 64 features, 10 classes)."""
    from sklearn.datasets import load_digits
    from sklearn.model_selection import train_test_split

    validation.seed("seed", seed)
    if not 0.0 < validation.real("test_fraction", test_fraction) < 1.0:
        raise ValueError(f"test_fraction must lie in (0, 1), got {test_fraction}")
    x, y = load_digits(return_X_y=True)
    x_tr, x_te, y_tr, y_te = train_test_split(
        x, y, test_size=test_fraction, random_state=seed, stratify=y
    )
    x_tr, x_te = _standardise(x_tr, x_te)
    return Dataset("digits", x_tr, y_tr.astype(np.int32), x_te, y_te.astype(np.int32), 10)


MNIST1D_MIN_SAMPLES = 10  # it makes num_samples // 10 signals of each of 10 templates


def mnist1d(seed: int = 0, num_samples: int = 5000) -> Dataset:
    """MNIST-1D (Greydanus, 2020): 40-sample 1-D signals of 10 digit templates, made in code.

    ``num_samples`` (at least ``MNIST1D_MIN_SAMPLES``) are split 80/20 into train and test.
    """
    from mnist1d.data import get_dataset_args, make_dataset

    validation.seed("seed", seed)
    if validation.integer("num_samples", num_samples) < MNIST1D_MIN_SAMPLES:
        raise ValueError(
            f"num_samples must be >= {MNIST1D_MIN_SAMPLES} (one signal of each of the 10 "
            f"templates), got {num_samples}"
        )

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


OFFLINE_DATASETS: dict[str, Callable[..., Dataset]] = {"digits": digits, "mnist1d": mnist1d}
DATASETS: dict[str, Callable[..., Dataset]] = {
    **OFFLINE_DATASETS,
    "mnist": mnist,
    "fashion-mnist": fashion_mnist,
    "cifar10": cifar10,
}


# each dataset's example shape and class count, as its loader gives them (a test checks):
# what a listing of the cells to train needs, without the data
SHAPES: dict[str, tuple[tuple[int, ...], int]] = {
    "digits": ((64,), 10),
    "mnist1d": ((40,), 10),
    "mnist": ((784,), 10),
    "fashion-mnist": ((784,), 10),
    "cifar10": ((32, 32, 3), 10),
}


def shape_of(name: str) -> tuple[tuple[int, ...], int]:
    """(the shape of one example, the number of classes) of the dataset ``name``, without
    loading it."""
    if not isinstance(name, str) or name not in SHAPES:
        raise ValueError(f"unknown dataset name {name!r}; available: {sorted(DATASETS)}")
    return SHAPES[name]


def load(name: str, seed: int = 0) -> Dataset:
    """Load a dataset by name: digits, mnist1d (offline), fashion-mnist (Debian package or
    downloaded once), mnist, cifar10 (downloaded once)."""
    if not isinstance(name, str) or name not in DATASETS:
        raise ValueError(f"unknown dataset name {name!r}; available: {sorted(DATASETS)}")
    return DATASETS[name](seed=validation.seed("seed", seed))
