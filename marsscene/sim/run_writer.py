"""The run folder as a drive writes it (layout in :mod:`marsscene.runs.logs`).

Everything streams to disk as it happens, so a drive of any length holds no growing logs in
memory and an interrupted one leaves a usable prefix: ``run.json`` is written first with
``summary.status = "running"``; the trajectories and CSV logs are appended per sample and
flushed once per simulated second; LiDAR PLYs and camera PNGs are written whole or not at all;
``run.json`` is rewritten at the end with the summary and ``status`` ``"complete"`` or
``"interrupted"``.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import Any

from marsscene.rover.geometry import DRIVE_JOINTS, STEER_JOINTS
from marsscene.runs.logs import (
    LIDAR_NOT_STORED,
    CsvLog,
    ImageWriter,
    TumLog,
    depth_mm,
    ply_bytes,
    write_file,
    write_json,
)

__all__ = ["RunWriter"]

_IMU_COLUMNS = ["t", "ax", "ay", "az", "gx", "gy", "gz"]
_BIAS_COLUMNS = ["t", "bgx", "bgy", "bgz", "bax", "bay", "baz"]
_FRAMES = {
    "world": "map: x east, y north, z up (REP-103/105)",
    "base_link": "x forward, y left, z up",
    "imu": "= base_link",
    "lidar": "x forward, y left, z up at the mast top",
}


class RunWriter:
    """Writes one drive's run folder ``out``; every method is a no-op without a folder."""

    def __init__(self, out: Path | None, sim: Any, *, lidar: bool, camera: bool, stereo: bool,
                 meta: dict[str, Any] | None = None, jpeg_cache: Any = None,
                 lidar_files: bool = True):
        self.out = out
        self.lidar_files = lidar_files
        #: a :class:`~marsscene.runs.export.bag_images.JpegCache` to fill beside the PNGs
        self.jpeg_cache = jpeg_cache
        self.logs: dict[str, CsvLog] = {}
        self.poses: dict[str, TumLog] = {}
        self.images = ImageWriter()  # camera PNGs are encoded beside the simulation
        self._made: set[Path] = set()
        self._soil = getattr(sim, "wheel_soil", None)
        if out is None:
            return
        out.mkdir(parents=True, exist_ok=True)
        self._meta = {**_meta(sim), **(meta or {})}
        write_json(out / "run.json", {"summary": {"status": "running"}, **self._meta})
        self.poses["gt"] = TumLog(out / "gt.tum", GT_HEADER)
        self.poses["odom"] = TumLog(out / "odom.tum", ODOM_HEADER)
        self.logs["cmd"] = CsvLog(out / "cmd.csv", ["t", "v", "omega"])
        self.logs["wheels"] = CsvLog(out / "wheels.csv", [
            "t", *[f"rate_{j[-2:]}" for j in DRIVE_JOINTS],
            *[f"steer_{j[-2:]}" for j in STEER_JOINTS]])
        if self._soil is not None:
            self.logs["soil"] = CsvLog(out / "soil.csv", ["t", *[
                f"{q}_{j[-2:]}" for q in ("slip", "sinkage_m", "load_n") for j in DRIVE_JOINTS]])
        self.logs["imu"] = CsvLog(out / "imu.csv", _IMU_COLUMNS)
        self.logs["imu_true"] = CsvLog(out / "imu_true.csv", _IMU_COLUMNS)
        self.logs["imu_bias"] = CsvLog(out / "imu_bias.csv", _BIAS_COLUMNS)
        if lidar:
            self.logs["lidar"] = CsvLog(out / "lidar" / "stamps.csv", ["t", "file", "points"])
            if not lidar_files:
                (out / "lidar").mkdir(parents=True, exist_ok=True)
                write_file(out / "lidar" / LIDAR_NOT_STORED, (
                    b"The LiDAR scans of this run were not stored (lidar_files = false): they "
                    b"went to the drive's listeners only; stamps.csv lists them.\n"))
        if camera:
            self.logs["camera"] = CsvLog(out / "camera" / "stamps.csv", ["t", "rgb", "depth"])
            write_json(out / "camera" / "intrinsics.json", sim.camera_intrinsics())
            if stereo:
                for side in ("left", "right"):
                    self.logs[side] = CsvLog(out / "camera" / side / "stamps.csv", ["t", "rgb"])
                    (out / "camera" / side / "rgb").mkdir(parents=True, exist_ok=True)
                    write_json(out / "camera" / side / "intrinsics.json",
                               sim.camera_intrinsics(side))

    def control(self, t: float, v: float, w: float, rates: Any, steer: Any,
                gt: tuple[Any, Any], odom: tuple[Any, Any]) -> None:
        """One control period: ground truth and odometry ``(xyz_m, quat_wxyz)``, command and
        wheels."""
        if self.logs:
            self.poses["gt"].row(t, *gt)
            self.poses["odom"].row(t, *odom)
            self.logs["cmd"].row(t, (v, w))
            self.logs["wheels"].row(t, (*rates, *steer))
            if self._soil is not None:
                ws = self._soil
                self.logs["soil"].row(t, (*ws.slip, *ws.sinkage_m, *ws.load_n))

    def imu(self, t: float, acc: Any, gyr: Any, acc_true: Any, gyr_true: Any,
            bias: Any = None) -> None:
        if self.logs:
            self.logs["imu"].row(t, (*acc, *gyr))
            self.logs["imu_true"].row(t, (*acc_true, *gyr_true))
            if bias is not None:  # gyro xyz, accel xyz: the bias inside this sample
                self.logs["imu_bias"].row(t, tuple(bias))

    def lidar(self, t: float, index: int, scan: dict[str, Any]) -> None:
        if self.out is None:
            return
        name = f"{index:06d}.ply" if self.lidar_files else ""
        if name:
            write_file(self.out / "lidar" / name,
                       ply_bytes(scan["xyz_m"], scan["intensity"], scan["ring"], scan["t_s"]))
        self.logs["lidar"].row(t, (name, len(scan["range_m"])))

    def camera(self, t: float, index: int, rgb: Any, depth: Any) -> None:
        if self.out is None:
            return
        name = f"{index:06d}.png"
        self.images.submit(self._dir("camera", "rgb") / name, rgb)
        self._jpeg("navcam", name, rgb)
        dname = ""
        if depth is not None:
            self.images.submit(self._dir("camera", "depth") / name, depth_mm(depth))
            dname = "depth/" + name
        self.logs["camera"].row(t, ("rgb/" + name, dname))

    def _jpeg(self, stream: str, name: str, rgb: Any) -> None:
        if self.jpeg_cache is not None:
            path = self.jpeg_cache.file(stream, name)  # already under out: not out / path
            if path.parent not in self._made:
                path.parent.mkdir(parents=True, exist_ok=True)
                self._made.add(path.parent)
            self.images.submit(path, rgb, self.jpeg_cache.encode)

    def _dir(self, *parts: str | Path) -> Path:
        """``out/parts...``, made on first use (not one mkdir call per frame)."""
        assert self.out is not None
        path = self.out.joinpath(*parts)
        if path not in self._made:
            path.mkdir(parents=True, exist_ok=True)
            self._made.add(path)
        return path

    def stereo(self, t: float, index: int, pair: Any) -> None:
        if self.out is None:
            return
        name = f"{index:06d}.png"
        for side, img in zip(("left", "right"), pair, strict=True):
            self.images.submit(self.out / "camera" / side / "rgb" / name, img)
            self._jpeg(side, name, img)
            self.logs[side].row(t, ("rgb/" + name,))

    def flush(self) -> None:
        """Push the logs to the operating system (a killed drive keeps them up to here)."""
        for log in self.logs.values():
            log.flush()
        for pose in self.poses.values():
            pose.flush()

    def park(self) -> None:
        """Close the logs until their next rows (:meth:`marsscene.runs.logs.CsvLog.park`)."""
        for log in (*self.logs.values(), *self.poses.values()):
            log.park()

    def close(self) -> None:
        self.images.close()
        for log in self.logs.values():
            log.close()
        for pose in self.poses.values():
            pose.close()

    def finish(self, summary: dict[str, Any]) -> None:
        """Rewrite ``run.json`` with the drive's summary (``summary["status"]`` says how it
        ended)."""
        if self.out is not None:
            write_json(self.out / "run.json", {"summary": summary, **self._meta})


GT_HEADER = "ground truth base_link in map (world) frame"
ODOM_HEADER = "wheel odometry base_link in odom frame (= map at t=0)"


def _meta(sim: Any) -> dict[str, Any]:
    run = sim.run
    soil_map = getattr(sim, "soil_map", None)
    soil = {} if soil_map is None else {"soil": [asdict(s) for s in soil_map.soils]}
    return {
        **soil,
        "rover": asdict(sim.rover),
        "noise": asdict(run.noise),
        "rates_hz": {
            "physics": 1.0 / sim.dt_physics_s,
            "control": run.control_hz,
            "imu": run.imu_hz,
            "lidar": run.lidar.spec.rate_hz if run.lidar else None,
            "camera": run.camera.rate_hz if run.camera else None,
        },
        "lidar": run.lidar.spec.to_dict() if run.lidar else None,
        "camera": asdict(run.camera) if run.camera else None,
        "pursuit": None,
        "frames": _FRAMES,
    }
