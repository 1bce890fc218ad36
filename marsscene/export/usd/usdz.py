"""``.usdz`` packaging with reproducible bytes.

``UsdUtils.CreateNewUsdzPackage`` writes a correct package (uncompressed entries, each entry's
data aligned to 64 bytes with a padding extra field, root layer first) but stamps every local
and central-directory header with the current time, so two builds differ in a few bytes. The
package is patched in place afterwards: each header's DOS modification time and date is set to
1980-01-01 00:00:00, the zip epoch (what reproducible-build tools use). Nothing else moves, so
the alignment pxr chose is kept.
"""

from __future__ import annotations

import struct
from pathlib import Path

from marsscene.errors import ExportError

__all__ = ["ZIP_EPOCH", "normalize_zip_times", "package_usdz"]

#: DOS (time, date) of 1980-01-01 00:00:00: date = (year - 1980) << 9 | month << 5 | day.
ZIP_EPOCH = (0, (1 << 5) | 1)

_EOCD = struct.Struct("<IHHHHIIH")  # end of central directory record (22 bytes, no comment)
_CDH = struct.Struct("<IHHHHHHIIIHHHHHII")  # central directory file header (46 bytes)
_EOCD_SIG, _CDH_SIG, _LFH_SIG = 0x06054B50, 0x02014B50, 0x04034B50


def normalize_zip_times(path: str | Path) -> int:
    """Set the modification time/date of every entry of the zip at ``path`` to 1980-01-01
    00:00:00, in both its local and central-directory headers (in place; sizes, offsets and
    data unchanged). Returns the number of entries.

    Raises :class:`ExportError` for archives this does not handle (a comment, ZIP64, a
    multi-disk archive): pxr writes none of those.
    """
    with open(path, "r+b") as fh:
        fh.seek(0, 2)
        size = fh.tell()
        if size < _EOCD.size:
            raise ExportError(f"{path}: not a zip archive")
        fh.seek(size - _EOCD.size)
        sig, disk, cd_disk, n_here, n_total, cd_size, cd_offset, comment = _EOCD.unpack(
            fh.read(_EOCD.size))
        if sig != _EOCD_SIG or comment or disk or cd_disk or n_here != n_total \
                or cd_offset == 0xFFFFFFFF or cd_offset + cd_size > size - _EOCD.size:
            raise ExportError(f"{path}: unsupported zip layout (comment, ZIP64 or multi-disk)")
        fh.seek(cd_offset)
        cd = bytearray(fh.read(cd_size))
        pos = 0
        local_offsets = []
        for _ in range(n_total):
            fields = _CDH.unpack_from(cd, pos)
            if fields[0] != _CDH_SIG:
                raise ExportError(f"{path}: corrupt central directory")
            struct.pack_into("<HH", cd, pos + 12, *ZIP_EPOCH)
            local_offsets.append(fields[16])
            pos += _CDH.size + fields[10] + fields[11] + fields[12]  # name, extra, comment
        for offset in local_offsets:
            fh.seek(offset)
            if struct.unpack("<I", fh.read(4))[0] != _LFH_SIG:
                raise ExportError(f"{path}: corrupt local header at {offset}")
            fh.seek(offset + 10)
            fh.write(struct.pack("<HH", *ZIP_EPOCH))
        fh.seek(cd_offset)
        fh.write(cd)
    return n_total


def package_usdz(root_layer: Path, target: Path) -> None:
    """Package ``root_layer`` and every asset it references as ``target`` (``.usdz``), with
    reproducible bytes (same inputs, same package)."""
    from pxr import UsdUtils

    if not UsdUtils.CreateNewUsdzPackage(str(root_layer), str(target)):
        raise ExportError(f"could not package {target}")
    normalize_zip_times(target)
