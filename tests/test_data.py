"""Dataset loaders: parsers on files written here, the checksummed cache, offline errors."""

import gzip
import io
import pickle
import tarfile
import urllib.error
from pathlib import Path

import numpy as np
import pytest

from sgb import data


def _idx_bytes(array: np.ndarray) -> bytes:
    header = bytes([0, 0, 0x08, array.ndim]) + b"".join(
        int(n).to_bytes(4, "big") for n in array.shape
    )
    return header + array.astype(np.uint8).tobytes()


def _write_mnist(directory: Path, rng: np.random.Generator, monkeypatch) -> dict:
    arrays = {
        "train_images": rng.integers(0, 256, (12, 28, 28)),
        "train_labels": rng.integers(0, 10, 12),
        "test_images": rng.integers(0, 256, (5, 28, 28)),
        "test_labels": rng.integers(0, 10, 5),
    }
    files = {}
    for split, array in arrays.items():
        path = directory / data.MNIST_FILES[split].name
        path.write_bytes(gzip.compress(_idx_bytes(array)))
        files[split] = data.MNIST_FILES[split]._replace(md5=data.md5sum(path))
    monkeypatch.setattr(data, "MNIST_FILES", files)
    return arrays


def _cifar_tar(path: Path, rng: np.random.Generator) -> dict:
    batches = {}
    with tarfile.open(path, "w:gz") as tar:
        for name in [f"data_batch_{i}" for i in range(1, 6)] + ["test_batch"]:
            images = rng.integers(0, 256, (3, 3072), dtype=np.uint8)
            labels = rng.integers(0, 10, 3).tolist()
            batches[name] = (images, labels)
            raw = pickle.dumps({b"data": images, b"labels": labels})
            info = tarfile.TarInfo(f"cifar-10-batches-py/{name}")
            info.size = len(raw)
            tar.addfile(info, io.BytesIO(raw))
    return batches


def test_parse_idx_roundtrip_and_rejects_bad_headers():
    array = np.arange(24, dtype=np.uint8).reshape(2, 3, 4)
    np.testing.assert_array_equal(data.parse_idx(_idx_bytes(array)), array)
    with pytest.raises(ValueError, match="magic"):
        data.parse_idx(b"\x00\x00\x0d\x01" + bytes(8))
    with pytest.raises(ValueError, match="shape"):
        data.parse_idx(_idx_bytes(array)[:-3])


def test_mnist_loads_written_idx_files(tmp_path, monkeypatch):
    arrays = _write_mnist(tmp_path, np.random.default_rng(0), monkeypatch)
    ds = data.mnist(directory=tmp_path)
    assert ds.x_train.shape == (12, 784) and ds.x_test.shape == (5, 784)
    assert data.shape_of("mnist") == (ds.x_train.shape[1:], ds.num_classes)
    assert ds.x_train.dtype == np.float32 and ds.y_train.dtype == np.int32
    np.testing.assert_array_equal(ds.y_test, arrays["test_labels"])
    # global standardisation by the training set keeps the pixel order
    raw = arrays["train_images"].reshape(12, -1).astype(np.float64)
    np.testing.assert_allclose(ds.x_train, (raw - raw.mean()) / (raw.std() + 1e-6), atol=1e-4)


def _write_fashion(directory: Path, rng: np.random.Generator, monkeypatch) -> dict:
    """Small Fashion-MNIST-format files in ``directory``; the expected MD5s become theirs."""
    directory.mkdir(parents=True, exist_ok=True)
    arrays = {
        "train_images": rng.integers(0, 256, (12, 28, 28)),
        "train_labels": rng.integers(0, 10, 12),
        "test_images": rng.integers(0, 256, (5, 28, 28)),
        "test_labels": rng.integers(0, 10, 5),
    }
    files = {}
    for split, array in arrays.items():
        remote, _ = data.FASHION_MNIST_FILES[split]
        raw = _idx_bytes(array)
        (directory / remote.name).write_bytes(gzip.compress(raw, compresslevel=1))
        files[split] = (remote._replace(md5="0" * 32), data.hashlib.md5(raw).hexdigest())
    monkeypatch.setattr(data, "FASHION_MNIST_FILES", files)
    return arrays


def test_fashion_mnist_reads_the_system_copy_by_its_decompressed_md5(tmp_path, monkeypatch):
    system = tmp_path / "system"
    arrays = _write_fashion(system, np.random.default_rng(2), monkeypatch)
    monkeypatch.setattr(data, "FASHION_MNIST_SYSTEM_DIR", system)
    monkeypatch.setattr(data, "download_url", lambda url, path: pytest.fail("downloaded"))
    ds = data.fashion_mnist(directory=tmp_path / "cache")
    assert ds.name == "fashion-mnist" and ds.x_train.shape == (12, 784)
    np.testing.assert_array_equal(ds.y_train, arrays["train_labels"])
    np.testing.assert_allclose(ds.x_train.mean(), 0.0, atol=1e-5)


def test_fashion_mnist_skips_a_corrupt_copy_and_downloads_when_none_is_good(tmp_path, monkeypatch):
    system, cache = tmp_path / "system", tmp_path / "cache"
    arrays = _write_fashion(system, np.random.default_rng(3), monkeypatch)
    good = {
        remote.name: (system / remote.name).read_bytes()
        for remote, _ in data.FASHION_MNIST_FILES.values()
    }
    name = data.FASHION_MNIST_FILES["test_labels"][0].name
    (system / name).write_bytes(gzip.compress(b"\x00\x00\x08\x01" + bytes(4)))  # wrong
    files = {
        split: (remote._replace(md5=data.hashlib.md5(good[remote.name]).hexdigest()), raw)
        for split, (remote, raw) in data.FASHION_MNIST_FILES.items()
    }
    monkeypatch.setattr(data, "FASHION_MNIST_FILES", files)
    monkeypatch.setattr(data, "FASHION_MNIST_SYSTEM_DIR", system)
    downloads = []

    def fake_download(url, path):
        downloads.append(url)
        Path(path).write_bytes(good[Path(path).name])

    monkeypatch.setattr(data, "download_url", fake_download)
    ds = data.fashion_mnist(directory=cache)
    np.testing.assert_array_equal(ds.y_test, arrays["test_labels"])
    assert downloads == [data.FASHION_MNIST_FILES["test_labels"][0].urls[0]]
    data.fashion_mnist(directory=cache)  # the cached copy now passes: no second download
    assert len(downloads) == 1


def test_cifar10_parses_written_tarball(tmp_path, monkeypatch):
    path = tmp_path / data.CIFAR10_FILE.name
    batches = _cifar_tar(path, np.random.default_rng(1))
    monkeypatch.setattr(data, "CIFAR10_FILE", data.CIFAR10_FILE._replace(md5=data.md5sum(path)))
    x_tr, y_tr, x_te, y_te = data.parse_cifar10_tar(path)
    assert x_tr.shape == (15, 32, 32, 3) and x_te.shape == (3, 32, 32, 3)
    images, labels = batches["test_batch"]
    # CIFAR rows are channel-major: red plane, green plane, blue plane
    np.testing.assert_array_equal(x_te[1, :, :, 2], images[1, 2048:].reshape(32, 32))
    np.testing.assert_array_equal(y_te, labels)
    assert y_tr.tolist() == sum((batches[f"data_batch_{i}"][1] for i in range(1, 6)), [])
    ds = data.cifar10(directory=tmp_path)
    assert ds.x_train.shape == (15, 32, 32, 3) and ds.num_classes == 10
    assert data.shape_of("cifar10") == (ds.x_train.shape[1:], ds.num_classes)
    np.testing.assert_allclose(ds.x_train.mean(axis=(0, 1, 2)), 0.0, atol=1e-4)


def test_corrupt_cache_is_downloaded_again(tmp_path, monkeypatch):
    good = b"the real file"
    remote = data.RemoteFile(
        "f.bin", ("https://a.example/f.bin",), data.hashlib.md5(good).hexdigest()
    )
    (tmp_path / "f.bin").write_bytes(good[:5])  # a partial download
    calls = []

    def fake_download(url, path):
        calls.append(url)
        Path(path).write_bytes(good)

    monkeypatch.setattr(data, "download_url", fake_download)
    assert data.fetch(remote, tmp_path).read_bytes() == good
    assert calls == ["https://a.example/f.bin"]
    data.fetch(remote, tmp_path)  # now valid: no second download
    assert len(calls) == 1


def test_wrong_checksum_from_every_mirror_is_an_error_and_leaves_no_file(tmp_path, monkeypatch):
    remote = data.RemoteFile("f.bin", ("https://a/f", "https://b/f"), "0" * 32)
    monkeypatch.setattr(data, "download_url", lambda url, path: Path(path).write_bytes(b"x"))
    with pytest.raises(RuntimeError, match="checksum mismatch"):
        data.fetch(remote, tmp_path)
    assert not (tmp_path / "f.bin").exists()


def test_offline_error_names_the_offline_datasets(tmp_path, monkeypatch):
    def no_internet(url, path):
        raise urllib.error.URLError("no route to host")

    monkeypatch.setattr(data, "download_url", no_internet)
    monkeypatch.setenv("SGB_DATA_DIR", str(tmp_path / "cache"))
    with pytest.raises(RuntimeError) as error:
        data.load("mnist")
    assert "digits" in str(error.value) and "mnist1d" in str(error.value)
    assert (tmp_path / "cache").is_dir()  # SGB_DATA_DIR chose the cache


def test_load_rejects_unknown_names():
    with pytest.raises(ValueError, match="cifar10"):
        data.load("imagenet")


def test_offline_datasets_shapes():
    ds = data.load("digits")
    assert ds.x_train.shape[1] == 64 and len(ds.x_train) + len(ds.x_test) == 1797
    np.testing.assert_allclose(ds.x_train.mean(axis=0), 0.0, atol=1e-5)
    # the table that lists cells without the data gives each loader's shapes
    for name in data.OFFLINE_DATASETS:
        ds = data.load(name)
        assert data.shape_of(name) == (ds.x_train.shape[1:], ds.num_classes)
    assert set(data.SHAPES) == set(data.DATASETS)
    with pytest.raises(ValueError, match="available"):
        data.shape_of("imagenet")


def test_features_constant_on_the_training_set_stay_bounded():
    # Digits' corner pixels are zero in (almost) every training image; a test image that
    # inks one must not become an input of size 1e6.
    x_train = np.array([[0.0, 1.0], [0.0, 3.0]])
    x_test = np.array([[16.0, 2.0]])
    train, test = data._standardise(x_train, x_test)
    np.testing.assert_allclose(train, [[0.0, -1.0], [0.0, 1.0]])
    np.testing.assert_allclose(test, [[16.0, 0.0]])
    ds = data.load("digits")
    assert np.abs(ds.x_test).max() < 100.0


@pytest.mark.skipif(
    not data.FASHION_MNIST_SYSTEM_DIR.is_dir(), reason="Debian's dataset-fashion-mnist absent"
)
def test_installed_fashion_mnist_passes_its_checks():
    ds = data.load("fashion-mnist")
    assert ds.x_train.shape == (60_000, 784) and ds.x_test.shape == (10_000, 784)
    assert data.shape_of("fashion-mnist") == (ds.x_train.shape[1:], ds.num_classes)
    np.testing.assert_array_equal(ds.y_train[:10], [9, 0, 0, 3, 0, 2, 7, 2, 5, 5])


def test_of_classes_keeps_exactly_the_examples_of_the_classes_asked():
    digits = data.load("digits")
    low = data.of_classes(digits, (0, 1, 2, 3, 4))
    high = data.of_classes(digits, range(5, 10))
    for split in ("train", "test"):
        y = getattr(digits, f"y_{split}")
        kept, rest = getattr(low, f"y_{split}"), getattr(high, f"y_{split}")
        assert set(kept) == {0, 1, 2, 3, 4} and set(rest) == {5, 6, 7, 8, 9}
        assert len(kept) + len(rest) == len(y) == len(getattr(digits, f"x_{split}"))
    np.testing.assert_array_equal(low.x_train, digits.x_train[digits.y_train < 5])
    assert low.num_classes == 10
    with pytest.raises(ValueError, match="classes must lie in"):
        data.of_classes(digits, (3, 10))
