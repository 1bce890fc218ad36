"""Per-stage random streams derived from one user seed.

Each stage gets an independent :class:`numpy.random.Generator` from
``SeedSequence(seed, spawn_key=(stage_id,))``. Stage ids are fixed and must never be renumbered:
changing a rock parameter must not move a single crater. See NumPy's "Parallel random number
generation" guide (SeedSequence spawning).
"""

from __future__ import annotations

import hashlib

import numpy as np

from marsscene._validate import plain
from marsscene.errors import ConfigError

__all__ = ["STAGE_IDS", "as_generator", "robot_rng", "stage_key", "stage_rng", "tile_rng"]

#: Stage name -> spawn key. Append new stages; never renumber existing ones.
STAGE_IDS: dict[str, int] = {
    "terrain": 0,
    "craters": 1,
    "rocks": 2,
    "lighting": 3,
    "runtime": 4,
    "terrain_detail": 5,
    "rock_shapes": 6,
    "texture": 7,
    "sensors": 8,
    "terrain_focus": 9,
    "craters_focus": 10,
    "rocks_outer": 11,
    "rocks_tile": 12,
    "terrain_detail_lod": 13,
    "albedo": 14,
    "soil": 15,
    "orbital": 16,
}


def _check_seed(seed: int) -> int:
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ConfigError(f"seed must be a non-negative integer; got {plain(seed)!r}")
    return int(seed)


def stage_rng(seed: int, stage: str) -> np.random.Generator:
    """Return the random generator of one pipeline stage.

    Parameters
    ----------
    seed : int
        The user seed (non-negative).
    stage : str
        A key of :data:`STAGE_IDS`.

    Examples
    --------
    >>> a = stage_rng(7, "craters").random()
    >>> b = stage_rng(7, "craters").random()
    >>> a == b
    True
    """
    try:
        stage_id = STAGE_IDS[stage]
    except KeyError:
        raise ConfigError(f"unknown stage {stage!r}; known: {sorted(STAGE_IDS)}") from None
    return np.random.default_rng(np.random.SeedSequence(_check_seed(seed), spawn_key=(stage_id,)))


def tile_rng(seed: int, stage: str, row: int, col: int) -> np.random.Generator:
    """The generator of one tile of a stage: ``SeedSequence(seed, spawn_key=(stage_id, row,
    col))``, independent of every other tile's and of the stage's own stream."""
    key = (STAGE_IDS[stage], int(row), int(col))
    return np.random.default_rng(np.random.SeedSequence(_check_seed(seed), spawn_key=key))


def robot_rng(seed: int, stage: str, name: str) -> np.random.Generator:
    """The generator of one named robot of a team in a stage: ``SeedSequence(seed,
    spawn_key=(stage_id, k))`` with ``k`` the first 8 bytes of the name's SHA-256, so each
    robot's stream depends on its name alone (adding a robot moves no other robot's noise)."""
    k = int.from_bytes(hashlib.sha256(name.encode("utf-8")).digest()[:8], "big")
    key = (STAGE_IDS[stage], k)
    return np.random.default_rng(np.random.SeedSequence(_check_seed(seed), spawn_key=key))


def stage_key(seed: int, stage: str) -> int:
    """A 64-bit seed word of a stage, for pointwise (hash-based) noise."""
    ss = np.random.SeedSequence(_check_seed(seed), spawn_key=(STAGE_IDS[stage],))
    return int(ss.generate_state(1, dtype=np.uint64)[0])


def as_generator(rng: np.random.Generator | int) -> np.random.Generator:
    """Normalise a user-facing ``rng`` argument (a Generator or an int seed) once."""
    if isinstance(rng, np.random.Generator):
        return rng
    return np.random.default_rng(_check_seed(rng))
