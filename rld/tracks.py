"""Tracks: cone maps with annotated boundaries, and their file formats.

- The FSD racetrack dataset format (Ivanov & Markgraf 2024, VIII-A): ``cone_map_K.yaml``
  (``id: [x, y]``) and ``boundaries_K.yaml`` (``left`` and ``right`` id lists, closed loops).
- Our CSV: one cone a row, ``id,x,y,side,order``; ``side`` is ``left``, ``right`` or empty and
  ``order`` the cone's position on its boundary. A first line ``# closed=1`` marks a closed
  track. A CSV with only ``x,y`` columns (no header names needed beyond them) is a bare map.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from rld import geometry as geo

__all__ = [
    "Track",
    "load_dataset_track",
    "read_csv",
    "write_csv",
    "load_map",
    "find_dataset_dir",
    "DATASET_TRACKS",
]

#: The dataset's place beside a checkout of this repository: ``../shared/data/...``.
_DATASET_REL = Path("shared") / "data" / "fsd_racetrack_dataset"
#: The track numbers of the shared subset.
DATASET_TRACKS = (1, 2, 3, 4, 6, 7)


def find_dataset_dir() -> Path | None:
    """The racetrack dataset folder: ``$RLD_DATASET_DIR`` when set, else ``../shared/data/
    fsd_racetrack_dataset`` beside the working directory or beside this checkout. ``None``
    when none exists (tests and notebooks then skip the dataset cases)."""
    import os

    candidates = []
    if os.environ.get("RLD_DATASET_DIR"):
        candidates.append(Path(os.environ["RLD_DATASET_DIR"]))
    candidates.append(Path.cwd().parent / _DATASET_REL)
    candidates.append(Path(__file__).resolve().parents[2] / _DATASET_REL)
    for c in candidates:
        if (c / "boundaries_1.yaml").exists() or any(c.glob("boundaries_*.yaml")):
            return c
    return None


@dataclass(frozen=True, eq=False)
class Track:
    """A cone map with its two boundaries.

    ``cones`` (N, 2) metres; ``ids`` (N,) int cone ids; ``left`` and ``right`` ordered index
    arrays into ``cones`` (the car drives in this order, ``left`` on its left); ``closed`` when
    each boundary's last cone connects back to its first. Cones in neither boundary are real but
    unlabelled (or the map's own false positives).
    """

    cones: np.ndarray
    ids: np.ndarray
    left: np.ndarray
    right: np.ndarray
    closed: bool = True
    name: str = ""
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "cones", np.ascontiguousarray(self.cones, dtype=np.float64))
        object.__setattr__(self, "ids", np.asarray(self.ids, dtype=np.int64))
        object.__setattr__(self, "left", np.asarray(self.left, dtype=np.int64))
        object.__setattr__(self, "right", np.asarray(self.right, dtype=np.int64))
        n = self.cones.shape[0]
        if self.cones.ndim != 2 or self.cones.shape[1] != 2:
            raise ValueError(f"Track cones must be (N, 2), got {self.cones.shape}")
        if self.ids.shape != (n,):
            raise ValueError("Track ids must have one id per cone")
        if np.unique(self.ids).size != n:
            raise ValueError("Track ids must be unique")
        for side in (self.left, self.right):
            if side.size and (side.min() < 0 or side.max() >= n):
                raise ValueError("Track boundary index out of range")
        if np.intersect1d(self.left, self.right).size or (
            np.unique(self.left).size != self.left.size
            or np.unique(self.right).size != self.right.size
        ):
            raise ValueError("Track boundaries must be disjoint simple sequences")

    @property
    def left_ids(self) -> np.ndarray:
        return self.ids[self.left]

    @property
    def right_ids(self) -> np.ndarray:
        return self.ids[self.right]

    @property
    def left_xy(self) -> np.ndarray:
        return self.cones[self.left]

    @property
    def right_xy(self) -> np.ndarray:
        return self.cones[self.right]

    @property
    def unlabelled(self) -> np.ndarray:
        """Indices of cones on neither boundary."""
        mask = np.ones(self.cones.shape[0], dtype=bool)
        mask[self.left] = False
        mask[self.right] = False
        return np.flatnonzero(mask)

    def boundary_length(self, side: str) -> float:
        """Length of one boundary (``"left"`` or ``"right"``), metres, around the loop if closed."""
        xy = self.left_xy if side == "left" else self.right_xy
        return geo.polyline_length(xy, closed=self.closed)

    def boundary_lines(self) -> tuple[np.ndarray, np.ndarray]:
        """Each boundary as a polyline through its cones ((k, 2) metres, left and right); a
        closed track's lines return to their first cone."""
        return (geo.boundary_line(self.left_xy, self.closed),
                geo.boundary_line(self.right_xy, self.closed))

    def boundary_distance(self, points: np.ndarray) -> np.ndarray:
        """(P,) distance in metres from each of ``points`` (P, 2) to the nearer boundary line
        (``boundary_lines``); inf when the track has no boundary cones."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        out = np.full(points.shape[0], np.inf)
        for line in self.boundary_lines():
            out = np.minimum(out, geo.point_polyline_distance(points, line))
        return out

    def centerline(self, resolution_m: float = 1.0) -> np.ndarray:
        """The track's centreline every ``resolution_m`` metres, from the first cones on."""
        return geo.centerline(self.left_xy, self.right_xy, self.closed, resolution_m)


def load_dataset_track(folder: str | Path, number: int) -> Track:
    """Load track ``number`` of the FSD racetrack dataset in ``folder`` (``cone_map_K.yaml`` and
    ``boundaries_K.yaml``). Every dataset track is closed."""
    folder = Path(folder)
    with open(folder / f"cone_map_{number}.yaml") as fh:
        cone_map = yaml.safe_load(fh)
    with open(folder / f"boundaries_{number}.yaml") as fh:
        bounds = yaml.safe_load(fh)
    if not isinstance(cone_map, dict) or not all(k in bounds for k in ("left", "right")):
        raise ValueError(f"{folder}: not in the racetrack dataset format")
    ids = np.array(sorted(int(k) for k in cone_map), dtype=np.int64)
    cones = np.array([cone_map[int(i)] for i in ids], dtype=np.float64).reshape(-1, 2)
    index = {int(i): k for k, i in enumerate(ids)}
    try:
        left = [index[int(i)] for i in bounds["left"]]
        right = [index[int(i)] for i in bounds["right"]]
    except KeyError as exc:
        raise ValueError(f"boundary cone {exc} is not in cone_map_{number}.yaml") from exc
    return Track(cones, ids, left, right, closed=True, name=f"track {number}")


def write_csv(track: Track, path: str | Path) -> None:
    """Write ``track`` in our CSV format (see the module docstring)."""
    side = np.full(track.cones.shape[0], "", dtype=object)
    order = np.full(track.cones.shape[0], "", dtype=object)
    for name, idx in (("left", track.left), ("right", track.right)):
        side[idx] = name
        order[idx] = [str(k) for k in range(idx.size)]
    with open(path, "w", newline="") as fh:
        fh.write(f"# closed={int(track.closed)}\n")
        w = csv.writer(fh)
        w.writerow(["id", "x", "y", "side", "order"])
        for k in range(track.cones.shape[0]):
            x, y = track.cones[k]
            w.writerow([int(track.ids[k]), repr(float(x)), repr(float(y)), side[k], order[k]])


def read_csv(path: str | Path) -> Track:
    """Read our CSV format; a bare ``x,y`` CSV gives a track with no boundaries."""
    text = Path(path).read_text()
    closed = True
    lines = []
    for line in text.splitlines():
        if line.startswith("#"):
            if "closed=0" in line.replace(" ", ""):
                closed = False
            continue
        if line.strip():
            lines.append(line)
    if not lines:
        raise ValueError(f"{path}: no rows")
    rows = list(csv.reader(io.StringIO("\n".join(lines))))
    header = [h.strip().lower() for h in rows[0]]
    if "x" in header and "y" in header:
        body = rows[1:]
    else:
        header, body = ["x", "y"], rows
    col = {h: k for k, h in enumerate(header)}
    try:
        cones = np.array([[float(r[col["x"]]), float(r[col["y"]])] for r in body])
    except (ValueError, IndexError) as exc:
        raise ValueError(f"{path}: bad x,y value: {exc}") from exc
    n = len(body)
    ids = (
        np.array([int(r[col["id"]]) for r in body]) if "id" in col else np.arange(n)
    )
    sides: dict[str, list[tuple[int, int]]] = {"left": [], "right": []}
    if "side" in col:
        for k, r in enumerate(body):
            s = r[col["side"]].strip().lower()
            if s in sides:
                o = int(r[col["order"]]) if "order" in col and r[col["order"]].strip() else k
                sides[s].append((o, k))
    left = [k for _, k in sorted(sides["left"])]
    right = [k for _, k in sorted(sides["right"])]
    return Track(cones.reshape(-1, 2), ids, left, right, closed=closed, name=Path(path).stem)


def load_map(path: str | Path) -> Track:
    """Load a map for ``rld solve``: a dataset ``cone_map_K.yaml`` (with its
    ``boundaries_K.yaml`` beside it when present) or one of our CSV files."""
    path = Path(path)
    if path.suffix.lower() in (".yaml", ".yml"):
        stem = path.stem
        if stem.startswith("cone_map_") and (
            path.parent / f"boundaries_{stem[len('cone_map_'):]}.yaml"
        ).exists():
            return load_dataset_track(path.parent, int(stem[len("cone_map_"):]))
        with open(path) as fh:
            cone_map = yaml.safe_load(fh)
        if not isinstance(cone_map, dict):
            raise ValueError(f"{path}: expected a mapping id: [x, y]")
        ids = np.array(sorted(int(k) for k in cone_map), dtype=np.int64)
        cones = np.array([cone_map[int(i)] for i in ids], dtype=np.float64).reshape(-1, 2)
        return Track(cones, ids, [], [], closed=False, name=stem)
    if path.suffix.lower() == ".csv":
        return read_csv(path)
    raise ValueError(f"{path}: unknown map format (expected .yaml or .csv)")
