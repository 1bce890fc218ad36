"""Compressed bags (issue 23): image_transport payloads decoded independently (OpenCV and the
ConfigHeader layout of compressed_depth_image_transport), MCAP chunk compression read by rosbags
and by mcap + mcap-ros2, sqlite3 message compression, Humble metadata, determinism."""

from __future__ import annotations

import struct
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("cv2")

import cv2
from rosbags.highlevel import AnyReader
from ruamel.yaml import YAML

from marsscene.cli import main
from marsscene.errors import ExportError
from marsscene.runs.export.bag import write_bag
from marsscene.runs.runlog import RunLog, read_image

RGB = "/rover/rgb/image_raw/compressed"
DEPTH = "/rover/depth/image_raw/compressedDepth"
LEFT = "/rover/stereo/left/image_raw/compressed"


def _raw(path: Path) -> dict[str, list[tuple[int, bytes, Any]]]:
    """Every message per topic as (log time, CDR bytes, decoded) through rosbags."""
    out: dict[str, list[tuple[int, bytes, Any]]] = defaultdict(list)
    with AnyReader([path]) as reader:
        for conn, stamp, raw in reader.messages():
            out[conn.topic].append((stamp, bytes(raw), reader.deserialize(raw, conn.msgtype)))
    return out


def _meta(path: Path) -> dict[str, Any]:
    return YAML(typ="safe").load((path / "metadata.yaml").read_text())[
        "rosbag2_bagfile_information"]


@pytest.fixture(scope="module")
def default_bag(stereo_run: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_bag(stereo_run, tmp_path_factory.mktemp("cbag") / "bag").path


@pytest.fixture(scope="module")
def default_msgs(default_bag: Path) -> dict[str, list[tuple[int, bytes, Any]]]:
    return _raw(default_bag)


def _decode_depth(msg: Any) -> tuple[str, np.ndarray]:
    """compressed_depth_image_transport's decoder, written from codec.cpp: int32 format (0 =
    INV_DEPTH), float32 A, B; a 16-bit PNG; 32FC1 depth = A / (q - B), q = 0 -> NaN."""
    data = msg.data.tobytes()
    fmt, a, b = struct.unpack("<iff", data[:12])
    assert fmt == 0
    q = cv2.imdecode(np.frombuffer(data[12:], np.uint8), cv2.IMREAD_UNCHANGED)
    assert q.dtype == np.uint16
    enc = msg.format.split(";")[0]
    if enc == "16UC1":
        return enc, q
    with np.errstate(divide="ignore"):
        d = np.float32(a) / (q.astype(np.float32) - np.float32(b))
    return enc, np.where(q == 0, np.nan, d)


def test_default_topics_formats_and_no_depth_cloud(default_msgs, stereo_run):
    run = RunLog(stereo_run)
    cam = run.camera_streams()[0]
    n = len(cam.stamps_s)
    for topic in (RGB, DEPTH, LEFT, "/rover/stereo/right/image_raw/compressed",
                  "/rover/rgb/camera_info", "/rover/depth/camera_info"):
        assert len(default_msgs[topic]) == n, topic
    for gone in ("/rover/rgb/image_raw", "/rover/depth/image_raw", "/rover/depth/points"):
        assert gone not in default_msgs
    assert {m.format for _, _, m in default_msgs[RGB]} == {"rgb8; jpeg compressed bgr8"}
    assert {m.format for _, _, m in default_msgs[LEFT]} == {"mono8; jpeg compressed mono8"}
    assert {m.format for _, _, m in default_msgs[DEPTH]} == {"16UC1; compressedDepth png"}
    for topic in (RGB, DEPTH):
        stamps = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec
                  for _, _, m in default_msgs[topic]]
        assert stamps == [t for t, _, _ in default_msgs[topic]]
        assert {m.header.frame_id for _, _, m in default_msgs[topic]} == {"navcam_optical_frame"}


def test_jpeg_colour_and_mono_decode_close_to_the_run(default_msgs, stereo_run):
    run = RunLog(stereo_run)
    cams = {c.name: c for c in run.camera_streams()}
    for topic, cam in ((RGB, cams["navcam"]), (LEFT, cams["left"])):
        for (_, _, msg), f in zip(default_msgs[topic], cam.rgb_files, strict=True):
            got = cv2.imdecode(msg.data, cv2.IMREAD_UNCHANGED).astype(np.int16)
            ref = read_image(f).astype(np.int16)
            if ref.ndim == 3:
                got = got[..., ::-1]  # OpenCV decodes to BGR ("... compressed bgr8")
            assert got.shape == ref.shape
            err = np.abs(got - ref)
            assert err.mean() < 2.5 and np.percentile(err, 99) <= 16, (topic, err.mean())


def test_png_colour_is_the_run_file_and_decodes_exactly(stereo_run, tmp_path):
    bag = write_bag(stereo_run, tmp_path / "png", image_codec="png", compression="lz4")
    msgs = _raw(bag.path)
    run = RunLog(stereo_run)
    cams = {c.name: c for c in run.camera_streams()}
    assert {m.format for _, _, m in msgs[RGB]} == {"rgb8; png compressed bgr8"}
    assert {m.format for _, _, m in msgs[LEFT]} == {"mono8; png compressed "}  # sic
    for topic, cam in ((RGB, cams["navcam"]), (LEFT, cams["left"])):
        for (_, _, msg), f in zip(msgs[topic], cam.rgb_files, strict=True):
            bgr = cv2.imdecode(msg.data, cv2.IMREAD_UNCHANGED)
            ref = read_image(f)
            np.testing.assert_array_equal(bgr[..., ::-1] if ref.ndim == 3 else bgr, ref)
            assert msg.data.tobytes() == f.read_bytes()  # reused, not re-encoded


def test_compressed_depth_32fc1_inverse_depth_within_one_quantisation_step(stereo_run, tmp_path):
    bag = write_bag(stereo_run, tmp_path / "m", depth_encoding="32FC1", sensors=["camera"])
    msgs = _raw(bag.path)
    assert {m.format for _, _, m in msgs[DEPTH]} == {"32FC1; compressedDepth png"}
    cam = RunLog(stereo_run).camera_streams()[0]
    a_ref = np.float32(100.0) * np.float32(101.0)  # depth_quantization z0 = 100 m
    for (_, _, msg), f in zip(msgs[DEPTH], cam.depth_files, strict=True):
        _, a, b = struct.unpack("<iff", msg.data.tobytes()[:12])
        assert a == a_ref and b == pytest.approx(1.0 - 10100.0 / 65.535, rel=1e-6)
        enc, d = _decode_depth(msg)
        mm = read_image(f)
        ok = (mm > 0) & (mm < 65535)
        assert enc == "32FC1" and ok.any() and (mm == 0).any()
        z = mm[ok] / 1000.0
        # truncation of A/z + B: decoded depth is >= z, by less than one step dz = z^2 / A
        err = d[ok] - z
        assert np.all(err >= -1e-4 * z) and np.all(err <= z**2 / a * 1.001 + 1e-4 * z)
        assert np.isnan(d[~ok]).all()


def test_compressed_depth_16uc1_is_exact_and_the_run_png(stereo_run, tmp_path):
    bag = write_bag(stereo_run, tmp_path / "mm", ros_distro="humble", sensors=["camera"])
    msgs = _raw(bag.path)
    cam = RunLog(stereo_run).camera_streams()[0]
    assert {m.format for _, _, m in msgs[DEPTH]} == {"16UC1; compressedDepth"}  # Humble
    for (_, _, msg), f in zip(msgs[DEPTH], cam.depth_files, strict=True):
        _, mm = _decode_depth(msg)
        np.testing.assert_array_equal(mm, read_image(f))
        assert msg.data.tobytes()[12:] == f.read_bytes()


def test_both_readers_agree_on_every_message_and_chunks_are_compressed(default_bag,
                                                                       default_msgs):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    mcap_raw: dict[str, list[tuple[int, bytes]]] = defaultdict(list)
    with open(default_bag / "bag.mcap", "rb") as fh:
        reader = make_reader(fh)
        chunks = reader.get_summary().chunk_indexes
        assert chunks and {c.compression for c in chunks} == {"zstd"}
        assert sum(c.compressed_size for c in chunks) < sum(c.uncompressed_size for c in chunks)
        for _, channel, message in reader.iter_messages(log_time_order=False):
            mcap_raw[channel.topic].append((message.log_time, message.data))
    assert {t: v for t, v in mcap_raw.items()} == {
        t: [(s, raw) for s, raw, _ in v] for t, v in default_msgs.items()}
    seen: dict[str, int] = defaultdict(int)
    with open(default_bag / "bag.mcap", "rb") as fh:
        for _, channel, _, msg in make_reader(fh, decoder_factories=[DecoderFactory()]
                                              ).iter_decoded_messages(topics=[RGB, DEPTH]):
            _, _, ref = default_msgs[channel.topic][seen[channel.topic]]
            assert msg.format == ref.format and bytes(msg.data) == ref.data.tobytes()
            assert msg.header.stamp.nanosec == ref.header.stamp.nanosec
            seen[channel.topic] += 1
    assert seen == {RGB: len(default_msgs[RGB]), DEPTH: len(default_msgs[DEPTH])}


@pytest.mark.parametrize("compression", ["none", "lz4", "zstd_fast"])
def test_chunk_codecs_write_the_same_messages(stereo_run, default_msgs, tmp_path, compression):
    from mcap.reader import make_reader

    bag = write_bag(stereo_run, tmp_path / "b", compression=compression)
    with open(bag.path / "b.mcap", "rb") as fh:
        codecs = {c.compression for c in make_reader(fh).get_summary().chunk_indexes}
    assert codecs == {"" if compression == "none" else compression.split("_")[0]}
    got = _raw(bag.path)
    assert {t: [r for _, r, _ in v] for t, v in got.items()} == {
        t: [r for _, r, _ in v] for t, v in default_msgs.items()}
    meta = _meta(bag.path)
    assert (meta["version"], meta["compression_format"], meta["compression_mode"]) == (9, "", "")
    assert meta["custom_data"]["marsscene.bag_compression"] == compression


def test_sqlite3_message_compression_recorded_and_read(stereo_run, default_msgs, tmp_path):
    bag = write_bag(stereo_run, tmp_path / "sq", storage="sqlite3")
    meta = _meta(bag.path)
    assert (meta["compression_format"], meta["compression_mode"]) == ("zstd", "message")
    assert meta["storage_identifier"] == "sqlite3" and meta["relative_file_paths"] == ["sq.db3"]
    got = _raw(bag.path)
    assert {t: [r for _, r, _ in v] for t, v in got.items()} == {
        t: [r for _, r, _ in v] for t, v in default_msgs.items()}
    with pytest.raises(ExportError, match="lz4"):
        write_bag(stereo_run, tmp_path / "sq2", storage="sqlite3", compression="lz4")


#: rosbag2 Humble, metadata_io.cpp (version 5): the keys it encodes, at each level.
HUMBLE_V5 = {
    "bag": {"version", "storage_identifier", "duration", "starting_time", "message_count",
            "topics_with_message_count", "compression_format", "compression_mode",
            "relative_file_paths", "files"},
    "topic": {"topic_metadata", "message_count"},
    "topic_metadata": {"name", "type", "serialization_format", "offered_qos_profiles"},
    "file": {"path", "starting_time", "duration", "message_count"},
}


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_humble_metadata_is_version_5_with_exactly_its_fields(stereo_run, default_msgs,
                                                              tmp_path, storage):
    bag = write_bag(stereo_run, tmp_path / "h", ros_distro="humble", storage=storage)
    meta = _meta(bag.path)
    assert meta["version"] == 5 and set(meta) == HUMBLE_V5["bag"]
    assert set(meta["duration"]) == {"nanoseconds"}
    assert set(meta["starting_time"]) == {"nanoseconds_since_epoch"}
    for t in meta["topics_with_message_count"]:
        assert set(t) == HUMBLE_V5["topic"] and set(t["topic_metadata"]) == HUMBLE_V5[
            "topic_metadata"]
        assert t["topic_metadata"]["serialization_format"] == "cdr"
        assert isinstance(t["topic_metadata"]["offered_qos_profiles"], str)
    for f in meta["files"]:
        assert set(f) == HUMBLE_V5["file"] and set(f["duration"]) == {"nanoseconds"}
    counts = {t["topic_metadata"]["name"]: t["message_count"]
              for t in meta["topics_with_message_count"]}
    assert counts == {t: len(v) for t, v in default_msgs.items()}
    assert meta["message_count"] == sum(counts.values()) == meta["files"][0]["message_count"]
    (static,) = [t for t in meta["topics_with_message_count"]
                 if t["topic_metadata"]["name"] == "/tf_static"]
    (qos,) = YAML(typ="safe").load(static["topic_metadata"]["offered_qos_profiles"])
    # Humble's qos.cpp: enums as ints (KEEP_LAST 1, RELIABLE 1, TRANSIENT_LOCAL 1), sec/nsec
    assert (qos["history"], qos["depth"], qos["reliability"], qos["durability"]) == (1, 1, 1, 1)
    assert qos["deadline"] == {"sec": 2147483647, "nsec": 4294967295}
    expect = ("zstd", "message") if storage == "sqlite3" else ("", "")
    assert (meta["compression_format"], meta["compression_mode"]) == expect
    got = _raw(bag.path)  # rosbags reads version 5
    assert {t: len(v) for t, v in got.items()} == counts
    assert {m.format for _, _, m in got[DEPTH]} == {"16UC1; compressedDepth"}


def test_same_run_same_bytes_and_cloud_option(stereo_run, default_bag, tmp_path):
    again = write_bag(stereo_run, tmp_path / "again" / "bag")
    for name in ("bag.mcap", "metadata.yaml"):
        assert (again.path / name).read_bytes() == (default_bag / name).read_bytes()
    both = write_bag(stereo_run, tmp_path / "both", images="both", sensors=["camera"])
    assert {"/rover/rgb/image_raw", RGB, "/rover/depth/image_raw", DEPTH,
            "/rover/depth/points"} <= set(both.counts)
    cloud = write_bag(stereo_run, tmp_path / "cloud", depth_cloud=True, sensors=["camera"])
    assert "/rover/depth/points" in cloud.counts and "/rover/rgb/image_raw" not in cloud.counts
    raw = write_bag(stereo_run, tmp_path / "raw", images="raw", depth_cloud=False,
                    sensors=["camera"])
    assert "/rover/depth/points" not in raw.counts and RGB not in raw.counts


def test_bad_options_are_one_line_errors(runner, stereo_run, tmp_path):
    for kw, match in (({"images": "tiff"}, "images"), ({"image_codec": "webp"}, "image_codec"),
                      ({"jpeg_quality": 0}, "jpeg_quality"), ({"compression": "gzip"},
                                                               "compression"),
                      ({"ros_distro": "iron"}, "ros_distro")):
        with pytest.raises(ExportError, match=match):
            write_bag(stereo_run, tmp_path / "x", **kw)
    assert not (tmp_path / "x").exists()
    res = runner.invoke(main, ["bag", str(stereo_run), "--out", str(tmp_path / "y"),
                               "--bag-storage", "sqlite3", "--bag-compression", "lz4"])
    assert res.exit_code == 1 and "lz4" in res.output and "Traceback" not in res.output
    assert len(res.output.strip().splitlines()) == 1
    res = runner.invoke(main, ["bag", str(stereo_run), "--out", str(tmp_path / "z"),
                               "--bag-images", "both", "--bag-image-format", "png",
                               "--ros-distro", "humble", "--sensor", "camera"])
    assert res.exit_code == 0, res.output
    meta = _meta(tmp_path / "z")
    assert meta["version"] == 5
    names = {t["topic_metadata"]["name"] for t in meta["topics_with_message_count"]}
    assert {RGB, "/rover/rgb/image_raw", "/rover/depth/points"} <= names


def test_shared_load_once_per_item_and_nothing_kept() -> None:
    """Two messages built from one file on different threads load it once, and the item is
    dropped after its second use (a long bag holds no growing cache)."""
    from concurrent.futures import ThreadPoolExecutor

    from marsscene.runs.export.bag_topics import _Shared

    loads: list[int] = []

    def load(i: int) -> int:
        loads.append(i)
        return i * 10

    shared = _Shared(load, 2)
    with ThreadPoolExecutor(4) as pool:
        got = list(pool.map(shared, [i for i in range(200) for _ in range(2)]))
    assert got == [i * 10 for i in range(200) for _ in range(2)]
    assert sorted(loads) == list(range(200))
    assert shared.slots == {}


def test_threaded_chunk_writer_makes_the_stock_mcap_writers_bytes(tmp_path):
    """marsscene's MCAP storage (chunks compressed on threads, Message records packed in one
    write) against rosbags' own McapWriter with the same compressor: the same file."""
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2.storage_mcap import McapWriter
    from rosbags.typesys import Stores, get_typestore

    from marsscene.runs.export.bag_writer import _compressor, open_writer

    class Stock(McapWriter):
        def __init__(self, path: Path, compression: Any) -> None:
            super().__init__(path, compression)
            self.compression, self.compressor = "zstd", _compressor("zstd", 3)

    store = get_typestore(Stores.ROS2_JAZZY)
    rng = np.random.default_rng(5)
    sizes = rng.integers(1, 3_000_000, 60)
    sizes[::3] = rng.integers(1, 200, 20)  # small and large messages, chunks of both kinds
    payloads = [rng.integers(0, 4, n, dtype=np.uint8).tobytes() for n in sizes]
    files = []
    for name, stock in (("ours", False), ("stock", True)):
        writer = open_writer(tmp_path / name / "bag", "mcap", "zstd", "jazzy")
        if stock:
            writer.STORAGE_PLUGINS = {**writer.STORAGE_PLUGINS, StoragePlugin.MCAP: Stock}
        with writer:
            a = writer.add_connection("/a", "std_msgs/msg/String", typestore=store)
            for i, data in enumerate(payloads):
                if i == 30:  # a channel added mid-way
                    b = writer.add_connection("/b", "std_msgs/msg/String", typestore=store)
                writer.write(a if i < 30 or i % 2 else b, 1000 + i, memoryview(data))
        files.append((tmp_path / name / "bag" / "bag.mcap").read_bytes())
    assert files[0] == files[1] and len(files[0]) > 1_000_000
