"""Newton's own USD importer collides with the rock colliders of a written scene.

``ModelBuilder.add_usd`` on ``scene.usda`` (not the project's Newton helper): a small sphere
dropped onto the top of each of the largest obstacle rocks (instance prims) and of the largest
merged rocks (one static mesh per tile) first stops on the rock's top, not on the terrain.
Skipped without the extra ``newton`` (CI does not install it: Warp compiles its CPU kernels on
first use, about 2 minutes here)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("newton", reason="needs the extra [newton]")
pytest.importorskip("warp", reason="needs the extra [newton]")
pytest.importorskip("pxr")

import marsscene as ms

pytestmark = pytest.mark.newton

RADIUS_M = 0.05
DROP_M = 0.3
DT_S = 0.002
IGNORE: list[str] = []  # e.g. ["/World/RockColliders"]: the test fails (spheres hit the ground)


def _tops(scene: ms.Scene, stage: object) -> tuple[np.ndarray, np.ndarray]:
    """Highest collider point (x, y, z) of the 3 widest instance rocks and merged rocks."""
    from marsscene.export.usd.rock_colliders_read import merged_rocks
    from marsscene.transforms import quat_to_matrix

    rocks = scene.rocks
    big = np.flatnonzero(rocks.diameter_m >= scene.config.export.rock_instance_min_diameter_m)
    tops = []
    for i in big[np.argsort(-rocks.diameter_m[big])[:3]]:
        verts = np.concatenate([p.vertices for p in
                                scene.rock_prototypes[rocks.prototype[i]].collision])
        world = (quat_to_matrix(rocks.orientation_wxyz[i]) @ (verts * rocks.scale_xyz_m[i]).T).T
        world += rocks.position_xyz_m[i]
        tops.append(world[np.argmax(world[:, 2])])
    merged = []
    for tile in merged_rocks(stage):
        face_rock = tile.rock_of_face()
        for k in np.argsort(-rocks.diameter_m[tile.rows])[:3]:
            pts = tile.points_m[tile.faces[face_rock == k].ravel()].astype(np.float64)
            merged.append((rocks.diameter_m[tile.rows[k]], pts[np.argmax(pts[:, 2])]))
    merged.sort(key=lambda m: -m[0])
    return np.array(tops), np.array([p for _, p in merged[:3]])


def test_spheres_dropped_on_rocks_stop_on_their_tops(tmp_path: Path) -> None:
    import newton
    import warp as wp
    from pxr import Usd

    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [24.0, 24.0], "post_m": 0.25,
                    "rms_height_m": 0.02},
        "craters": {"enabled": False}, "rocks": {"k": 0.15, "d_min_m": 0.25},
        "export": {"formats": ["usd"]}})
    scene = ms.build_scene(cfg, seed=4)
    ms.write_scene(scene, tmp_path / "s")
    stage = Usd.Stage.Open(str(tmp_path / "s" / "scene.usda"))
    big, small = _tops(scene, stage)
    assert len(big) == 3 and len(small) == 3
    tops = np.vstack([big, small])
    wp.config.quiet = True
    builder = newton.ModelBuilder(up_axis=newton.Axis.Z)
    builder.add_usd(stage, ignore_paths=IGNORE)
    bodies = []
    for x, y, z in tops:
        body = builder.add_body(xform=wp.transform(wp.vec3(x, y, z + RADIUS_M + DROP_M),
                                                   wp.quat_identity()))
        builder.add_shape_sphere(body, radius=RADIUS_M)
        bodies.append(body)
    model = builder.finalize(device="cpu")
    solver = newton.solvers.SolverXPBD(model)
    state, nxt, control = model.state(), model.state(), model.control()
    pipeline = newton.CollisionPipeline(model, broad_phase="sap")
    contacts = pipeline.contacts()
    stop_z = np.full(len(bodies), np.nan)
    for _ in range(int(0.8 / DT_S)):  # free fall of 0.3 m at 3.72 m/s^2: 0.4 s
        pipeline.collide(state, contacts)
        state.clear_forces()
        solver.step(state, nxt, control, contacts, DT_S)
        state, nxt = nxt, state
        q, qd = state.body_q.numpy()[bodies], state.body_qd.numpy()[bodies]
        first = np.isnan(stop_z) & (qd[:, 2] > -0.05) & (q[:, 2] < tops[:, 2] + DROP_M)
        stop_z[first] = q[first, 2]
    ground = scene.heightfield.sample(tops[:, 0], tops[:, 1])
    np.testing.assert_allclose(stop_z, tops[:, 2] + RADIUS_M, atol=0.03)
    assert (tops[:, 2] - ground > 0.08).all()  # the terrain would stop it that much lower
