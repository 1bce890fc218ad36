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
from marsscene.benchmark.vpr.spec import PROTOCOLS, VprSpec
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
@given(protocol=st.sampled_from(list(PROTOCOLS)),
       length_m=st.floats(min_value=5.0, max_value=300.0))
def test_any_length_is_authored_or_refused(dust_scene: Path, protocol: str,
                                           length_m: float) -> None:
    spec = VprSpec.from_toml(protocol)
    assert spec.scene.base_config() == VprSpec.from_toml("dust").scene.base_config()
    _authored_or_refused(spec.with_length(length_m), dust_scene)


@settings(max_examples=12, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(scene=st.sampled_from(["gentle_scene", "slope_scene"]),
       shape=st.sampled_from(["loop", "out-and-back"]),
       length_m=st.floats(min_value=5.0, max_value=2000.0),
       width_m=st.floats(min_value=1.0, max_value=60.0),
       heading_deg=st.floats(min_value=-360.0, max_value=360.0))
def test_slam_routes_on_any_scene_are_authored_or_refused(
        request: pytest.FixtureRequest, scene: str, shape: str, length_m: float,
        width_m: float, heading_deg: float) -> None:
    """The SLAM spec's automatic routes (``--length-m``) on other scenes: a gentle plain and a
    slope, lengths up to far more than the scene holds."""
    from marsscene.benchmark.routes import auto_route
    from marsscene.benchmark.slam.spec import RouteSpec
    from marsscene.sim.world import load_world

    world = load_world(request.getfixturevalue(scene))
    spec = RouteSpec(shape=shape, length_m=length_m, width_m=width_m, heading_deg=heading_deg)
    try:
        route = auto_route(spec, world.heightfield, world.obstacles)
    except RuntimeSimError as err:
        assert "\n" not in str(err) and str(err)
        return
    assert abs(route.length_m / length_m - 1.0) <= MAX_LENGTH_ERROR


@pytest.mark.parametrize(("shape", "length_m"), [("loop", 30.0), ("out-and-back", 40.0)])
def test_a_route_that_fits_the_plain_is_authored(gentle_scene: Path, shape: str,
                                                 length_m: float) -> None:
    from marsscene.benchmark.routes import auto_route
    from marsscene.benchmark.slam.spec import RouteSpec
    from marsscene.sim.world import load_world

    world = load_world(gentle_scene)
    route = auto_route(RouteSpec(shape=shape, length_m=length_m), world.heightfield,
                       world.obstacles)
    assert abs(route.length_m / length_m - 1.0) <= MAX_LENGTH_ERROR
