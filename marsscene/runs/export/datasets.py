"""SLAM dataset folders from a run folder: TUM RGB-D and EuRoC MAV (numpy + Pillow only).

* ``tum-rgbd`` (Sturm et al. 2012): ``rgb/``, ``depth/`` (16-bit PNG, 0 = no return),
  ``rgb.txt``, ``depth.txt``, ``groundtruth.txt`` (navcam optical frame in ``map``),
  ``associations.txt`` and an ORB-SLAM3 settings file ``orbslam3_rgbd.yaml``. The depth
  scale (counts per metre) is in ``depth.txt``'s header and the settings'
  ``RGBD.DepthMapFactor`` (:func:`tum_depth_per_m`): the format's 5000 (what Open3D's
  ``create_from_tum_format`` and most TUM loaders assume; 13.1 m at most, farther is 0), or
  with ``images="run-depth"`` the run's own 1000, hard-linked, in a folder named for it
  (``tum_rgbd_depth1000``). The colour images are hard links to the run's PNGs.
* ``euroc`` (Burri et al. 2016): ``mav0/cam0`` (navcam or stereo left), ``mav0/cam1`` (stereo
  right, when logged), ``mav0/imu0`` (noisy IMU, body = ``base_link``),
  ``mav0/state_groundtruth_estimate0``, each with ``data.csv`` and ``sensor.yaml``, plus
  ``timestamps.txt`` and ORB-SLAM3 settings (``orbslam3_stereo_inertial.yaml`` or
  ``orbslam3_mono_inertial.yaml``). Images are the run's RGB PNGs, hard-linked
  (``images="link"``; ORB-SLAM3 turns them grey itself), or mono8 copies as in EuRoC
  (``images="convert"``).

Commands to run ORB-SLAM3 on them: :doc:`/ros`.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from marsscene._atomic import replacing_dir
from marsscene.errors import ExportError, RuntimeSimError
from marsscene.runs.export.frames import camera_frame, frame_in_base, static_transforms
from marsscene.runs.export.imu_noise import EUROC_IMU_KEYS, imu_noise_declared, rate_hz
from marsscene.runs.export.options import DATASET_FORMATS, DATASET_IMAGES, dataset_folder
from marsscene.runs.logs import png_bytes
from marsscene.runs.runlog import CameraStream, RunLog, read_image

__all__ = ["FORMATS", "RUN_DEPTH_PER_M", "TUM_DEPTH_PER_M", "export_dataset",
           "tum_associations", "tum_depth_per_m"]

FORMATS = DATASET_FORMATS
#: TUM RGB-D reference depth PNG scale: 5000 counts per metre (max 13.1 m; farther is stored
#: as 0); the default.
TUM_DEPTH_PER_M = 5000
#: The run folder's depth PNGs: millimetres (max 65.5 m); ``images="run-depth"`` keeps it.
RUN_DEPTH_PER_M = 1000


def export_dataset(
    run_dir: str | os.PathLike[str],
    fmt: str,
    out_dir: str | os.PathLike[str] | None = None,
    *,
    overwrite: bool = False,
    progress: Callable[[int, int], None] | None = None,
    images: str = "link",
) -> Path:
    """Write ``RUN_DIR`` as a ``tum-rgbd`` or ``euroc`` folder (default
    ``RUN_DIR/<format>``, :func:`~marsscene.runs.export.options.dataset_folder`).

    Needs camera logs (``euroc`` also uses ``camera/left`` and ``camera/right`` when present);
    a camera-less run raises :class:`~marsscene.errors.RuntimeSimError`, an existing output
    folder :class:`~marsscene.errors.ExportError` unless ``overwrite``. ``progress(done,
    total)`` is called per image written. ``images``: ``"link"`` hard-links the run's colour
    PNGs (copied where the file system cannot link) and writes TUM depth at 5000 per metre;
    ``"convert"`` also writes EuRoC mono8; ``"run-depth"`` hard-links TUM depth at the run's
    1000 per metre. Returns the folder.

    Parameters
    ----------
    run_dir : path-like
        A run folder of :func:`marsscene.drive` with camera logs.
    fmt : {"tum-rgbd", "euroc"}
        TUM RGB-D (colour, depth, ``groundtruth.txt``, ``associations.txt``, an ORB-SLAM3
        settings file) or EuRoC MAV (``mav0/``: cameras, IMU, ground truth).
    out_dir : path-like, optional
        The dataset folder (default ``RUN_DIR/tum_rgbd`` or ``RUN_DIR/euroc``).
    overwrite : bool
        Replace an existing dataset folder.
    progress : callable, optional
        ``progress(done, total)`` per image written.
    images : {"link", "convert", "run-depth"}
        How images are written (above).

    Returns
    -------
    Path
        The dataset folder.

    Raises
    ------
    RuntimeSimError
        A run without camera logs.
    ExportError
        An unknown format, or an existing folder without ``overwrite``.

    Examples
    --------
    A one-second drive with a small camera, written as TUM RGB-D:

    >>> import tempfile
    >>> import marsscene as ms
    >>> from marsscene.runs.export import export_dataset
    >>> cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [20, 20]}})
    >>> camera = ms.CameraConfig(width_px=64, height_px=48, rate_hz=2.0)
    >>> run = ms.drive(ms.build_scene(cfg, seed=1), command=(0.3, 0.0), seconds=1.0,
    ...                config=ms.RunConfig(camera=camera), out_dir=tempfile.mkdtemp())
    >>> folder = export_dataset(run.out_dir, "tum-rgbd")
    >>> folder.name, sorted(p.name for p in folder.iterdir())[:4]
    ('tum_rgbd', ['associations.txt', 'depth', 'depth.txt', 'groundtruth.txt'])
    >>> len(list((folder / "rgb").glob("*.png")))
    3
    """
    if fmt not in FORMATS:
        raise ExportError(f"format = {fmt!r}; expected one of {', '.join(FORMATS)}")
    if images not in DATASET_IMAGES:
        raise ExportError(f"images = {images!r}; expected one of {', '.join(DATASET_IMAGES)}")
    run = RunLog(run_dir)
    cams = run.camera_streams()
    if not cams:
        raise RuntimeSimError(f"{run.path} has no camera logs; drive with --camera to export "
                              f"{fmt}")
    if fmt == "tum-rgbd" and not cams[0].depth_files:
        raise RuntimeSimError(f"{run.path}: the camera logged no depth; tum-rgbd needs RGB-D")
    final = Path(out_dir) if out_dir is not None else run.path / dataset_folder(fmt, images)
    stereo = [c for c in cams[1:] if c.name in ("left", "right")]
    statics = static_transforms(run.rover, {c.name: c.intrinsics for c in stereo})
    pair = sorted(stereo, key=lambda c: c.name)  # left, right
    used = [cams[0]] if fmt == "tum-rgbd" or len(pair) != 2 else pair
    total = sum(len(c.stamps_s) for c in used)
    done = iter(range(1, total + 1))

    def tick() -> None:
        if progress is not None:
            progress(next(done), total)

    with replacing_dir(final, overwrite=overwrite, create=False) as tmp:
        if fmt == "tum-rgbd":
            _tum_rgbd(run, cams[0], statics, tmp, tick, link_depth=images == "run-depth")
        else:
            _euroc(run, used, statics, tmp, tick, link=images != "convert")
    return final


def tum_depth_per_m(folder: str | os.PathLike[str]) -> float:
    """Depth counts per metre of a TUM RGB-D folder: its ``orbslam3_rgbd.yaml``'s
    ``RGBD.DepthMapFactor`` (5000, the TUM reference, for folders without one)."""
    path = Path(folder) / "orbslam3_rgbd.yaml"
    if path.is_file():
        for line in path.read_text(encoding="utf-8").splitlines():
            if line.startswith("RGBD.DepthMapFactor:"):
                return float(line.split(":", 1)[1])
    return float(TUM_DEPTH_PER_M)


def tum_associations(folder: str | os.PathLike[str]) -> list[list[str]]:
    """The rows of a TUM RGB-D folder's ``associations.txt``: colour stamp and file, depth
    stamp and file."""
    text = (Path(folder) / "associations.txt").read_text(encoding="utf-8")
    return [ln.split() for ln in text.splitlines() if ln.strip() and not ln.startswith("#")]


def camera_trajectory(
    run: RunLog, t_base_cam: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Ground-truth poses of a camera (4 x 4 pose in ``base_link``): xyz (N, 3), quat xyzw."""
    rot = Rotation.from_quat(run.gt.quat_xyzw)
    xyz = run.gt.xyz_m + rot.apply(t_base_cam[:3, 3])
    q = (rot * Rotation.from_matrix(t_base_cam[:3, :3])).as_quat()
    return xyz, q


def _lines(rows: list[str], head: str) -> str:
    return head + "".join(r + "\n" for r in rows)


def _link_or_copy(src: Path, dst: Path) -> None:
    """``dst`` as a hard link to ``src`` (no second copy of a long run's images on disk), or a
    copy where the file system cannot link (another device, no hard links)."""
    try:
        os.link(src, dst)
    except OSError:
        dst.write_bytes(src.read_bytes())


def _tum_rgbd(
    run: RunLog, cam: CameraStream, statics: list, out: Path, tick: Callable[[], None], *,
    link_depth: bool
) -> None:
    (out / "rgb").mkdir(parents=True)
    (out / "depth").mkdir()
    stamps = [f"{t:.6f}" for t in cam.stamps_s]
    per_m = RUN_DEPTH_PER_M if link_depth else TUM_DEPTH_PER_M
    for s, rgb, dep in zip(stamps, cam.rgb_files, cam.depth_files, strict=True):
        _link_or_copy(rgb, out / "rgb" / f"{s}.png")
        if link_depth:
            _link_or_copy(dep, out / "depth" / f"{s}.png")
        else:
            mm = read_image(dep).astype(np.uint32) * (TUM_DEPTH_PER_M // RUN_DEPTH_PER_M)
            (out / "depth" / f"{s}.png").write_bytes(
                png_bytes(np.where(mm > 65535, 0, mm).astype(np.uint16)))
        tick()
    src = f"# file: marsscene run {run.path.name}\n"
    (out / "rgb.txt").write_text(_lines([f"{s} rgb/{s}.png" for s in stamps],
                                        "# color images\n" + src + "# timestamp filename\n"))
    (out / "depth.txt").write_text(_lines(
        [f"{s} depth/{s}.png" for s in stamps],
        f"# depth maps ({per_m} per metre, 0 = no return)\n" + src
        + "# timestamp filename\n"))
    (out / "associations.txt").write_text(
        _lines([f"{s} rgb/{s}.png {s} depth/{s}.png" for s in stamps], ""))
    xyz, q = camera_trajectory(run, frame_in_base(statics, camera_frame(cam.name)))
    rows = [
        f"{t:.6f} " + " ".join(f"{v:.6f}" for v in p) + " " + " ".join(f"{v:.9f}" for v in r)
        for t, p, r in zip(run.gt.timestamps_s, xyz, q, strict=True)
    ]
    (out / "groundtruth.txt").write_text(_lines(
        rows, "# ground truth trajectory: navcam optical frame in map\n" + src
        + "# timestamp tx ty tz qx qy qz qw\n"))
    i = cam.intrinsics
    (out / "orbslam3_rgbd.yaml").write_text(_orb_head(cam, run) + _orb_cam(1, i) + (
        f"Stereo.ThDepth: 40.0\nStereo.b: 0.07\nRGBD.DepthMapFactor: {per_m:.1f}\n"
    ) + _ORB_TAIL)


def _euroc(
    run: RunLog, cams: list[CameraStream], statics: list, out: Path, tick: Callable[[], None],
    *, link: bool
) -> None:
    mav = out / "mav0"
    t_b_c = [frame_in_base(statics, camera_frame(c.name)) for c in cams]
    for k, (cam, tbc) in enumerate(zip(cams, t_b_c, strict=True)):
        d = mav / f"cam{k}"
        (d / "data").mkdir(parents=True)
        ns = [round(t * 1e9) for t in cam.stamps_s]
        for n, rgb in zip(ns, cam.rgb_files, strict=True):
            if link:
                _link_or_copy(rgb, d / "data" / f"{n}.png")
            else:
                img = read_image(rgb)
                mono = img if img.ndim == 2 else np.round(img @ [0.299, 0.587, 0.114]).astype(
                    np.uint8)
                (d / "data" / f"{n}.png").write_bytes(png_bytes(mono))
            tick()
        (d / "data.csv").write_text(_lines([f"{n},{n}.png" for n in ns],
                                           "#timestamp [ns],filename\n"))
        i = cam.intrinsics
        (d / "sensor.yaml").write_text(
            f"sensor_type: camera\ncomment: marsscene {camera_frame(cam.name)}"
            f"{', rgb8 PNGs (links to the run frames)' if link else ''}\n"
            + _t_bs(tbc) + f"rate_hz: {rate_hz(cam.stamps_s):g}\n"
            f"resolution: [{i['width']}, {i['height']}]\ncamera_model: pinhole\n"
            f"intrinsics: [{i['fx']:.9g}, {i['fy']:.9g}, {i['cx']:.9g}, {i['cy']:.9g}]\n"
            "distortion_model: radial-tangential\ndistortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n"
        )
        if k == 0:
            (out / "timestamps.txt").write_text(_lines([str(n) for n in ns], ""))
    imu = mav / "imu0"
    imu.mkdir(parents=True)
    rows = [f"{round(r[0] * 1e9)}," + ",".join(f"{v:.9g}" for v in (*r[4:7], *r[1:4]))
            for r in run.imu]
    (imu / "data.csv").write_text(_lines(rows, "#timestamp [ns],w_RS_S_x [rad s^-1],"
                                  "w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
                                  "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n"))
    nd = imu_noise_declared(run)
    (imu / "sensor.yaml").write_text(
        f"sensor_type: imu\ncomment: marsscene IMU (body = base_link), noise profile "
        f"{nd['profile']}: white noise, per-run turn-on bias, bias random walk\n"
        + _t_bs(np.eye(4)) + f"rate_hz: {rate_hz(run.imu[:, 0]):g}\n"
        + "".join(f"{k}: {nd[k]:.9g}\n" for k in EUROC_IMU_KEYS)
    )
    gt = mav / "state_groundtruth_estimate0"
    gt.mkdir()
    v = np.gradient(run.gt.xyz_m, run.gt.timestamps_s, axis=0) if len(run.gt) > 1 else \
        np.zeros_like(run.gt.xyz_m)
    bias = _true_bias(run)
    rows = [
        f"{round(t * 1e9)}," + ",".join(f"{x:.9g}" for x in (*p, q[3], *q[:3], *vel, *b))
        for t, p, q, vel, b in zip(run.gt.timestamps_s, run.gt.xyz_m, run.gt.quat_xyzw, v, bias,
                                   strict=True)
    ]
    (gt / "data.csv").write_text(_lines(rows, _EUROC_GT_HEAD))
    name = "stereo_inertial" if len(cams) == 2 else "mono_inertial"
    text = _orb_head(cams[0], run) + "".join(_orb_cam(k + 1, c.intrinsics)
                                             for k, c in enumerate(cams))
    if len(cams) == 2:
        text += "Stereo.ThDepth: 60.0\n" + _cv_mat("Stereo.T_c1_c2",
                                                   np.linalg.inv(t_b_c[0]) @ t_b_c[1])
    text += _cv_mat("IMU.T_b_c1", t_b_c[0]) + "IMU.InsertKFsWhenLost: 0\n" + _orb_imu(nd) + (
        f"IMU.Frequency: {rate_hz(run.imu[:, 0]):.1f}\n")
    (out / f"orbslam3_{name}.yaml").write_text(text + _ORB_TAIL)


_EUROC_GT_HEAD = (
    "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
    "q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], "
    "b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], "
    "b_a_RS_S_z [m s^-2]\n"
)


#: ORB-SLAM3 key, EuRoC key, floor used only where the simulated value is 0 (profile none).
_ORB_IMU = (("IMU.NoiseGyro", "gyroscope_noise_density", 1e-5),
            ("IMU.NoiseAcc", "accelerometer_noise_density", 1e-4),
            ("IMU.GyroWalk", "gyroscope_random_walk", 1e-6),
            ("IMU.AccWalk", "accelerometer_random_walk", 1e-5))


def _orb_imu(nd: dict[str, Any]) -> str:
    """ORB-SLAM3's IMU noise (the same densities as imu0/sensor.yaml); a zero is floored."""
    out = ""
    for key, euroc, floor in _ORB_IMU:
        value = nd[euroc]
        if value <= 0.0:
            out += (f"# {key}: the simulated value is 0 (profile {nd['profile']}); ORB-SLAM3 "
                    f"needs > 0, so a small floor is declared\n")
        out += f"{key}: {value if value > 0.0 else floor:.9g}\n"
    return out


def _true_bias(run: RunLog) -> NDArray[np.float64]:
    """IMU bias (gyro xyz, accel xyz) at each ground-truth stamp: from ``imu_bias.csv`` (the
    bias of every IMU sample) interpolated to the stamps; for older runs, the turn-on bias
    and, for a walking bias, the mean of the walk given its start and end (linear)."""
    t = run.gt.timestamps_s
    if run.imu_bias is not None and len(run.imu_bias):
        b = run.imu_bias
        return np.stack([np.interp(t, b[:, 0], b[:, k]) for k in range(1, 7)], axis=1)
    summary = run.meta.get("summary", {}).get("imu_bias")
    noise = run.meta.get("noise", {})
    start = np.array([*noise.get("gyro_bias_rad_s", (0, 0, 0)),
                      *noise.get("accel_bias_m_s2", (0, 0, 0))], np.float64)
    end = start
    if summary:
        start = np.array([*summary["gyro_start_rad_s"], *summary["accel_start_m_s2"]])
        end = np.array([*summary["gyro_end_rad_s"], *summary["accel_end_m_s2"]])
    t_imu = run.imu[:, 0] if len(run.imu) else t
    span = float(t_imu[-1] - t_imu[0]) if len(t_imu) > 1 else 0.0
    f = np.clip((t - t_imu[0]) / span, 0.0, 1.0) if span > 0 else np.zeros(len(t))
    return start + f[:, None] * (end - start)


def _t_bs(m: NDArray[np.float64]) -> str:
    data = ", ".join(f"{v:.9g}" for v in m.ravel())
    return f"T_BS:\n  cols: 4\n  rows: 4\n  data: [{data}]\n"


def _cv_mat(name: str, m: NDArray[np.float64]) -> str:
    data = ", ".join(f"{v:.9f}" for v in m.ravel())
    return f"{name}: !!opencv-matrix\n  rows: 4\n  cols: 4\n  dt: f\n  data: [{data}]\n"


def _orb_head(cam: CameraStream, run: RunLog) -> str:
    i = cam.intrinsics
    return (f'%YAML:1.0\n# ORB-SLAM3 settings for marsscene run {run.path.name}\n'
            f'File.version: "1.0"\nCamera.type: "PinHole"\nCamera.width: {i["width"]}\n'
            f'Camera.height: {i["height"]}\nCamera.fps: {round(rate_hz(cam.stamps_s))}\n'
            "Camera.RGB: 1\n")


def _orb_cam(k: int, i: dict[str, float]) -> str:
    return "".join(f"Camera{k}.{n}: {float(i[n]):.9g}\n" for n in ("fx", "fy", "cx", "cy")) + \
        "".join(f"Camera{k}.{n}: 0.0\n" for n in ("k1", "k2", "p1", "p2"))


_ORB_TAIL = (
    "ORBextractor.nFeatures: 1250\nORBextractor.scaleFactor: 1.2\nORBextractor.nLevels: 8\n"
    "ORBextractor.iniThFAST: 20\nORBextractor.minThFAST: 7\nViewer.KeyFrameSize: 0.05\n"
    "Viewer.KeyFrameLineWidth: 1.0\nViewer.GraphLineWidth: 0.9\nViewer.PointSize: 2.0\n"
    "Viewer.CameraSize: 0.08\nViewer.CameraLineWidth: 3.0\nViewer.ViewpointX: 0.0\n"
    "Viewer.ViewpointY: -0.7\nViewer.ViewpointZ: -1.8\nViewer.ViewpointF: 500.0\n"
)
