"""A user's own Cyclone DDS configuration never stops the server: the configuration matrix of
issue 45 (a CYCLONEDDS_URI naming `lo`, naming 127.0.0.1, in a file, turning multicast off,
selecting another interface), each with and without localhost mode, creates a real participant
-- on the loopback only."""

from __future__ import annotations

import itertools
import warnings

import pytest

from marsscene.errors import MarsSceneWarning
from marsscene.ros2 import dds

_XML = '<CycloneDDS><Domain Id="any"><General>{}</General></Domain></CycloneDDS>'
LO_NAME = _XML.format('<Interfaces><NetworkInterface name="lo"/></Interfaces>')
LO_ADDRESS = _XML.format('<Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces>')
NO_MULTICAST = _XML.format("<AllowMulticast>false</AllowMulticast>")
_DOMAIN = itertools.count(150)


def _start(monkeypatch: pytest.MonkeyPatch, uri: str | None, localhost: bool) -> list[str]:
    """Create a participant; the warnings it gave."""
    if uri is None:
        monkeypatch.delenv("CYCLONEDDS_URI", raising=False)
    else:
        monkeypatch.setenv("CYCLONEDDS_URI", uri)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        part = dds.Participant(next(_DOMAIN), localhost)
        assert len(part.guid) == 16
    return [str(w.message) for w in caught if issubclass(w.category, MarsSceneWarning)]


@pytest.mark.parametrize("localhost", [True, False])
@pytest.mark.parametrize("uri", [LO_NAME, LO_ADDRESS], ids=["lo-by-name", "127.0.0.1"])
def test_a_uri_choosing_the_loopback_starts_either_way(monkeypatch, uri, localhost):
    assert _start(monkeypatch, uri, localhost) == []


def test_a_file_uri_choosing_lo_starts_either_way(monkeypatch, tmp_path):
    path = tmp_path / "cyclone.xml"
    path.write_text(LO_NAME, encoding="utf-8")
    assert dds.user_interfaces(f"file://{path}") == ["lo"]
    for localhost in (True, False):
        assert _start(monkeypatch, f"file://{path}", localhost) == []


@pytest.mark.parametrize("uri", [None, NO_MULTICAST], ids=["no-uri", "multicast-off"])
def test_localhost_mode_with_no_interface_chosen(monkeypatch, uri):
    assert _start(monkeypatch, uri, True) == []  # (without localhost: the default interface)


def test_another_interface_yields_to_localhost_mode_with_a_warning(monkeypatch):
    other = _XML.format('<Interfaces><NetworkInterface name="eth7"/></Interfaces>')
    said = _start(monkeypatch, other, True)
    assert len(said) == 1 and "eth7" in said[0] and "--localhost" in said[0]


def test_loopback_is_not_selected_twice():
    config = dds.cyclone_config(True, {"CYCLONEDDS_URI": LO_NAME})
    assert config is not None and config.count("NetworkInterface") == 1
    assert "<AllowMulticast>false</AllowMulticast>" in config.split(",", 1)[1]
