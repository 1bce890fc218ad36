"""The rosbag2 writer of a bag: storage, compression and ``metadata.yaml`` per ROS 2 distro.

``rosbags.rosbag2.Writer`` writes the storage (MCAP or sqlite3) and ``metadata.yaml``; this
module chooses how it compresses and which metadata version it is:

* MCAP: **chunk compression** as rosbag2's MCAP storage plugin does it (``mcap::McapWriter``):
  ``lz4``, ``zstd`` (level 3, zstd's own default; MCAP's ``Default`` is 1, which gains little
  on LiDAR floats), ``zstd_fast`` (level -5: rosbag2's storage preset of that name) or
  ``zstd_small`` (level 19: the preset of that name; slow). Chunks are rosbags' 1 MiB.
  rosbag2 does not record chunk compression in ``metadata.yaml`` (``compression_format`` and
  ``compression_mode`` stay empty; each MCAP chunk names its codec); version-9 metadata
  records the choice in ``custom_data`` (``marsscene.*`` keys).
* sqlite3: rosbag2's **message** compression (``compression_format: zstd``,
  ``compression_mode: message``); any ``zstd*`` setting selects it, ``lz4`` is refused (rosbag2
  has no lz4 compressor plugin).
* ``distro="jazzy"``: metadata version 9 (rosbag2 on Jazzy and later); ``"humble"``: version 5,
  the newest that Humble's rosbag2 defines (``bag_metadata.hpp``: ``int version = 5``), with
  exactly its fields (:data:`HUMBLE_FIELDS`) and the QoS profiles as Humble's YAML string.
"""

from __future__ import annotations

import struct
import threading
from collections.abc import Callable
from io import StringIO
from pathlib import Path
from typing import Any

from marsscene.errors import missing_dependency
from marsscene.runs.export.options import DISTROS, BagOptions

__all__ = ["COMPRESSIONS", "DISTROS", "HUMBLE_FIELDS", "METADATA_VERSION", "check_options",
           "finish_metadata", "humble_metadata", "open_writer", "require_backends"]

#: ``compression`` -> (MCAP chunk codec, level); ``None``: no compression.
COMPRESSIONS: dict[str, tuple[str, int] | None] = {
    "none": None, "lz4": ("lz4", 0), "zstd_fast": ("zstd", -5), "zstd": ("zstd", 3),
    "zstd_small": ("zstd", 19),
}
METADATA_VERSION = {"jazzy": 9, "humble": 5}
#: Fields of rosbag2 metadata version 5 (Humble ``metadata_io.cpp``: the keys it encodes).
HUMBLE_FIELDS = {
    "bag": ("version", "storage_identifier", "duration", "starting_time", "message_count",
            "topics_with_message_count", "compression_format", "compression_mode",
            "relative_file_paths", "files"),
    "topic": ("topic_metadata", "message_count"),
    "topic_metadata": ("name", "type", "serialization_format", "offered_qos_profiles"),
    "file": ("path", "starting_time", "duration", "message_count"),
}


def check_options(storage: str, compression: str, distro: str) -> None:
    """Refuse settings rosbag2 cannot write or read (:class:`~marsscene.errors.ExportError`):
    the rules of :class:`~marsscene.runs.export.options.BagOptions`."""
    BagOptions(storage=storage, compression=compression, ros_distro=distro)


def require_backends(compression: str = "zstd") -> None:
    """Refuse up front (before a long drive) when the bag's libraries are not installed:
    ``rosbags``, and ``zstandard`` for zstd chunks."""
    import importlib.util

    for module, needed in (("rosbags", True), ("zstandard", compression == "zstd")):
        if needed and importlib.util.find_spec(module) is None:
            raise missing_dependency(module, "ros")


def _compressor(codec: str, level: int) -> Callable[[bytes], bytes]:
    """One-shot chunk compression, safe on several threads.

    zstd is python-zstandard's bundled library (its symbols are private), not the
    ``backports.zstd`` / ``compression.zstd`` that rosbags uses: those resolve ``ZSTD_*`` to
    whichever ``libzstd`` the process loaded first, and a drive's EGL renderer loads the
    system's (Mesa links it), so the same chunks came out of ``marsscene drive --bag`` (zstd
    1.5.4 here) and ``marsscene bag`` (1.5.7) as different bytes. The frame is the one-shot
    zstd frame with the content size (what ``zstd.compress`` writes).
    """
    if codec == "lz4":
        import lz4.frame  # a dependency of rosbags

        return lambda data: bytes(lz4.frame.compress(data))
    try:
        import zstandard
    except ImportError:  # pragma: no cover - exercised without the extra only
        raise missing_dependency("zstandard", "ros") from None

    local = threading.local()

    def compress(data: bytes) -> bytes:
        if not hasattr(local, "zc"):
            local.zc = zstandard.ZstdCompressor(level=level)
        return bytes(local.zc.compress(data))

    return compress


def _returns(data: bytes) -> Callable[[bytes], bytes]:
    """A stand-in compressor that hands back ``data`` (already compressed)."""
    return lambda _raw: data


#: MCAP Message record head: opcode, record length, channel id, sequence, log/publish time.
_MESSAGE_HEAD = struct.Struct("<BQHIQQ")

#: Chunks compressed at once beside the writer (the oldest is waited for beyond). A chunk
#: closes past 1 MiB, so it holds 1 MiB plus its last message: an os1-128 scan (~1.5 MB)
#: makes a chunk of its own; the pending chunks hold ~20-100 MB, raw and compressed.
_CHUNKS_IN_FLIGHT = 8


def _chunked_mcap(codec: str, level: int) -> Any:
    """``rosbags``' MCAP storage with its chunk compressor replaced (same records otherwise).

    Chunks are compressed on two threads (zstd and lz4 release the GIL) while the writer goes
    on filling the next ones; each is written, in order, by rosbags' own ``close_chunk`` with
    the compressed bytes handed in, so the file is byte for byte the one a sequential writer
    makes. This halved the compression's share of a bag's write time (zstd on the LiDAR's
    ~15 MB/s was ~half of it, all on the writer's thread).
    """
    from collections import defaultdict, deque
    from concurrent.futures import Future, ThreadPoolExecutor
    from io import BytesIO

    from rosbags.rosbag2.enums import CompressionMode
    from rosbags.rosbag2.storage_mcap import McapWriter, PendingChunk

    compress = _compressor(codec, level)

    class ChunkCompressedMcap(McapWriter):
        def __init__(self, path: Path, compression: CompressionMode) -> None:
            super().__init__(path, CompressionMode.NONE)
            self.compression = codec  # the Chunk record's compression string
            self.pool = ThreadPoolExecutor(2, thread_name_prefix="marsscene-mcap")
            self.pending: deque[tuple[Any, Future[bytes]]] = deque()

        def write(self, connection: Any, timestamp: int, data: bytes | memoryview) -> None:
            """rosbags' ``McapWriter.write`` with the Message record packed in one go (the
            same bytes: opcode, length, channel, sequence 0, log and publish time, data)
            instead of through a fresh BytesIO per message (~1.4 ms per LiDAR scan)."""
            self.message_start_time = min(timestamp, self.message_start_time)
            self.message_end_time = max(timestamp, self.message_end_time)
            self.channel_stats[connection.id] += 1
            chunk = self.chunk
            chunk.message_start_time = min(timestamp, chunk.message_start_time)
            chunk.message_end_time = max(timestamp, chunk.message_end_time)
            chunk.msgs[connection.id].append((timestamp, chunk.bio.tell()))
            chunk.bio.write(_MESSAGE_HEAD.pack(0x05, 22 + memoryview(data).nbytes,
                                               connection.id, 0, timestamp, timestamp))
            chunk.bio.write(data)
            if chunk.bio.tell() > 2**20:
                self.close_chunk()

        def close_chunk(self) -> None:
            chunk = self.chunk
            self.pending.append((chunk, self.pool.submit(compress, chunk.bio.getvalue())))
            self.chunk = PendingChunk(2**63 - 1, 0, BytesIO(), defaultdict(list))
            self._drain(wait=len(self.pending) > _CHUNKS_IN_FLIGHT)

        def _drain(self, *, wait: bool = False, everything: bool = False) -> None:
            while self.pending and (everything or wait or self.pending[0][1].done()):
                chunk, future = self.pending.popleft()
                data = future.result()
                live, self.chunk = self.chunk, chunk
                self.compressor = _returns(data)
                try:
                    super().close_chunk()  # writes the Chunk, MessageIndex records, ChunkIndex
                finally:
                    self.chunk = live
                wait = False

        def close(self, version: int, metadata: str) -> None:
            try:
                if self.chunk.bio.tell():
                    self.close_chunk()
                self._drain(everything=True)
            finally:
                self.pool.shutdown(wait=True, cancel_futures=True)
            super().close(version, metadata)

        def abort(self) -> None:
            """On an error: drop the chunks still compressing (the folder is discarded)."""
            self.pending.clear()
            self.pool.shutdown(wait=False, cancel_futures=True)
            super().abort()

    return ChunkCompressedMcap


def open_writer(path: Path, storage: str, compression: str, distro: str) -> Any:
    """A ``rosbags.rosbag2.Writer`` (not yet opened) set up for ``storage`` and ``compression``.

    Humble bags are written as version 8 (QoS as Humble's YAML string) and rewritten to
    version 5 by :func:`finish_metadata`.
    """
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

    check_options(storage, compression, distro)
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    writer = Writer(path, version=9 if distro == "jazzy" else 8, storage_plugin=plugin)
    codec = COMPRESSIONS[compression]
    if codec is not None and storage == "sqlite3":
        writer.set_compression(CompressionMode.MESSAGE, CompressionFormat.ZSTD)
    elif codec is not None:
        writer.STORAGE_PLUGINS = {**Writer.STORAGE_PLUGINS,
                                  StoragePlugin.MCAP: _chunked_mcap(*codec)}
    if distro == "jazzy" and storage == "mcap":
        writer.set_custom_data("marsscene.mcap_chunk_compression", codec[0] if codec else "")
        writer.set_custom_data("marsscene.mcap_chunk_compression_level",
                               str(codec[1]) if codec else "")
        writer.set_custom_data("marsscene.bag_compression", compression)
    return writer


def _dump(doc: Any) -> str:
    from ruamel.yaml import YAML

    yaml = YAML(typ="safe")
    yaml.default_flow_style = False
    out = StringIO()
    yaml.dump(doc, out)
    return out.getvalue()


def humble_metadata(info: dict[str, Any]) -> dict[str, Any]:
    """Version-5 ``rosbag2_bagfile_information`` from rosbags' version-8 one (fields selected)."""
    bag = {k: info[k] for k in HUMBLE_FIELDS["bag"]} | {"version": 5}
    bag["topics_with_message_count"] = [
        {"topic_metadata": {k: t["topic_metadata"][k] for k in HUMBLE_FIELDS["topic_metadata"]},
         "message_count": t["message_count"]}
        for t in info["topics_with_message_count"]
    ]
    bag["files"] = [{k: f[k] for k in HUMBLE_FIELDS["file"]} for f in info["files"]]
    return bag


def finish_metadata(path: Path, distro: str) -> None:
    """Rewrite ``path/metadata.yaml`` as version 5 for Humble (Jazzy's is rosbags' own)."""
    if distro != "humble":
        return
    from ruamel.yaml import YAML

    meta = path / "metadata.yaml"
    info = YAML(typ="safe").load(meta.read_text())["rosbag2_bagfile_information"]
    meta.write_text(_dump({"rosbag2_bagfile_information": humble_metadata(info)}))
