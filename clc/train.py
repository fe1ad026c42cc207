"""Training of CLC's learned ranker (Ivanov & Markgraf 2024, section VII). Needs torch (the
``train`` extra); everything that runs on the car is in ``clc.ranker`` (numpy only).

Data (``collect``): the evaluation protocol (``rld.simulation``) drives laps over tracks; at
every ``every``-th pose CLC enumerates its candidates on the partial map (cold start, it_max of
``LaneParams``) and each candidate gets a score: the protocol's IoU with the true lane
(``rld.metrics.candidate_ious``, the one the evaluation scores with; since 2026-12-02, before
which training compared with the uncut truth polygon, behind the car included) minus
``wrong_cone_penalty`` for every cone it puts on a side whose boundary does not hold that cone
(a false positive, an unlabelled cone, a cone of the other side). One *list* per pose:
(features, scores). Deviation: the paper's target is the IoU alone; a boundary that hooks onto
the other side's last cone, or takes an unlabelled cone beside the line, changes the IoU by
almost nothing, and a ranker trained on IoU alone learned to prefer such lanes for their extra
length (measured: a model trained on IoU alone picked the hooked lane on a clean straight).
Training pairs candidates of one list with the target p_GT = sigmoid(lambda_iou (t_1 - t_2))
(eq. 14, with the targets t in place of the IoUs) and fits Net(x_1) - Net(x_2) to it with
binary cross-entropy (RankNet), Net an 8-100-1 ReLU network on standardised features.
"""

from __future__ import annotations

import json
import math
import platform
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rld.costs import FEATURE_NAMES
from rld.metrics import candidate_ious, true_polygon
from rld.types import LaneParams

if TYPE_CHECKING:
    from rld.tracks import Track

__all__ = ["RankingList", "collect", "pairwise_dataset", "train_ranker", "save_ranker",
           "top_pick_iou", "heldout_mean_best_iou"]


@dataclass
class RankingList:
    """The candidates of one pose: features (K, 8) and their target scores (K,): IoU with the
    true lane minus the wrong-cone penalty (see the module docstring)."""

    features: np.ndarray
    iou: np.ndarray
    track: str
    pose: int
    fp_rate: float
    range_m: float
    target: np.ndarray | None = None
    """Training target per candidate; None: the IoU."""

    def __post_init__(self) -> None:
        if self.target is None:
            self.target = self.iou


def _as_lists(lists) -> list[RankingList]:
    """``RankingList``s as they are; ``(features (K, 8), ious (K,))`` pairs wrapped in one
    (the IoU is then the target), with the shapes checked."""
    out = []
    for k, cl in enumerate(lists):
        if not isinstance(cl, RankingList):
            features, iou = cl
            cl = RankingList(np.asarray(features, dtype=np.float64),
                             np.asarray(iou, dtype=np.float64), "", k, float("nan"),
                             float("nan"))
        nf = len(FEATURE_NAMES)
        if cl.features.ndim != 2 or cl.features.shape[1] != nf:
            raise ValueError(f"list {k}: features have shape {cl.features.shape}, "
                             f"expected (K, {nf})")
        if cl.features.shape[0] == 0:
            raise ValueError(f"list {k} has no candidates")
        if cl.iou.shape != (cl.features.shape[0],) or cl.target.shape != cl.iou.shape:
            raise ValueError(f"list {k}: {cl.features.shape[0]} candidates but IoUs of shape "
                             f"{cl.iou.shape} and targets of shape {cl.target.shape}")
        out.append(cl)
    return out


def collect(tracks: Iterable[Track], fp_rates=(0.0, 0.1, 0.3), ranges=(50.0,), every: int = 4,
            max_per_list: int = 96, seed: int = 0, params: LaneParams | None = None,
            wrong_cone_penalty: float = 0.03, progress: bool = True) -> list[RankingList]:
    """Candidate lists over the protocol's partial maps (see the module docstring). Lists keep
    at most ``max_per_list`` candidates: the 8 longest and a seeded sample of the rest."""
    from tqdm import tqdm

    from clc.search import enumerate_candidates
    from rld.simulation import simulate_lap

    params = params or LaneParams()
    rng = np.random.default_rng(seed)
    tracks = list(tracks)
    jobs = [(t, fp, r) for t in tracks for fp in fp_rates for r in ranges]
    out: list[RankingList] = []
    bar = tqdm(total=None, desc="collecting candidates", unit="pose", disable=not progress)
    for track, fp, r in jobs:
        lap = simulate_lap(track, range_m=r, fp_rate=fp, seed=seed)
        for k in range(0, len(lap), every):
            frame = lap.frame(k)
            res = enumerate_candidates(frame.cones, frame.pose, params)
            bar.update(1)
            n = len(res.candidates)
            if n < 2 or frame.gt_left.size < 2 or frame.gt_right.size < 2:
                continue
            if true_polygon(frame).area <= 0:
                continue
            keep = np.arange(n)
            if n > max_per_list:
                # A seeded sample, plus the longest lanes (where the best usually are).
                longest = np.argsort(-res.features[:, 0], kind="stable")[:8]
                rest = np.setdiff1d(np.arange(n), longest)
                keep = np.sort(np.concatenate(
                    [longest, rng.choice(rest, size=max_per_list - longest.size,
                                         replace=False)]))
            chosen = [res.candidates[int(i)] for i in keep]
            iou = candidate_ious(frame, chosen)  # the protocol's own IoU (rld.metrics)
            on_left = np.zeros(frame.cones.shape[0], dtype=bool)
            on_right = np.zeros(frame.cones.shape[0], dtype=bool)
            on_left[frame.left_seq[frame.left_seq >= 0]] = True
            on_right[frame.right_seq[frame.right_seq >= 0]] = True
            wrong = np.array([(~on_left[a]).sum() + (~on_right[b]).sum() for a, b, _ in chosen])
            out.append(RankingList(res.features[keep].copy(), iou, track.name, k, fp, r,
                                   target=iou - wrong_cone_penalty * wrong))
    bar.close()
    return out


def pairwise_dataset(lists: list[RankingList] | list[tuple[np.ndarray, np.ndarray]],
                     lambda_iou: float = 20.0, pairs_per_list: int = 256,
                     seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ordered candidate pairs within each list, ``(x1 (P, 8), x2 (P, 8), p_gt (P,))`` with
    p_gt = sigmoid(lambda_iou (t_1 - t_2)) (CLC eq. 14 with the targets t in place of the
    IoUs; for ``(features, ious)`` pairs the targets are the IoUs). Pairs are a seeded sample
    (with replacement) of ``pairs_per_list`` index pairs per list, dropping those with equal
    targets (hence every pair with i == j); lists of fewer than two candidates give none."""
    rng = np.random.default_rng(seed)
    x1, x2, p = [], [], []
    for cl in _as_lists(lists):
        t = cl.target
        n = t.size
        if n < 2:
            continue
        i = rng.integers(0, n, size=pairs_per_list)
        j = rng.integers(0, n, size=pairs_per_list)
        ok = t[i] != t[j]
        i, j = i[ok], j[ok]
        x1.append(cl.features[i])
        x2.append(cl.features[j])
        p.append(1.0 / (1.0 + np.exp(-lambda_iou * (t[i] - t[j]))))
    if sum(v.size for v in p) == 0:
        raise ValueError("no training pairs: every list has equal IoUs")
    return np.vstack(x1), np.vstack(x2), np.concatenate(p)


def _standardiser(lists: list[RankingList]) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation of the training features (std 1 for a constant feature)."""
    f = np.vstack([cl.features for cl in lists])
    mean = f.mean(axis=0)
    std = f.std(axis=0)
    return mean, np.where(std > 1e-9, std, 1.0)


def train_ranker(lists: list[RankingList] | list[tuple[np.ndarray, np.ndarray]], seed: int = 0,
                 epochs: int = 200, lr: float = 0.008, batch_size: int = 8192,
                 lambda_iou: float = 20.0, hidden: int = 100,
                 progress: bool = True) -> dict[str, np.ndarray]:
    """Fit the 8-100-1 RankNet (section VII; the paper: Adam, lr 0.008, batch 8192, 200 epochs)
    with binary cross-entropy on sigmoid(Net(x_1) - Net(x_2)) against p_GT (eq. 14). Returns
    the arrays ``LearnedRanker`` reads (``save_ranker`` writes them)."""
    import torch
    from tqdm import tqdm

    lists = _as_lists(lists)
    torch.manual_seed(seed)
    mean, std = _standardiser(lists)
    x1, x2, p = pairwise_dataset(lists, lambda_iou=lambda_iou, seed=seed)
    t1 = torch.tensor((x1 - mean) / std, dtype=torch.float32)
    t2 = torch.tensor((x2 - mean) / std, dtype=torch.float32)
    tp = torch.tensor(p, dtype=torch.float32)
    net = torch.nn.Sequential(torch.nn.Linear(len(FEATURE_NAMES), hidden), torch.nn.ReLU(),
                              torch.nn.Linear(hidden, 1))
    opt = torch.optim.Adam(net.parameters(), lr=lr)
    loss_fn = torch.nn.BCEWithLogitsLoss()
    gen = torch.Generator().manual_seed(seed)
    n = tp.shape[0]
    for _ in tqdm(range(epochs), desc="training ranker", disable=not progress):
        order = torch.randperm(n, generator=gen)
        for s in range(0, n, batch_size):
            b = order[s: s + batch_size]
            logit = (net(t1[b]) - net(t2[b])).squeeze(1)
            loss = loss_fn(logit, tp[b])
            opt.zero_grad()
            loss.backward()
            opt.step()
    lin1, lin2 = net[0], net[2]
    return {
        "W1": lin1.weight.detach().numpy().T.astype(np.float64).copy(),
        "b1": lin1.bias.detach().numpy().astype(np.float64).copy(),
        "w2": lin2.weight.detach().numpy()[0].astype(np.float64).copy(),
        "b2": np.float64(lin2.bias.detach().numpy()[0]),
        "mean": mean, "std": std,
        "feature_names": np.array(FEATURE_NAMES),
    }


def heldout_mean_best_iou(ranker: Any,
                          lists: list[RankingList] | list[tuple[np.ndarray, np.ndarray]]
                          ) -> tuple[float, float]:
    """``(mean IoU of the top-scored candidate, mean best IoU)`` over the lists: the ranker's
    accuracy and the oracle's (the ceiling the enumeration allows), the two numbers a model
    card reports (CLC section VII; ``top_pick_iou`` gives them with more)."""
    out = top_pick_iou(ranker, lists)
    return out["mean_iou_top"], out["mean_iou_oracle"]


def top_pick_iou(ranker: Any,
                 lists: list[RankingList] | list[tuple[np.ndarray, np.ndarray]]
                 ) -> dict[str, float]:
    """Mean IoU of the top-scored candidate per list, beside the oracle (best IoU per list)
    and the longest-lane heuristic: what a ranker card reports (the paper: 94.8 % held out,
    oracle 97.8 %). Scores come from ``ranker.score(None, None, None, [None] * K, features)``
    (rankers that need the cones, such as ``rld_cost``, do not fit here); ties go to the
    first candidate."""
    lists = _as_lists(lists)
    if not lists:
        raise ValueError("no lists to score")
    picked, oracle, longest, exact = [], [], [], []
    for cl in lists:
        s = ranker.score(None, None, None, [None] * cl.iou.size, cl.features)
        k = int(np.argmax(s))
        picked.append(cl.iou[k])
        oracle.append(cl.iou.max())
        longest.append(cl.iou[int(np.argmax(cl.features[:, 0]))])
        exact.append(cl.target[k] == cl.target.max())
    return {"lists": len(lists), "mean_iou_top": float(np.mean(picked)),
            "mean_iou_oracle": float(np.mean(oracle)),
            "mean_iou_longest": float(np.mean(longest)),
            "best_target_picked": float(np.mean(exact))}


def save_ranker(arrays: dict[str, np.ndarray], path: str | Path, card: dict) -> Path:
    """Write the weights (``.npz``) and a JSON card with the same stem beside them: the model,
    the feature names, the layer sizes and the Python version, then whatever ``card`` holds
    (training data, seed, hyper-parameters, held-out scores; its keys win). Returns the path of
    the ``.npz`` (``.npz`` is appended to a path without it, as ``numpy.savez`` does)."""
    path = Path(path)
    if path.suffix != ".npz":  # where np.savez would put it
        path = path.with_name(path.name + ".npz")
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez(path, **arrays)
    W1 = np.asarray(arrays["W1"])
    full = {"model": "RankNet 8-100-1 ReLU (CLC section VII)",
            "features": list(FEATURE_NAMES),
            "layers": [int(W1.shape[0]), int(W1.shape[1]), 1] if W1.ndim == 2 else None,
            "python": platform.python_version(), **card}
    path.with_suffix(".json").write_text(json.dumps(full, indent=2, default=_jsonable) + "\n")
    return path


def _jsonable(v):
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, float) and math.isnan(v):
        return None
    raise TypeError(f"not JSON: {type(v)}")
