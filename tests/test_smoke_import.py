"""`import marsscene` stays light: none of the heavy optional runtimes are imported."""

from __future__ import annotations

import subprocess
import sys


def test_import_pulls_no_heavy_dependencies() -> None:
    code = (
        "import sys, marsscene\n"
        "heavy = ('pxr', 'mujoco', 'coacd', 'click', 'rasterio', 'rosbags', 'mcap', 'pyarrow',"
        " 'trimesh', 'newton', 'warp')\n"
        "heavy = [m for m in heavy if m in sys.modules]\n"
        "print(','.join(heavy))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""
