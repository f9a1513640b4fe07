"""Reading what survived of an MCAP recording whose writer was killed (SIGKILL, power loss).

Such a file has no footer and no summary, so an indexed reader (rosbags, ``mcap``'s seeking reader)
refuses it ("File end magic is invalid"), although every record written before the kill is intact.
:class:`SalvageReader` streams the records with ``mcap``'s StreamReader and stops quietly at the first
incomplete one; it offers the slice of the rosbags Reader interface that ``rbnx replay`` uses
(``connections``, ``start_time``, ``end_time``, ``messages(connections=…)``, ``close``).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass(frozen=True)
class SalvagedConnection:
    """One recorded channel (the fields of a rosbags Connection that replay reads)."""

    id: int
    topic: str
    msgtype: str


class SalvageReader:
    """The complete records of a truncated MCAP file; :attr:`messages_found` counts the intact messages."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.connections: list[SalvagedConnection] = []
        self.start_time = self.end_time = 0
        self.messages_found = 0
        self.truncated = False
        self._scan()

    def _records(self) -> Iterator[Any]:
        from mcap.stream_reader import StreamReader

        with open(self.path, "rb") as fh:
            try:
                yield from StreamReader(fh, record_size_limit=1 << 30).records
            except Exception:  # the record cut by the kill (EOF mid-record, bad length): the end of what survived
                self.truncated = True

    def _scan(self) -> None:
        from mcap.records import Channel, Footer, Message, Schema

        schemas: dict[int, str] = {}
        times: list[int] = []
        footer = False
        for rec in self._records():
            if isinstance(rec, Schema):
                schemas[rec.id] = rec.name
            elif isinstance(rec, Channel):
                self.connections.append(SalvagedConnection(rec.id, rec.topic, schemas.get(rec.schema_id, "")))
            elif isinstance(rec, Message):
                self.messages_found += 1
                if not times:
                    times = [rec.log_time, rec.log_time]
                times = [min(times[0], rec.log_time), max(times[1], rec.log_time)]
            elif isinstance(rec, Footer):
                footer = True
        self.truncated = self.truncated or not footer
        if times:
            self.start_time, self.end_time = times

    def messages(self, connections: list[SalvagedConnection] | None = None) -> Iterator[tuple[Any, int, bytes]]:
        """``(connection, log_time, data)`` in file order, for the given connections (all when None)."""
        from mcap.records import Message

        wanted = {c.id: c for c in (connections if connections is not None else self.connections)}
        for rec in self._records():
            if isinstance(rec, Message) and rec.channel_id in wanted:
                yield wanted[rec.channel_id], rec.log_time, rec.data

    def close(self) -> None:
        """Nothing held open between reads (kept for the Reader interface)."""


__all__ = ["SalvageReader", "SalvagedConnection"]
