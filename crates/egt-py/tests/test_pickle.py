"""Issue 17: a Train pickles through its spec (multiprocessing, joblib and
Dask need it) and the copy gives the same numbers, in this process and in a
process pool."""

from __future__ import annotations

import pickle
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import egt

ROOT = Path(__file__).resolve().parents[3]


def _speeds(train: egt.Train) -> dict[str, float]:
    return dict(train.kinematics({"2": 100.0}))


def test_pickle_round_trip_gives_the_same_train() -> None:
    train = egt.load(ROOT / "examples" / "fig3_example61.toml")
    copy = pickle.loads(pickle.dumps(train))
    assert copy.link_names == train.link_names
    assert dict(copy.kinematics({"2": 100.0})) == dict(train.kinematics({"2": 100.0}))
    d = egt.Train.from_dict({"frame": "1", "adjacency": "1-2:a 2-3:b 1-4:a 1-3:G=-2 3-4:G=-3/2"})
    assert pickle.loads(pickle.dumps(d)).dof == 1


def test_trains_cross_a_process_pool() -> None:
    train = egt.load(ROOT / "examples" / "fig3_example61.toml")
    with ProcessPoolExecutor(max_workers=2) as pool:
        results = list(pool.map(_speeds, [train, train]))
    assert results == [_speeds(train)] * 2
