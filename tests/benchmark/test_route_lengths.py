"""Automatic benchmark routes at any length a user may type (``--length-m``, at least 5 m):
the route is authored within :data:`~marsscene.benchmark.routes.MAX_LENGTH_ERROR` of the
length, or refused with a one-line error; never a traceback. The VPR protocols' out-and-back
around the Mars Base habitat is the case that once divided by zero (a short shape shrunk into
the habitat's footprint gave a route of length 0)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

pytest.importorskip("mujoco")

from marsscene.benchmark.routes import MAX_LENGTH_ERROR
from marsscene.benchmark.vpr.dataset import _route, _scene
from marsscene.benchmark.vpr.spec import VprSpec
from marsscene.errors import RuntimeSimError


@pytest.fixture(scope="module")
def dust_scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _scene(VprSpec.from_toml("dust"), tmp_path_factory.mktemp("vpr"))


def _authored_or_refused(spec: VprSpec, scene: Path) -> None:
    try:
        route = _route(spec, scene)
    except RuntimeSimError as err:
        assert "\n" not in str(err) and "--length-m" in str(err)
        return
    asked = spec.scene.route.length_m
    assert asked is not None
    assert abs(route.length_m / asked - 1.0) <= MAX_LENGTH_ERROR


@pytest.mark.parametrize("length_m", [5.0, 30.0, 40.0])
def test_the_short_routes_that_crashed_are_refused_in_one_line(dust_scene: Path,
                                                                length_m: float) -> None:
    spec = VprSpec.from_toml("dust").with_length(length_m)
    with pytest.raises(RuntimeSimError, match="no out-and-back route of about"):
        _route(spec, dust_scene)


@settings(max_examples=6, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(protocol=st.sampled_from(["dust", "day-dark"]),
       length_m=st.floats(min_value=5.0, max_value=300.0))
def test_any_length_is_authored_or_refused(dust_scene: Path, protocol: str,
                                           length_m: float) -> None:
    spec = VprSpec.from_toml(protocol)
    assert spec.scene.base_config() == VprSpec.from_toml("dust").scene.base_config()
    _authored_or_refused(spec.with_length(length_m), dust_scene)
