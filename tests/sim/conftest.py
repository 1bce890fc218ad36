"""These tests drive or render the rover: they need mujoco."""

import pytest

pytest.importorskip("mujoco")
