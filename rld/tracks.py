"""Tracks: cone maps with annotated boundaries, and their file formats.

- The FSD racetrack dataset format (Ivanov & Markgraf 2024, VIII-A): ``cone_map_K.yaml``
  (``id: [x, y]``) and ``boundaries_K.yaml`` (``left`` and ``right`` id lists, closed loops).
- Our CSV: one cone a row, ``id,x,y,side,order``; ``side`` is ``left``, ``right`` or empty and
  ``order`` the cone's position on its boundary. A first line ``# closed=1`` marks a closed
  track. A CSV with only ``x,y`` columns (no header names needed beyond them) is a bare map.
  An optional ``color`` (or ``colour``) column holds each cone's colour label as written
  (``Track.meta["colors"]``, lower-cased, an empty cell ``unknown``).

The readers raise ``ValueError`` naming the file (and the line or cone) for a file that is not
in its format.
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
    map_path = folder / f"cone_map_{number}.yaml"
    bounds_path = folder / f"boundaries_{number}.yaml"
    ids, cones = _cone_map(map_path, _read_yaml(map_path))
    bounds = _read_yaml(bounds_path)
    if not isinstance(bounds, dict) or not all(
        isinstance(bounds.get(k), list) for k in ("left", "right")
    ):
        raise ValueError(f"{bounds_path}: expected lists 'left' and 'right' of cone ids")
    index = {int(i): k for k, i in enumerate(ids)}
    sides = []
    for side in ("left", "right"):
        try:
            sides.append([index[_cone_id(i)] for i in bounds[side]])
        except KeyError as exc:
            raise ValueError(f"{bounds_path}: {side} boundary cone {exc} is not in "
                             f"{map_path.name}") from exc
        except ValueError as exc:
            raise ValueError(f"{bounds_path}: {side} boundary: {exc}") from exc
    try:
        return Track(cones, ids, sides[0], sides[1], closed=True, name=f"track {number}")
    except ValueError as exc:
        raise ValueError(f"{bounds_path}: {exc}") from exc


def _read_yaml(path: Path):
    """``path``'s YAML; ``ValueError`` naming the file when it is not YAML."""
    try:
        with open(path, encoding="utf-8") as fh:
            return yaml.safe_load(fh)
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not a text file") from exc
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1})" if mark is not None else ""
        problem = getattr(exc, "problem", None) or type(exc).__name__
        raise ValueError(f"{path}: not valid YAML{where}: {problem}") from exc


def _cone_id(key) -> int:
    """A cone id as written in a file (an integer, or a string of one); ``ValueError``
    otherwise (booleans and fractions too)."""
    value = None
    if isinstance(key, (int, np.integer)) and not isinstance(key, bool):
        value = int(key)
    elif isinstance(key, str):
        try:
            value = int(key.strip())
        except ValueError:
            pass
    if value is None or not -(2**63) <= value < 2**63:
        raise ValueError(f"cone id {key!r} is not an integer")
    return value


def _cone_map(path: Path, cone_map) -> tuple[np.ndarray, np.ndarray]:
    """The ids (sorted) and (N, 2) positions of a dataset-style ``id: [x, y]`` mapping read
    from ``path``; ``ValueError`` naming the file and the cone for anything else."""
    if not isinstance(cone_map, dict) or not cone_map:
        raise ValueError(f"{path}: expected a mapping of cone ids to [x, y] in metres")
    xy: dict[int, tuple[float, float]] = {}
    for key, value in cone_map.items():
        try:
            cid = _cone_id(key)
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from exc
        if cid in xy:
            raise ValueError(f"{path}: cone id {cid} appears twice")
        try:
            x, y = (float(v) for v in value)
            if isinstance(value, (str, bytes)) or not (np.isfinite(x) and np.isfinite(y)):
                raise ValueError
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{path}: cone {cid}: expected [x, y] in metres, got "
                             f"{value!r}") from exc
        xy[cid] = (x, y)
    ids = np.array(sorted(xy), dtype=np.int64)
    cones = np.array([xy[int(i)] for i in ids], dtype=np.float64).reshape(-1, 2)
    return ids, cones


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
    """Read our CSV format; a bare ``x,y`` CSV gives a track with no boundaries. A ``color``
    (or ``colour``) column's labels land in ``meta["colors"]`` (see the module docstring)."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not a text file") from exc
    closed = True
    lines = []
    numbers = []  # each kept line's number in the file, for the messages
    for number, line in enumerate(text.splitlines(), start=1):
        if line.startswith("#"):
            if "closed=0" in line.replace(" ", ""):
                closed = False
            continue
        if line.strip():
            lines.append(line)
            numbers.append(number)
    if not lines:
        raise ValueError(f"{path}: no rows")
    try:
        rows = list(csv.reader(io.StringIO("\n".join(lines))))
    except csv.Error as exc:
        raise ValueError(f"{path}: not a CSV file: {exc}") from exc
    header = [h.strip().lower() for h in rows[0]]
    if "x" in header and "y" in header:
        body, numbers = rows[1:], numbers[1:]
    else:
        header, body = ["x", "y"], rows
    if not body:
        raise ValueError(f"{path}: no rows")
    col = {h: k for k, h in enumerate(header)}
    if "colour" in col and "color" not in col:
        col["color"] = col["colour"]

    def cell(r: list[str], name: str, line: int) -> str:
        try:
            return r[col[name]].strip()
        except IndexError:
            raise ValueError(f"{path}: line {line}: no {name!r} column "
                             f"({len(r)} of {len(header)} cells)") from None

    cones = np.empty((len(body), 2))
    for k, (r, line) in enumerate(zip(body, numbers, strict=True)):
        for j, name in enumerate(("x", "y")):
            text_value = cell(r, name, line)
            try:
                cones[k, j] = float(text_value)
            except ValueError:
                raise ValueError(f"{path}: line {line}: bad x,y value: {name} = "
                                 f"{text_value!r} is not a number") from None
            if not np.isfinite(cones[k, j]):
                raise ValueError(f"{path}: line {line}: bad x,y value: {name} = "
                                 f"{text_value!r} is not finite")
    n = len(body)
    ids = np.arange(n)
    if "id" in col:
        for k, (r, line) in enumerate(zip(body, numbers, strict=True)):
            try:
                ids[k] = _cone_id(cell(r, "id", line))
            except ValueError as exc:
                raise ValueError(f"{path}: line {line}: {exc}") from None
        seen: dict[int, int] = {}
        for cid, line in zip(ids.tolist(), numbers, strict=True):
            if cid in seen:
                raise ValueError(f"{path}: line {line}: cone id {cid} appears twice (also on "
                                 f"line {seen[cid]})")
            seen[cid] = line
    sides: dict[str, list[tuple[int, int]]] = {"left": [], "right": []}
    if "side" in col:
        for k, (r, line) in enumerate(zip(body, numbers, strict=True)):
            s = cell(r, "side", line).lower()
            if s in sides:
                o = cell(r, "order", line) if "order" in col else ""
                try:
                    sides[s].append((int(o) if o else k, k))
                except ValueError:
                    raise ValueError(f"{path}: line {line}: order {o!r} is not an "
                                     "integer") from None
    left = [k for _, k in sorted(sides["left"])]
    right = [k for _, k in sorted(sides["right"])]
    meta = {}
    if "color" in col:
        meta["colors"] = tuple(cell(r, "color", line).lower() or "unknown"
                               for r, line in zip(body, numbers, strict=True))
    try:
        return Track(cones, ids, left, right, closed=closed, name=Path(path).stem, meta=meta)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from exc


def load_map(path: str | Path) -> Track:
    """Load a map for ``rld solve``: a dataset ``cone_map_K.yaml`` (with its
    ``boundaries_K.yaml`` beside it when present) or one of our CSV files."""
    path = Path(path)
    if path.suffix.lower() in (".yaml", ".yml"):
        stem = path.stem
        number = stem[len("cone_map_"):] if stem.startswith("cone_map_") else ""
        if number.isdigit() and (path.parent / f"boundaries_{number}.yaml").exists():
            return load_dataset_track(path.parent, int(number))
        ids, cones = _cone_map(path, _read_yaml(path))
        return Track(cones, ids, [], [], closed=False, name=stem)
    if path.suffix.lower() == ".csv":
        return read_csv(path)
    raise ValueError(f"{path}: unknown map format (expected .yaml or .csv)")
