"""The local map's scans: a method option keeps a query's last N scans; a spec whose methods
read no image drives with the LiDAR alone."""

from __future__ import annotations

import re

import numpy as np
import pytest

from marsscene.benchmark.loc.methods import last_scans
from marsscene.benchmark.loc.spec import LocSpec
from marsscene.errors import ConfigError


def _doc(counts: list[int]) -> dict[str, object]:
    return {"lidar": {"scans": len(counts), "points": sum(counts), "points_per_scan": counts}}


def test_last_scans_keeps_the_last_n_scans_points() -> None:
    counts = [3, 5, 2, 4]
    scan_of = np.repeat(np.arange(4), counts).astype(np.float64)  # each point names its scan
    pts = np.column_stack([scan_of, scan_of, scan_of])
    for n in range(1, 5):
        kept = last_scans(pts, _doc(counts), n)
        assert len(kept) == sum(counts[-n:])
        assert set(kept[:, 0].astype(int)) == set(range(4 - n, 4))


@pytest.mark.parametrize(("doc", "scans", "message"), [
    (_doc([3, 5]), 3, "option scans = 3; need 1..2 (the query's scans)"),
    (_doc([3, 5]), 0, "option scans = 0; need 1..2"),
    (_doc([3, 5]), 1.5, "option scans = 1.5; need 1..2"),
    ({"lidar": {"scans": 2, "points": 8}}, 1, "needs a query folder with lidar.points_per_scan"),
])
def test_a_bad_scan_count_is_a_one_line_error(doc: dict[str, object], scans: object,
                                              message: str) -> None:
    with pytest.raises(ConfigError, match=re.escape(message)) as err:
        last_scans(np.zeros((8, 3)), doc, scans)
    assert "\n" not in str(err.value)


def _spec(*kinds: str) -> LocSpec:
    return LocSpec.from_dict({
        "scenes": [{"name": "s", "preset": "jezero-plain", "route": {"shape": "loop",
                                                                    "length_m": 100.0}}],
        "methods": [{"name": f"m{i}", "kind": k, **({"command": "true"} if k == "command"
                                                    else {})} for i, k in enumerate(kinds)]})


def test_the_camera_is_driven_only_when_a_method_may_read_it() -> None:
    lidar_only = _spec("dem-correlation", "prior")
    assert not lidar_only.needs_camera
    assert lidar_only.run_config(lidar=True, camera=False).camera is None
    assert _spec("dem-correlation", "ortho-match").needs_camera
    assert _spec("prior", "command").needs_camera  # a user's method may read the images
    assert _spec("prior").run_config(lidar=True).camera is not None
