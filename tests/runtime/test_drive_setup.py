"""A drive's set-up: the simulator is built (its MJCF compiled) once, with only the rocks of the
route's corridor, and a controller gets the route the drive authored instead of authoring it
again."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import marsscene as ms
from marsscene.cli import main
from marsscene.sim.control import OnStart
from marsscene.sim.world import load_world, world_obstacles

pytest.importorskip("mujoco")

WP = [[-6.0, -6.0], [4.0, -6.0]]


@pytest.fixture(scope="module")
def rocky_scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 30 m procedural scene with rocks (MJCF only)."""
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [30, 30], "post_m": 0.25,
                    "rms_height_m": 0.05},
        "craters": {"enabled": False}})
    out = tmp_path_factory.mktemp("rocky") / "scene"
    ms.write_scene(ms.build_scene(cfg, seed=5), out, formats=("mjcf",))
    return out


def _count_builds(monkeypatch: pytest.MonkeyPatch) -> list[bool]:
    """Every ``RoverSim`` built from now on: whether it had a rock corridor."""
    from marsscene.sim.rover_sim import RoverSim

    built: list[bool] = []
    init = RoverSim.__init__

    def counting(self: Any, *args: Any, **kwargs: Any) -> None:
        built.append(kwargs.get("contact_corridor_xy_m") is not None)
        init(self, *args, **kwargs)

    monkeypatch.setattr(RoverSim, "__init__", counting)
    return built


def test_the_simulator_is_built_once_and_the_controller_gets_the_route(
    rocky_scene: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    built = _count_builds(monkeypatch)
    seen: dict[str, Any] = {}

    def make(sim: Any, route: Any) -> Any:
        seen.update(sim=sim, route=route)
        return lambda obs: (0.0, 0.0)

    run = ms.drive(rocky_scene, waypoints=WP, controller=OnStart(make), seconds=0.1)
    kept, total = run.rocks_kept
    assert total > 0 and kept < total  # the corridor's rocks only
    assert built == [True]  # one simulator, built with the corridor
    assert seen["route"] is run.route
    np.testing.assert_array_equal(run.route.xy_m[0], WP[0])
    # the authored route is the one planned on the whole scene (every rock an obstacle)
    world = load_world(rocky_scene)
    assert len(world.obstacles.radius_m) == total
    again = ms.drive(rocky_scene, waypoints=WP, seconds=0.1)
    np.testing.assert_array_equal(again.route.xy_m, run.route.xy_m)


def test_rocks_that_touch_nothing_have_the_same_obstacles(rocky_scene: Path) -> None:
    """A world to plan on compiles its rocks without contacts (no convex hulls): their discs
    and heights, hence the routes planned around them, are the simulated rocks' to the bit."""
    import mujoco

    from marsscene.sim.rover_sim import load_scene_spec
    from marsscene.sim.terrain import scene_heightfield

    def world(contacts: bool) -> tuple[Any, Any]:
        spec, _, _ = load_scene_spec(rocky_scene, rock_contacts=contacts)
        model = spec.compile()
        data = mujoco.MjData(model)
        mujoco.mj_kinematics(model, data)
        return model, world_obstacles(model, data, scene_heightfield(model))

    (solid, a), (ghost, b) = world(True), world(False)
    rocks = [i for i in range(solid.ngeom) if solid.geom(i).name.startswith("rock_")]
    assert rocks and solid.geom_contype[rocks].all() and not ghost.geom_contype[rocks].any()
    for key in ("xy_m", "radius_m", "height_m"):
        np.testing.assert_array_equal(getattr(a, key), getattr(b, key))


_NAV = '''
SEEN = []


class Planner:
    def __init__(self, route=None):
        SEEN.append(route)

    def __call__(self, obs):
        return 0.0, 0.0
'''


def test_drive_cli_gives_a_controller_class_the_drive_route(
    rocky_scene: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, runner: Any
) -> None:
    (tmp_path / "route_nav.py").write_text(_NAV)
    (tmp_path / "wp.txt").write_text("\n".join(f"{x} {y}" for x, y in WP))
    monkeypatch.chdir(tmp_path)
    monkeypatch.delitem(sys.modules, "route_nav", raising=False)
    built = _count_builds(monkeypatch)
    res = runner.invoke(main, ["drive", str(rocky_scene), "--waypoints", "wp.txt", "--controller",
                               "route_nav:Planner", "--seconds", "0.1", "--out", "run"])
    assert res.exit_code == 0, res.output
    (route,) = sys.modules["route_nav"].SEEN
    written = ms.runtime.read_tum(tmp_path / "run" / "route.tum")
    np.testing.assert_allclose(route.xy_m, written.xyz_m[:, :2], atol=1e-6)  # 6 decimals
    assert built == [True]
    res = runner.invoke(main, ["drive", str(rocky_scene), "--controller", "route_nav:Planner",
                               "--seconds", "0.1", "--out", "free"])
    assert res.exit_code == 0, res.output
    assert sys.modules["route_nav"].SEEN[-1] is None  # no route: the class gets None
