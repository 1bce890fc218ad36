"""The counts of a live session (:class:`SessionStats`)."""

from __future__ import annotations

from typing import Any

__all__ = ["SessionStats"]


class SessionStats:
    """Counts of a live session: messages, bytes and write seconds per topic, message-building
    seconds per sample stream (image codecs included), commands, resets, the goal."""

    def __init__(self) -> None:
        self.messages: dict[str, int] = {}
        self.bytes: dict[str, int] = {}
        self.write_s: dict[str, float] = {}  # per topic: CDR + DDS write
        self.build_s: dict[str, float] = {}  # per sample stream: building the messages
        self.commands = 0
        self.timeouts = 0
        self.resets = 0
        self.teleports = 0
        self.goal_reached_t_s: float | None = None
        self.sleep_s = 0.0

    def as_dict(self) -> dict[str, Any]:
        return {"messages": dict(self.messages), "bytes": dict(self.bytes),
                "write_s": {k: round(v, 6) for k, v in self.write_s.items()},
                "build_s": {k: round(v, 6) for k, v in self.build_s.items()},
                "commands": self.commands, "command_timeouts": self.timeouts,
                "resets": self.resets, "teleports": self.teleports,
                "goal_reached_t_s": self.goal_reached_t_s, "pacing_sleep_s": round(self.sleep_s, 3)}
