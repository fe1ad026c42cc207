import numpy as np
import pytest

from rld.geometry import polyline_length
from rld.tracks import DATASET_TRACKS, Track, load_dataset_track, load_map, read_csv, write_csv

# The dataset README's table: cones, left, right, cones in no boundary, left and right length (m).
README = {
    1: (136, 66, 70, 0, 202, 228),
    2: (159, 81, 78, 0, 273, 243),
    3: (142, 59, 62, 21, 151, 175),
    4: (169, 81, 88, 0, 253, 279),
    6: (286, 75, 74, 137, 229, 250),
    7: (173, 80, 79, 14, 233, 213),
}


@pytest.mark.parametrize("number", DATASET_TRACKS)
def test_loader_reads_readme_counts(dataset_dir, number):
    track = load_dataset_track(dataset_dir, number)
    cones, nl, nr, free, len_l, len_r = README[number]
    assert track.cones.shape == (cones, 2)
    assert track.left.size == nl and track.right.size == nr
    assert track.unlabelled.size == free
    assert track.closed
    # The README's lengths are of the open lists (without the closing gap).
    assert polyline_length(track.left_xy) == pytest.approx(len_l, abs=1.0)
    assert polyline_length(track.right_xy) == pytest.approx(len_r, abs=1.0)
    assert track.boundary_length("left") > polyline_length(track.left_xy)
    # Consecutive boundary cones are 1.2-5.2 m apart (README), around the loop.
    for xy in (track.left_xy, track.right_xy):
        gaps = np.hypot(*np.diff(np.vstack([xy, xy[:1]]), axis=0).T)
        assert 1.0 < gaps.min() and gaps.max() < 5.3


def test_loader_maps_ids_to_positions(dataset_dir):
    import yaml

    track = load_dataset_track(dataset_dir, 1)
    raw = yaml.safe_load(open(dataset_dir / "cone_map_1.yaml"))
    bounds = yaml.safe_load(open(dataset_dir / "boundaries_1.yaml"))
    assert track.left_ids.tolist() == bounds["left"]
    assert track.right_ids.tolist() == bounds["right"]
    first = bounds["left"][0]
    np.testing.assert_allclose(track.cones[track.left[0]], raw[first])


def _toy_track(closed=True):
    cones = np.array([[0, 2], [3, 2], [6, 2], [0, -2], [3, -2], [6, -2], [9, 9]], float)
    return Track(cones, [10, 11, 12, 20, 21, 22, 99], [0, 1, 2], [3, 4, 5], closed=closed)


@pytest.mark.parametrize("closed", [True, False])
def test_csv_round_trip(tmp_path, closed):
    track = _toy_track(closed)
    path = tmp_path / "t.csv"
    write_csv(track, path)
    back = read_csv(path)
    np.testing.assert_array_equal(back.cones, track.cones)
    assert back.ids.tolist() == track.ids.tolist()
    assert back.left_ids.tolist() == [10, 11, 12]
    assert back.right_ids.tolist() == [20, 21, 22]
    assert back.closed == closed
    assert load_map(path).left.tolist() == track.left.tolist()


def test_csv_round_trip_of_a_dataset_track(tmp_path, dataset_dir):
    track = load_dataset_track(dataset_dir, 3)
    write_csv(track, tmp_path / "3.csv")
    back = read_csv(tmp_path / "3.csv")
    np.testing.assert_array_equal(back.cones, track.cones)
    assert back.left_ids.tolist() == track.left_ids.tolist()
    assert back.right_ids.tolist() == track.right_ids.tolist()


def test_bare_xy_csv(tmp_path):
    path = tmp_path / "bare.csv"
    path.write_text("x,y\n0,1\n2,3\n4,5\n")
    track = read_csv(path)
    assert track.cones.tolist() == [[0, 1], [2, 3], [4, 5]]
    assert track.left.size == 0 and track.right.size == 0


def test_bad_files_raise_value_error(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y\n0,abc\n")
    with pytest.raises(ValueError, match="bad x,y"):
        read_csv(bad)
    other = tmp_path / "m.txt"
    other.write_text("")
    with pytest.raises(ValueError, match="unknown map format"):
        load_map(other)


def test_track_rejects_inconsistent_boundaries():
    cones = np.zeros((4, 2))
    with pytest.raises(ValueError, match="disjoint"):
        Track(cones, [0, 1, 2, 3], [0, 1], [1, 2])
    with pytest.raises(ValueError, match="unique"):
        Track(cones, [0, 0, 2, 3], [0], [1])
    with pytest.raises(ValueError, match="out of range"):
        Track(cones, [0, 1, 2, 3], [0, 7], [1])
