"""Query places and priors: the seeded distributions, determinism, the answer contract."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from marsscene.benchmark.loc.cell import score
from marsscene.benchmark.loc.methods import read_answer, run_method, write_answer
from marsscene.benchmark.loc.queries import draw_priors, query_arc_lengths, query_rng
from marsscene.benchmark.loc.spec import LocMethod, LocSpec
from marsscene.errors import ConfigError


def test_prior_errors_have_the_seeded_distribution() -> None:
    priors = draw_priors(2000, (5.0, 50.0), 3.0, rng=query_rng(0, "plain"))
    d = np.array([p.distance_m for p in priors])
    ang = np.array([math.atan2(p.dy_m, p.dx_m) for p in priors])
    head = np.degrees([p.dyaw_rad for p in priors])
    assert d.min() >= 5.0 and d.max() <= 50.0
    assert stats.kstest(d, stats.uniform(5.0, 45.0).cdf).pvalue > 0.01
    assert stats.kstest(ang, stats.uniform(-math.pi, 2 * math.pi).cdf).pvalue > 0.01
    assert np.abs(head).max() <= 3.0
    assert stats.kstest(head, stats.uniform(-3.0, 6.0).cdf).pvalue > 0.01


def test_queries_are_deterministic_per_seed_and_scene() -> None:
    def draw(seed: int, scene: str) -> tuple[np.ndarray, list[float]]:
        rng = query_rng(seed, scene)
        s = query_arc_lengths(300.0, 20, 5.0, rng=rng)
        return s, [p.dx_m for p in draw_priors(20, (5.0, 50.0), 3.0, rng=rng)]

    a, b = draw(0, "plain"), draw(0, "plain")
    assert np.array_equal(a[0], b[0]) and a[1] == b[1]
    assert not np.array_equal(a[0], draw(0, "crater")[0])
    assert not np.array_equal(a[0], draw(1, "plain")[0])
    assert a[0].min() >= 6.0 and a[0].max() <= 299.0 and np.all(np.diff(a[0]) >= 0)


def test_the_answer_file_round_trips(tmp_path: Path) -> None:
    write_answer(tmp_path / "a.tum", 12.5, -3.25, math.radians(170.0), stamp_s=4.0)
    x, y, yaw = read_answer(tmp_path / "a.tum") or (0.0, 0.0, 0.0)
    assert (x, y) == pytest.approx((12.5, -3.25)) and math.degrees(yaw) == pytest.approx(170.0)
    assert read_answer(tmp_path / "missing.tum") is None
    (tmp_path / "b.tum").write_text("# nothing\n")
    assert read_answer(tmp_path / "b.tum") is None
    truth = {"x_m": 12.0, "y_m": -3.25, "yaw_rad": math.radians(173.0)}
    s = score((x, y, yaw), truth)
    assert s["position_error_m"] == pytest.approx(0.5) and s["heading_error_deg"] == \
        pytest.approx(3.0)
    assert not s["success_1m_2deg"] and s["success_5m_5deg"]


USER_MODULE = """
import json
from marsscene.benchmark.loc.methods import write_answer


def shifted_prior(query_dir, answer):  # the prior + 1 m east
    p = json.loads((query_dir / "query.json").read_text())["prior"]
    write_answer(answer, p["x_m"] + 1.0, p["y_m"], p["yaw_rad"])
"""


def _query_dir(tmp_path: Path) -> Path:
    q = tmp_path / "query"
    q.mkdir()
    (q / "query.json").write_text('{"prior": {"x_m": 3.0, "y_m": 4.0, "yaw_rad": 0.5}, '
                                  '"stamp_s": 2.0}')
    return q


def test_the_user_method_contract_round_trips(tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    q = _query_dir(tmp_path)
    (tmp_path / "my_loc_method.py").write_text(USER_MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    py = LocMethod(name="mine", kind="python", function="my_loc_method:shifted_prior")
    run_method(py, q, tmp_path / "py.tum")
    assert read_answer(tmp_path / "py.tum") == pytest.approx((4.0, 4.0, 0.5))
    script = ("import sys, json; p = json.load(open(sys.argv[1] + '/query.json'))['prior']; "
              "open(sys.argv[2], 'w').write('0 %f %f 0 0 0 0 1\\n' % (p['x_m'], p['y_m'] - 2))")
    cmd = LocMethod(name="cmd", kind="command",
                    command=f"{sys.executable} -c \"{script}\" {{query_dir}} {{answer}}")
    run_method(cmd, q, tmp_path / "cmd.tum")
    assert read_answer(tmp_path / "cmd.tum") == pytest.approx((3.0, 2.0, 0.0))
    bad = LocMethod(name="bad", kind="command", command=f"{sys.executable} -c 'exit(3)'")
    with pytest.raises(ConfigError, match="exited with 3"):
        run_method(bad, q, tmp_path / "bad.tum")


def test_spec_errors_are_one_line() -> None:
    base = {"scenes": [{"name": "p", "preset": "jezero-plain",
                        "route": {"shape": "loop", "length_m": 50.0}}],
            "methods": [{"name": "prior", "kind": "prior"}]}
    assert LocSpec.from_dict(base).methods_for(0.5)[0].sensor == "none"
    with pytest.raises(ConfigError, match="position_error_m"):
        LocSpec.from_dict({**base, "prior": {"position_error_m": [50.0, 5.0]}})
    with pytest.raises(ConfigError, match="kind"):
        LocSpec.from_dict({**base, "methods": [{"name": "x", "kind": "magic"}]})
    with pytest.raises(ConfigError, match="unknown key"):
        LocSpec.from_dict({**base, "local": {"scan": 3}})
