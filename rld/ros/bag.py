"""Reading and writing ROS 2 bags without ROS: rosbags for rosbag2 (MCAP or sqlite3, a bag
folder or a bare ``.mcap``/``.db3`` file), and Foxglove's ``mcap`` reader to salvage what a
truncated MCAP still holds (a recording cut off before its summary, which rosbags refuses).

``BagReader`` yields the raw messages of chosen topics in log-time order and says in
``problem`` when the bag ended early; ``BagWriter`` writes an MCAP file (or a bag folder) that
Foxglove and ``ros2 bag play`` open. Both import their libraries lazily.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Collection, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

from rld.ros.typestore import default_typestore, msgdef_of, typestore_for

__all__ = ["BagError", "Connection", "BagMessage", "BagReader", "BagWriter"]


class BagError(ValueError):
    """A bag that cannot be read or written at all (the message names the file)."""


@dataclass(frozen=True)
class Connection:
    """One topic of a bag with its message type and, when the bag records it, the type's
    definition (``msgdef`` in format ``fmt``: ``ros2msg``, ``ros2idl`` or empty) and hash."""

    topic: str
    msgtype: str
    msgdef: str = ""
    fmt: str = ""
    digest: str = ""

    def typestore(self) -> Any:
        """The typestore that decodes this connection (``typestore_for``)."""
        return typestore_for(self.msgtype, self.msgdef, self.fmt)


class BagMessage(NamedTuple):
    connection: Connection
    log_time_ns: int
    raw: bytes


def _mcap_files(path: Path) -> list[Path]:
    if path.is_dir():
        return sorted(path.glob("*.mcap"))
    return [path] if path.suffix == ".mcap" else []


class BagReader:
    """The messages of ``topics`` (all topics when empty) in a bag at ``path``: a rosbag2
    folder, or a bare ``.mcap`` or ``.db3`` file. ``connections`` lists every topic of the bag;
    ``total`` counts the chosen messages (None when unknown); ``problem`` is None, or why the
    bag ended before its end (a truncated file: what rosbags or the salvage reader said)."""

    def __init__(self, path: str | os.PathLike, topics: Collection[str] = ()) -> None:
        from rosbags.rosbag2 import Reader

        self.path = Path(path)
        self.topics = set(topics)
        self.problem: str | None = None
        self.salvaged = False
        self._reader = None
        self._salvage: list[BagMessage] = []
        if not self.path.exists():
            raise BagError(f"{self.path}: no such file or folder")
        try:
            reader = Reader(self.path)
            reader.open()
        except Exception as exc:  # noqa: BLE001 - any failure to open: salvage or say why
            files = _mcap_files(self.path)
            if not files:
                raise BagError(f"{self.path}: cannot read the bag: {exc}") from exc
            self.problem = f"not a complete bag ({exc})"
            self._salvage_mcap(files)
            return
        self._reader = reader
        self._conns = {c.id: _connection(c) for c in reader.connections}
        self.connections = list(dict.fromkeys(self._conns.values()))
        self.total = sum(c.msgcount for c in reader.connections if self._chosen(c.topic))

    def _chosen(self, topic: str) -> bool:
        return not self.topics or topic in self.topics

    def _salvage_mcap(self, files: list[Path]) -> None:
        """Every complete message of the chosen topics in ``files``, read record by record
        until a file ends; sorted by log time (stable)."""
        from mcap.records import Channel, Message, Schema
        from mcap.stream_reader import StreamReader

        self.salvaged = True
        conns: dict[Connection, None] = {}
        out: list[BagMessage] = []
        for file in files:
            schemas: dict[int, Any] = {}
            channels: dict[int, Connection] = {}
            try:
                with open(file, "rb") as fh:
                    for rec in StreamReader(fh).records:
                        if isinstance(rec, Schema):
                            schemas[rec.id] = rec
                        elif isinstance(rec, Channel):
                            s = schemas.get(rec.schema_id)
                            channels[rec.id] = Connection(
                                rec.topic, s.name if s else "",
                                s.data.decode("utf-8", "replace") if s else "",
                                s.encoding if s else "", "")
                            conns[channels[rec.id]] = None
                        elif isinstance(rec, Message):
                            c = channels.get(rec.channel_id)
                            if c is not None and self._chosen(c.topic):
                                out.append(BagMessage(c, int(rec.log_time), bytes(rec.data)))
            except Exception as exc:  # noqa: BLE001 - the truncation itself ends the read
                where = f"{file.name}: " if self.path.is_dir() else ""
                self.problem = (f"{self.problem}; {where}read {len(out)} messages of the chosen "
                                f"topics before the file ends ({type(exc).__name__}"
                                f"{': ' + str(exc) if str(exc) else ''})")
        out.sort(key=lambda m: m.log_time_ns)
        self._salvage = out
        self.connections = list(conns)
        self.total = len(out)

    def messages(self) -> Iterator[BagMessage]:
        """The chosen messages in log-time order. A read error ends them and sets
        ``problem``."""
        if self._reader is None:
            yield from self._salvage
            return
        chosen = [c for c in self._reader.connections if self._chosen(c.topic)]
        if not chosen:
            return
        it = self._reader.messages(connections=chosen)
        count = 0
        while True:
            try:
                conn, t, raw = next(it)
            except StopIteration:
                return
            except Exception as exc:  # noqa: BLE001 - a damaged chunk or page ends the bag
                self.problem = (f"read {count} messages of the chosen topics before an error "
                                f"({type(exc).__name__}: {exc})")
                return
            count += 1
            yield BagMessage(self._conns[conn.id], int(t), bytes(raw))

    def close(self) -> None:
        if self._reader is not None:
            self._reader.close()
            self._reader = None

    def __enter__(self) -> BagReader:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _connection(c: Any) -> Connection:
    from rosbags.interfaces import MessageDefinitionFormat

    fmt = {MessageDefinitionFormat.MSG: "ros2msg",
           MessageDefinitionFormat.IDL: "ros2idl"}.get(c.msgdef.format, "")
    return Connection(c.topic, c.msgtype, c.msgdef.data if fmt else "", fmt, c.digest or "")


class BagWriter:
    """Writes a bag at ``path``: a bare MCAP file when it ends in ``.mcap`` (what Foxglove
    opens, and ``ros2 bag play`` from Iron on), a bare sqlite3 file for ``.db3``, else a rosbag2
    folder of ``storage`` (``mcap`` or ``sqlite3``). The file appears at ``close``; ``abort``
    leaves nothing behind. ``path`` must not exist."""

    def __init__(self, path: str | os.PathLike, storage: str = "mcap") -> None:
        from rosbags.rosbag2 import StoragePlugin, Writer

        self.path = Path(path)
        suffix = self.path.suffix.lower()
        self.single = suffix in (".mcap", ".db3")
        if self.single:
            storage = "mcap" if suffix == ".mcap" else "sqlite3"
        if storage not in ("mcap", "sqlite3"):
            raise ValueError(f"storage must be mcap or sqlite3, got {storage!r}")
        self.storage = storage
        if self.path.exists() and (not self.single or self.path.is_dir()):
            raise BagError(f"{self.path} exists already")
        self._dir = (self.path.parent / f".{self.path.name}.{os.getpid()}.tmp" if self.single
                     else self.path)
        if self._dir.exists():
            shutil.rmtree(self._dir)
        plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
        self._writer = Writer(self._dir, version=9, storage_plugin=plugin)
        try:
            self._writer.open()
        except Exception as exc:  # noqa: BLE001
            raise BagError(f"{self.path}: cannot write: {exc}") from exc
        self._conns: dict[tuple, Any] = {}
        self.count = 0

    def connection(self, topic: str, msgtype: str, msgdef: str = "", digest: str = "",
                   store: Any = None) -> Any:
        """The writer's connection for ``topic`` and ``msgtype``, made at first use: with
        ``msgdef`` and ``digest`` as a bag recorded them, else (or where missing) from ``store``
        (default: ``default_typestore()``)."""
        key = (topic, msgtype, msgdef)
        if key not in self._conns:
            store = store or default_typestore()
            if not msgdef or not digest:
                gen_def, gen_digest = msgdef_of(store, msgtype)
                msgdef, digest = msgdef or gen_def, digest or gen_digest
            self._conns[key] = self._writer.add_connection(topic, msgtype, msgdef=msgdef,
                                                           rihs01=digest)
        return self._conns[key]

    def write_raw(self, conn: Any, log_time_ns: int, raw: bytes) -> None:
        self._writer.write(conn, int(log_time_ns), raw)
        self.count += 1

    def write(self, topic: str, msg: Any, log_time_ns: int, msgtype: str | None = None) -> None:
        """Serialize ``msg`` (a message of ``default_typestore()``) to ``topic``."""
        store = default_typestore()
        msgtype = msgtype or msg.__msgtype__
        self.write_raw(self.connection(topic, msgtype), log_time_ns,
                       bytes(store.serialize_cdr(msg, msgtype)))

    def close(self) -> Path:
        """Finish the bag and put it at ``path``; returns ``path``."""
        self._writer.close()
        if self.single:
            name = f"{self._dir.name}.{'mcap' if self.storage == 'mcap' else 'db3'}"
            os.replace(self._dir / name, self.path)
            shutil.rmtree(self._dir, ignore_errors=True)
        return self.path

    def abort(self) -> None:
        """Drop the bag being written."""
        try:
            self._writer.close()
        except Exception:  # noqa: BLE001, S110 - the writer may be half-open; remove it anyway
            pass
        shutil.rmtree(self._dir, ignore_errors=True)

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()
