"""Chapter 5's walking animation: each tile's label sits above that tile, and the frames
themselves come through untouched."""

import numpy as np
import pytest

from sgb.plots.rl import label_tiles, stack_rows


def frames(n_tiles=3, t=4, size=20, seed=0):
    rng = np.random.default_rng(seed)
    return rng.integers(0, 255, size=(t, size, n_tiles * size, 3), dtype=np.uint8)


def ink(band: np.ndarray) -> np.ndarray:
    """Columns of a white band that hold dark (text) pixels."""
    return np.flatnonzero((band.min(axis=2) < 128).any(axis=0))


def test_labels_sit_above_their_tiles_and_leave_the_frames_alone():
    clip = frames(n_tiles=3, size=60)
    out = label_tiles(clip, ["return 1", "return 22", "return 333"], font_size=12)
    band = out.shape[1] - clip.shape[1]
    assert band > 0 and out.shape[0] == clip.shape[0] and out.shape[2:] == clip.shape[2:]
    np.testing.assert_array_equal(out[:, band:], clip)
    # the band is the same in every frame, and each tile's label is within that tile
    np.testing.assert_array_equal(
        out[:, :band], np.broadcast_to(out[0, :band], out[:, :band].shape)
    )
    columns = ink(out[0, :band])
    tiles = set(columns // 60)
    assert tiles == {0, 1, 2}
    widths = [np.ptp(columns[columns // 60 == k]) for k in range(3)]
    assert widths[0] < widths[1] < widths[2]  # longer labels are wider
    for k in range(3):  # centred in the tile
        cols = columns[columns // 60 == k]
        assert abs((cols.min() + cols.max()) / 2 - (60 * k + 30)) <= 3


def test_a_title_adds_a_band_across_the_row():
    clip = frames(n_tiles=2, size=80)
    plain = label_tiles(clip, ["a", "b"])
    titled = label_tiles(clip, ["a", "b"], title="wide genome")
    extra = titled.shape[1] - plain.shape[1]
    assert extra > 0
    np.testing.assert_array_equal(titled[:, extra:], plain)
    columns = ink(titled[0, :extra])
    assert columns.min() < 80 < columns.max()  # one title, across both tiles


def test_labels_must_split_the_row_into_equal_tiles():
    with pytest.raises(ValueError, match="2 labels"):
        label_tiles(frames(n_tiles=3, size=21), ["a", "b"])
    with pytest.raises(ValueError, match="frames must be"):
        label_tiles(np.zeros((4, 5, 6)), ["a"])


def test_rows_are_stacked_with_a_white_gap_and_cut_to_the_shortest():
    top = label_tiles(frames(t=5, seed=1), ["a", "b", "c"])
    bottom = label_tiles(frames(t=4, seed=2), ["d", "e", "f"])
    clip = stack_rows([top, bottom], gap=6)
    assert clip.shape == (4, top.shape[1] + 6 + bottom.shape[1], top.shape[2], 3)
    np.testing.assert_array_equal(clip[:, : top.shape[1]], top[:4])
    assert (clip[:, top.shape[1] : top.shape[1] + 6] == 255).all()
    np.testing.assert_array_equal(clip[:, top.shape[1] + 6 :], bottom)
    with pytest.raises(ValueError, match="equally wide"):
        stack_rows([top, label_tiles(frames(n_tiles=2), ["a", "b"])])
